// Bounds-checked OBJ / OFF / PLY readers. (OpenMesh's readers are not used for intake: the
// Debian build asserts, i.e. aborts the host process, on malformed OBJ faces — found by fuzzing.
// The tests compare these readers with OpenMesh on every shared mesh.)
#include "intake/read_mesh_file.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string_view>

#include "core/error.h"

namespace qgp {
namespace {

[[noreturn]] void unreadable(const std::string& path, const std::string& why) {
  throw Error(ErrorCode::UnreadableFile, "cannot read '" + path + "': " + why);
}

std::string lower_extension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  const auto slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) unreadable(path, "file does not exist or is not readable");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Splits text into lines (handles \n, \r\n and \r) and whitespace-separated tokens.
class LineReader {
 public:
  explicit LineReader(std::string_view text) : text_(text) {}
  // Next line without its terminator; false at the end.
  bool next(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    size_t end = pos_;
    while (end < text_.size() && text_[end] != '\n' && text_[end] != '\r') ++end;
    line = text_.substr(pos_, end - pos_);
    pos_ = end;
    if (pos_ < text_.size() && text_[pos_] == '\r') ++pos_;
    if (pos_ < text_.size() && text_[pos_] == '\n') ++pos_;
    ++number_;
    return true;
  }
  size_t line_number() const { return number_; }
  size_t position() const { return pos_; }

 private:
  std::string_view text_;
  size_t pos_ = 0, number_ = 0;
};

bool next_token(std::string_view& line, std::string_view& token) {
  size_t i = 0;
  while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
  if (i == line.size()) return false;
  size_t j = i;
  while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
  token = line.substr(i, j - i);
  line = line.substr(j);
  return true;
}

bool parse_double(std::string_view token, double& value) {
  if (token.empty() || token.size() > 64) return false;
  char buffer[65];
  std::memcpy(buffer, token.data(), token.size());
  buffer[token.size()] = '\0';
  char* end = nullptr;
  errno = 0;
  value = std::strtod(buffer, &end);
  return end == buffer + token.size();
}

bool parse_long(std::string_view token, long long& value) {
  if (token.empty() || token.size() > 20) return false;
  char buffer[21];
  std::memcpy(buffer, token.data(), token.size());
  buffer[token.size()] = '\0';
  char* end = nullptr;
  errno = 0;
  value = std::strtoll(buffer, &end, 10);
  return end == buffer + token.size() && errno == 0;
}

std::string at_line(size_t n) { return "line " + std::to_string(n) + ": "; }

// The texture coordinate index of an OBJ face corner "v/vt[/vn]" (-1 without one), resolved as for vertices.
int corner_texcoord(const std::string& path, size_t line, std::string_view token, size_t num_texcoords) {
  const size_t slash = token.find('/');
  if (slash == std::string_view::npos) return -1;
  std::string_view text = token.substr(slash + 1);
  text = text.substr(0, text.find('/'));
  if (text.empty()) return -1;
  long long index = 0;
  if (!parse_long(text, index) || index == 0)
    unreadable(path, at_line(line) + "bad texture coordinate reference '" + std::string(token) + "'");
  const long long resolved = index > 0 ? index - 1 : static_cast<long long>(num_texcoords) + index;
  if (resolved < 0 || resolved >= static_cast<long long>(num_texcoords))
    unreadable(path, at_line(line) + "texture coordinate reference " + std::to_string(index) + " out of range");
  return static_cast<int>(resolved);
}

std::array<double, 2> read_texcoord(const std::string& path, size_t line, std::string_view rest) {
  std::array<double, 2> uv;
  for (int k = 0; k < 2; ++k) {
    std::string_view t;
    if (!next_token(rest, t) || !parse_double(t, uv[k]) || !std::isfinite(uv[k]))
      unreadable(path, at_line(line) + "a texture coordinate needs two finite numbers");
  }
  return uv;
}

// ---- OBJ: v / vt / f records; normal references, groups, materials are ignored ----
PolygonSoup read_obj(const std::string& path, const std::string& text) {
  PolygonSoup soup;
  LineReader lines(text);
  std::string_view line, token;
  std::vector<int> face;
  std::string joined;
  while (lines.next(line)) {
    // Backslash continuation.
    while (!line.empty() && line.back() == '\\') {
      joined.assign(line.substr(0, line.size() - 1));
      std::string_view more;
      if (!lines.next(more)) break;
      joined.append(" ").append(more);
      line = joined;
    }
    std::string_view rest = line;
    if (!next_token(rest, token)) continue;
    if (token == "v") {
      Vec3 p;
      for (int k = 0; k < 3; ++k) {
        std::string_view t;
        if (!next_token(rest, t) || !parse_double(t, p[k]))
          unreadable(path, at_line(lines.line_number()) + "a vertex needs three numbers");
      }
      soup.positions.push_back(p);
    } else if (token == "vt") {
      soup.texcoords.push_back(read_texcoord(path, lines.line_number(), rest));
    } else if (token == "f") {
      face.clear();
      while (next_token(rest, token)) {
        soup.corner_texcoord.push_back(corner_texcoord(path, lines.line_number(), token, soup.texcoords.size()));
        const std::string_view index_text = token.substr(0, token.find('/'));
        long long index = 0;
        if (!parse_long(index_text, index) || index == 0)
          unreadable(path, at_line(lines.line_number()) + "bad vertex reference '" + std::string(token) + "'");
        // Negative indices count back from the last vertex read so far.
        const long long resolved = index > 0 ? index - 1 : static_cast<long long>(soup.positions.size()) + index;
        if (resolved < 0 || resolved > INT32_MAX)
          unreadable(path,
                     at_line(lines.line_number()) + "vertex reference " + std::to_string(index) + " out of range");
        face.push_back(static_cast<int>(resolved));
      }
      if (face.size() < 3) unreadable(path, at_line(lines.line_number()) + "a face needs at least three vertices");
      soup.add_face(face.data(), static_cast<int>(face.size()));
    }
  }
  if (std::all_of(soup.corner_texcoord.begin(), soup.corner_texcoord.end(), [](int t) { return t < 0; })) {
    soup.texcoords.clear();
    soup.corner_texcoord.clear();
  }
  return soup;
}

// ---- OFF: [C][N][ST]OFF header, counts, vertex lines, face lines "n i0 .. in-1 [colour]" ----
PolygonSoup read_off(const std::string& path, const std::string& text) {
  PolygonSoup soup;
  LineReader lines(text);
  std::string_view line, token;
  // Meaningful lines: comments (#...) and blank lines are skipped.
  auto next_content = [&](std::string_view& out) {
    while (lines.next(out)) {
      const auto hash = out.find('#');
      if (hash != std::string_view::npos) out = out.substr(0, hash);
      std::string_view probe = out;
      if (next_token(probe, token)) return true;
    }
    return false;
  };
  if (!next_content(line) || !next_token(line, token) || token.size() < 3 || token.substr(token.size() - 3) != "OFF")
    unreadable(path, "not an OFF file (no OFF header)");
  if (token.find("4") != std::string_view::npos || token.find("n") == 0)
    unreadable(path, "OFF variant '" + std::string(token) + "' (higher dimension) is not supported");
  std::string_view counts = line;
  long long nv = 0, nf = 0;
  if (!next_token(counts, token)) {
    if (!next_content(line)) unreadable(path, "missing vertex and face counts");
    counts = line;
    next_token(counts, token);
  }
  if (!parse_long(token, nv) || !next_token(counts, token) || !parse_long(token, nf) || nv < 0 || nf < 0)
    unreadable(path, at_line(lines.line_number()) + "bad vertex/face counts");
  // Every record needs at least a few bytes: reject counts the file cannot hold.
  if (static_cast<double>(nv) * 6 + static_cast<double>(nf) * 8 > static_cast<double>(text.size()) + 64)
    unreadable(path, "the header announces " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                         " faces, more than the file holds (truncated?)");
  soup.positions.reserve(static_cast<size_t>(nv));
  for (long long v = 0; v < nv; ++v) {
    if (!next_content(line))
      unreadable(path, "file ends after " + std::to_string(v) + " of " + std::to_string(nv) + " vertices");
    Vec3 p;
    for (int k = 0; k < 3; ++k)
      if (!next_token(line, token) || !parse_double(token, p[k]))
        unreadable(path, at_line(lines.line_number()) + "a vertex needs three numbers");
    soup.positions.push_back(p);
  }
  std::vector<int> face;
  for (long long f = 0; f < nf; ++f) {
    if (!next_content(line))
      unreadable(path, "file ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces");
    long long n = 0;
    if (!next_token(line, token) || !parse_long(token, n) || n < 3 || n > 100000)
      unreadable(path, at_line(lines.line_number()) + "bad face size");
    face.clear();
    for (long long k = 0; k < n; ++k) {
      long long index = 0;
      if (!next_token(line, token) || !parse_long(token, index) || index < INT32_MIN || index > INT32_MAX)
        unreadable(path, at_line(lines.line_number()) + "a face needs " + std::to_string(n) + " vertex indices");
      face.push_back(static_cast<int>(index));
    }
    soup.add_face(face.data(), static_cast<int>(face.size()));
  }
  return soup;
}

// ---- PLY: ascii / binary little / big endian; vertex x y z; face lists or triangle strips ----
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

int ply_type_size(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

class PlyData {
 public:
  PlyData(const std::string& text, size_t start, const std::string& format, const std::string& path)
      : text_(text), pos_(start), ascii_(format == "ascii"), swap_(format == "binary_big_endian"), path_(path) {}

  double read(const std::string& type) {
    if (ascii_) {
      while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
      size_t end = pos_;
      while (end < text_.size() && !std::isspace(static_cast<unsigned char>(text_[end]))) ++end;
      double v;
      if (pos_ == end || !parse_double(std::string_view(text_).substr(pos_, end - pos_), v))
        unreadable(path_, "PLY data ends early or holds a non-number");
      pos_ = end;
      return v;
    }
    const int n = ply_type_size(type);
    if (pos_ + n > text_.size()) unreadable(path_, "PLY data ends early (truncated file)");
    unsigned char b[8];
    std::memcpy(b, text_.data() + pos_, n);
    pos_ += n;
    if (swap_) std::reverse(b, b + n);
    if (type == "char" || type == "int8") return static_cast<int8_t>(b[0]);
    if (type == "uchar" || type == "uint8") return b[0];
    if (type == "short" || type == "int16") {
      int16_t v;
      std::memcpy(&v, b, 2);
      return v;
    }
    if (type == "ushort" || type == "uint16") {
      uint16_t v;
      std::memcpy(&v, b, 2);
      return v;
    }
    if (type == "int" || type == "int32") {
      int32_t v;
      std::memcpy(&v, b, 4);
      return v;
    }
    if (type == "uint" || type == "uint32") {
      uint32_t v;
      std::memcpy(&v, b, 4);
      return v;
    }
    if (type == "float" || type == "float32") {
      float v;
      std::memcpy(&v, b, 4);
      return v;
    }
    double v;
    std::memcpy(&v, b, 8);
    return v;
  }
  size_t remaining() const { return text_.size() - pos_; }
  bool ascii() const { return ascii_; }

 private:
  const std::string& text_;
  size_t pos_;
  bool ascii_, swap_;
  const std::string& path_;
};

// Triangles of one strip; strips alternate orientation and use repeated indices (zero-area
// "swap" triangles) as connectors, which are skipped.
void append_strip(const std::vector<int>& strip, PolygonSoup& soup) {
  for (size_t i = 2; i < strip.size(); ++i) {
    int tri[3] = {strip[i - 2], strip[i - 1], strip[i]};
    if (i % 2 == 1) std::swap(tri[0], tri[1]);
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
    soup.add_face(tri, 3);
  }
}

PolygonSoup read_ply(const std::string& path, const std::string& text) {
  LineReader lines(text);
  std::string_view line, token;
  if (!lines.next(line) || line != "ply") unreadable(path, "not a PLY file (no 'ply' magic)");
  std::string format;
  std::vector<PlyElement> elements;
  bool header_done = false;
  while (!header_done && lines.next(line)) {
    std::string_view rest = line;
    if (!next_token(rest, token)) continue;
    if (token == "format") {
      if (next_token(rest, token)) format = std::string(token);
    } else if (token == "element") {
      PlyElement e;
      long long count = -1;
      if (!next_token(rest, token)) unreadable(path, "malformed PLY element line");
      e.name = std::string(token);
      if (!next_token(rest, token) || !parse_long(token, count) || count < 0)
        unreadable(path, "malformed PLY element line '" + std::string(line) + "'");
      e.count = count;
      elements.push_back(e);
    } else if (token == "property") {
      if (elements.empty()) unreadable(path, "PLY property before any element");
      PlyProperty p;
      std::vector<std::string> words;
      while (next_token(rest, token)) words.emplace_back(token);
      if (words.size() == 4 && words[0] == "list") {
        p.is_list = true;
        p.count_type = words[1];
        p.type = words[2];
        p.name = words[3];
      } else if (words.size() == 2) {
        p.type = words[0];
        p.name = words[1];
      } else {
        unreadable(path, "malformed PLY property '" + std::string(line) + "'");
      }
      if (ply_type_size(p.type) == 0 || (p.is_list && ply_type_size(p.count_type) == 0))
        unreadable(path, "unsupported PLY property type in '" + std::string(line) + "'");
      elements.back().properties.push_back(p);
    } else if (token == "end_header") {
      header_done = true;
    }
  }
  if (!header_done) unreadable(path, "PLY header has no end_header");
  if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
    unreadable(path, "unknown PLY format '" + format + "'");
  bool has_faces = false;
  for (const PlyElement& e : elements) has_faces |= (e.name == "face" || e.name == "tristrips") && e.count > 0;
  if (!has_faces) unreadable(path, "PLY file has no 'face' or 'tristrips' element");

  PolygonSoup soup;
  PlyData data(text, lines.position(), format, path);
  std::vector<int> list;
  for (const PlyElement& element : elements) {
    // Each record takes at least one byte: reject counts the file cannot hold.
    if (static_cast<double>(element.count) > static_cast<double>(data.remaining()) + 1)
      unreadable(path, "PLY element '" + element.name + "' announces " + std::to_string(element.count) +
                           " records, more than the file holds (truncated?)");
    const bool is_vertex = element.name == "vertex";
    const bool is_face = element.name == "face";
    const bool is_strips = element.name == "tristrips";
    if (is_vertex) soup.positions.reserve(static_cast<size_t>(element.count));
    for (long long i = 0; i < element.count; ++i) {
      Vec3 p(0, 0, 0);
      for (const PlyProperty& prop : element.properties) {
        if (!prop.is_list) {
          const double v = data.read(prop.type);
          if (is_vertex) {
            if (prop.name == "x")
              p.x() = v;
            else if (prop.name == "y")
              p.y() = v;
            else if (prop.name == "z")
              p.z() = v;
          }
          continue;
        }
        const double n = data.read(prop.count_type);
        if (!(n >= 0) || n > static_cast<double>(data.remaining()) + 1)
          unreadable(path, "PLY list length out of range");
        const bool indices = (is_face || is_strips) && (prop.name == "vertex_indices" || prop.name == "vertex_index");
        list.clear();
        for (long long k = 0; k < static_cast<long long>(n); ++k) {
          const double idx = data.read(prop.type);
          if (!indices) continue;
          if (!(idx >= INT32_MIN && idx <= INT32_MAX) || idx != std::floor(idx))
            unreadable(path, "PLY vertex index out of range");
          if (is_strips && idx < 0) {  // -1 restarts the strip
            append_strip(list, soup);
            list.clear();
          } else {
            list.push_back(static_cast<int>(idx));
          }
        }
        if (!indices) continue;
        if (is_strips) {
          append_strip(list, soup);
        } else {
          if (list.size() < 3) unreadable(path, "a PLY face needs at least three vertices");
          soup.add_face(list.data(), static_cast<int>(list.size()));
        }
      }
      if (is_vertex) soup.positions.push_back(p);
    }
  }
  return soup;
}

}  // namespace

PolygonSoup read_mesh_file(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext != ".obj" && ext != ".ply" && ext != ".off") {
    std::ifstream probe(path);
    if (!probe) unreadable(path, "file does not exist or is not readable");
    unreadable(path, "unsupported extension '" + ext + "' (supported: .obj, .ply, .off)");
  }
  const std::string text = read_all(path);
  PolygonSoup soup = ext == ".obj" ? read_obj(path, text) : ext == ".off" ? read_off(path, text) : read_ply(path, text);
  if (soup.num_faces() == 0) unreadable(path, "the file holds no faces");
  return soup;
}

}  // namespace qgp
