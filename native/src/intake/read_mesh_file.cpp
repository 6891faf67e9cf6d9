#include "intake/read_mesh_file.h"

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <mutex>
#include <sstream>

#include "core/error.h"

namespace qgp {
namespace {

using OpenMesh::IO::BaseImporter;
namespace OM = OpenMesh;

// Collects vertices and faces exactly as the file lists them (OpenMesh's own mesh kernels would
// silently drop non-manifold faces, which intake must see and report).
class SoupImporter final : public BaseImporter {
 public:
  explicit SoupImporter(PolygonSoup& soup) : soup_(soup) {}

  OM::VertexHandle add_vertex(const OM::Vec3f& p) override { return add_vertex(OM::Vec3d(p)); }
  OM::VertexHandle add_vertex(const OM::Vec3d& p) override {
    soup_.positions.emplace_back(p[0], p[1], p[2]);
    return OM::VertexHandle(static_cast<int>(soup_.positions.size()) - 1);
  }
  OM::VertexHandle add_vertex() override { return add_vertex(OM::Vec3d(0, 0, 0)); }
  OM::FaceHandle add_face(const VHandles& idx) override {
    for (const auto& vh : idx) soup_.face_vertices.push_back(vh.idx());
    soup_.face_start.push_back(static_cast<int>(soup_.face_vertices.size()));
    return OM::FaceHandle(soup_.num_faces() - 1);
  }
  void set_point(OM::VertexHandle vh, const OM::Vec3f& p) override {
    if (vh.idx() >= 0 && vh.idx() < soup_.num_vertices()) soup_.positions[vh.idx()] = Vec3(p[0], p[1], p[2]);
  }
  size_t n_vertices() const override { return soup_.positions.size(); }
  size_t n_faces() const override { return static_cast<size_t>(soup_.num_faces()); }
  size_t n_edges() const override { return 0; }

  // Everything else a reader may hand over (normals, colours, texture data) is not needed.
  OM::HalfedgeHandle add_edge(OM::VertexHandle, OM::VertexHandle) override { return OM::HalfedgeHandle(); }
  OM::FaceHandle add_face(OM::HalfedgeHandle) override { return OM::FaceHandle(); }
  void add_face_texcoords(OM::FaceHandle, OM::VertexHandle, const std::vector<OM::Vec2f>&) override {}
  void add_face_texcoords(OM::FaceHandle, OM::VertexHandle, const std::vector<OM::Vec3f>&) override {}
  void set_face_texindex(OM::FaceHandle, int) override {}
  void set_halfedge(OM::VertexHandle, OM::HalfedgeHandle) override {}
  void set_normal(OM::VertexHandle, const OM::Vec3f&) override {}
  void set_normal(OM::VertexHandle, const OM::Vec3d&) override {}
  void set_color(OM::VertexHandle, const OM::Vec3uc&) override {}
  void set_color(OM::VertexHandle, const OM::Vec4uc&) override {}
  void set_color(OM::VertexHandle, const OM::Vec3f&) override {}
  void set_color(OM::VertexHandle, const OM::Vec4f&) override {}
  void set_texcoord(OM::VertexHandle, const OM::Vec2f&) override {}
  void set_status(OM::VertexHandle, const OM::Attributes::StatusInfo&) override {}
  void set_next(OM::HalfedgeHandle, OM::HalfedgeHandle) override {}
  void set_face(OM::HalfedgeHandle, OM::FaceHandle) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(OM::HalfedgeHandle, const OM::Vec2f&) override {}
  void set_texcoord(OM::VertexHandle, const OM::Vec3f&) override {}
  void set_texcoord(OM::HalfedgeHandle, const OM::Vec3f&) override {}
  void set_status(OM::HalfedgeHandle, const OM::Attributes::StatusInfo&) override {}
  void set_color(OM::EdgeHandle, const OM::Vec3uc&) override {}
  void set_color(OM::EdgeHandle, const OM::Vec4uc&) override {}
  void set_color(OM::EdgeHandle, const OM::Vec3f&) override {}
  void set_color(OM::EdgeHandle, const OM::Vec4f&) override {}
  void set_status(OM::EdgeHandle, const OM::Attributes::StatusInfo&) override {}
  void set_normal(OM::FaceHandle, const OM::Vec3f&) override {}
  void set_normal(OM::FaceHandle, const OM::Vec3d&) override {}
  void set_color(OM::FaceHandle, const OM::Vec3uc&) override {}
  void set_color(OM::FaceHandle, const OM::Vec4uc&) override {}
  void set_color(OM::FaceHandle, const OM::Vec3f&) override {}
  void set_color(OM::FaceHandle, const OM::Vec4f&) override {}
  void set_status(OM::FaceHandle, const OM::Attributes::StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}

 private:
  PolygonSoup& soup_;
};

std::string lower_extension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  const auto slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

[[noreturn]] void unreadable(const std::string& path, const std::string& why) {
  throw Error(ErrorCode::UnreadableFile, "cannot read '" + path + "': " + why);
}

// ---- PLY header and triangle-strip reader (OpenMesh's PLY reader knows only face lists) ----

struct PlyProperty {
  std::string name, type;  // scalar type, or the item type of a list
  bool is_list = false;
  std::string count_type;
};
struct PlyElement {
  std::string name;
  long long count = 0;
  std::vector<PlyProperty> properties;
};
struct PlyHeader {
  std::string format;  // ascii | binary_little_endian | binary_big_endian
  std::vector<PlyElement> elements;
  std::streampos data_start;
};

int ply_type_size(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

PlyHeader read_ply_header(std::istream& in, const std::string& path) {
  PlyHeader header;
  std::string line;
  if (!std::getline(in, line) || line.rfind("ply", 0) != 0) unreadable(path, "not a PLY file (no 'ply' magic)");
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "format") {
      ls >> header.format;
    } else if (word == "element") {
      PlyElement e;
      ls >> e.name >> e.count;
      if (!ls || e.count < 0) unreadable(path, "malformed PLY element line '" + line + "'");
      header.elements.push_back(e);
    } else if (word == "property") {
      if (header.elements.empty()) unreadable(path, "PLY property before any element");
      PlyProperty p;
      ls >> p.type;
      if (p.type == "list") {
        p.is_list = true;
        ls >> p.count_type >> p.type;
      }
      ls >> p.name;
      if (!ls || ply_type_size(p.type) == 0 || (p.is_list && ply_type_size(p.count_type) == 0))
        unreadable(path, "unsupported PLY property '" + line + "'");
      header.elements.back().properties.push_back(p);
    } else if (word == "end_header") {
      header.data_start = in.tellg();
      return header;
    }
  }
  unreadable(path, "PLY header has no end_header");
}

class PlyValueReader {
 public:
  PlyValueReader(std::istream& in, const std::string& format, const std::string& path)
      : in_(in), ascii_(format == "ascii"), swap_(format == "binary_big_endian"), path_(path) {}

  double read(const std::string& type) {
    if (ascii_) {
      double v;
      if (!(in_ >> v)) unreadable(path_, "PLY data ends early or holds a non-number");
      return v;
    }
    const int n = ply_type_size(type);
    unsigned char b[8];
    if (!in_.read(reinterpret_cast<char*>(b), n)) unreadable(path_, "PLY data ends early");
    if (swap_) std::reverse(b, b + n);
    if (type == "char" || type == "int8") return static_cast<int8_t>(b[0]);
    if (type == "uchar" || type == "uint8") return b[0];
    if (type == "short" || type == "int16") { int16_t v; std::memcpy(&v, b, 2); return v; }
    if (type == "ushort" || type == "uint16") { uint16_t v; std::memcpy(&v, b, 2); return v; }
    if (type == "int" || type == "int32") { int32_t v; std::memcpy(&v, b, 4); return v; }
    if (type == "uint" || type == "uint32") { uint32_t v; std::memcpy(&v, b, 4); return v; }
    if (type == "float" || type == "float32") { float v; std::memcpy(&v, b, 4); return v; }
    double v;
    std::memcpy(&v, b, 8);
    return v;
  }

 private:
  std::istream& in_;
  bool ascii_, swap_;
  const std::string& path_;
};

// Appends the triangles of one strip; strips alternate orientation and use repeated indices
// (zero-area "swap" triangles) as connectors, which are skipped.
void append_strip(const std::vector<int>& strip, PolygonSoup& soup) {
  for (size_t i = 2; i < strip.size(); ++i) {
    int tri[3] = {strip[i - 2], strip[i - 1], strip[i]};
    if (i % 2 == 1) std::swap(tri[0], tri[1]);
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
    soup.add_face(tri, 3);
  }
}

PolygonSoup read_ply_tristrips(std::istream& in, const PlyHeader& header, const std::string& path) {
  PolygonSoup soup;
  PlyValueReader reader(in, header.format, path);
  for (const PlyElement& element : header.elements) {
    const bool is_vertex = element.name == "vertex";
    const bool is_strips = element.name == "tristrips";
    if (is_vertex) soup.positions.reserve(static_cast<size_t>(element.count));
    for (long long i = 0; i < element.count; ++i) {
      Vec3 p(0, 0, 0);
      std::vector<int> strip;
      for (const PlyProperty& prop : element.properties) {
        if (prop.is_list) {
          const double n = reader.read(prop.count_type);
          if (n < 0 || n > 1e9) unreadable(path, "PLY list length out of range");
          const long long count = static_cast<long long>(n);
          for (long long k = 0; k < count; ++k) {
            const double idx = reader.read(prop.type);
            if (!is_strips || prop.name != "vertex_indices") continue;
            if (idx < 0) {  // -1 restarts the strip
              append_strip(strip, soup);
              strip.clear();
            } else {
              strip.push_back(static_cast<int>(idx));
            }
          }
        } else {
          const double v = reader.read(prop.type);
          if (is_vertex) {
            if (prop.name == "x") p.x() = v;
            else if (prop.name == "y") p.y() = v;
            else if (prop.name == "z") p.z() = v;
          }
        }
      }
      if (is_vertex) soup.positions.push_back(p);
      if (is_strips) append_strip(strip, soup);
    }
  }
  return soup;
}

PolygonSoup read_with_openmesh(const std::string& path) {
  static std::mutex openmesh_mutex;  // OpenMesh's IO manager is a process-wide singleton
  std::lock_guard<std::mutex> lock(openmesh_mutex);
  omerr().disable();
  omlog().disable();
  omout().disable();
  PolygonSoup soup;
  SoupImporter importer(soup);
  OpenMesh::IO::Options options;
  if (!OpenMesh::IO::IOManager().read(path, importer, options))
    unreadable(path, "the " + lower_extension(path).substr(1) + " reader could not parse it");
  return soup;
}

}  // namespace

PolygonSoup read_mesh_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) unreadable(path, "file does not exist or is not readable");
  const std::string ext = lower_extension(path);
  if (ext != ".obj" && ext != ".ply" && ext != ".off")
    unreadable(path, "unsupported extension '" + ext + "' (supported: .obj, .ply, .off)");
  if (ext == ".ply") {
    const PlyHeader header = read_ply_header(in, path);
    bool has_faces = false, has_strips = false;
    for (const PlyElement& e : header.elements) {
      has_faces |= e.name == "face" && e.count > 0;
      has_strips |= e.name == "tristrips" && e.count > 0;
    }
    if (has_strips && !has_faces) {
      in.seekg(header.data_start);
      return read_ply_tristrips(in, header, path);
    }
    if (!has_faces) unreadable(path, "PLY file has no 'face' or 'tristrips' element");
  }
  in.close();
  PolygonSoup soup = read_with_openmesh(path);
  if (soup.num_faces() == 0) unreadable(path, "the file holds no faces");
  return soup;
}

}  // namespace qgp
