#include "mesh_writers.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace qgp::cli {
namespace {

// Writes one vt per distinct (vertex, u, v) of the corners (corners of a vertex inside one chart
// share it); returns the vt index (0-based) of every corner.
std::vector<int> write_corner_vt(FILE* out, const std::vector<int>& corner_vertex, const UvMatrix& corner_uv) {
  std::vector<int> vt(corner_vertex.size(), -1);
  std::map<std::tuple<int, double, double>, int> index;
  for (size_t c = 0; c < corner_vertex.size(); ++c) {
    const auto key = std::make_tuple(corner_vertex[c], corner_uv(c, 0), corner_uv(c, 1));
    auto it = index.find(key);
    if (it == index.end()) {
      it = index.emplace(key, static_cast<int>(index.size())).first;
      std::fprintf(out, "vt %.17g %.17g\n", corner_uv(c, 0), corner_uv(c, 1));
    }
    vt[c] = it->second;
  }
  return vt;
}

}  // namespace

void write_obj(const std::string& path, const TriMesh& mesh, const UvMatrix* corner_uv, const std::string& header) {
  const int nf = mesh.num_faces();
  if (corner_uv && corner_uv->rows() != 3 * nf) throw std::runtime_error("uv array does not match the mesh");
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "w"), &std::fclose);
  if (!file) throw std::runtime_error("cannot write '" + path + "': " + std::strerror(errno));
  FILE* out = file.get();
  std::istringstream lines(header);
  for (std::string line; std::getline(lines, line);) std::fprintf(out, "# %s\n", line.c_str());
  for (int v = 0; v < mesh.num_vertices(); ++v)
    std::fprintf(out, "v %.17g %.17g %.17g\n", mesh.V(v, 0), mesh.V(v, 1), mesh.V(v, 2));
  std::vector<int> corner_vertex(3 * nf);
  for (int c = 0; c < 3 * nf; ++c) corner_vertex[c] = mesh.F(c / 3, c % 3);
  const std::vector<int> vt = corner_uv ? write_corner_vt(out, corner_vertex, *corner_uv) : std::vector<int>();
  for (int f = 0; f < nf; ++f) {
    if (corner_uv)
      std::fprintf(out, "f %d/%d %d/%d %d/%d\n", mesh.F(f, 0) + 1, vt[3 * f] + 1, mesh.F(f, 1) + 1, vt[3 * f + 1] + 1,
                   mesh.F(f, 2) + 1, vt[3 * f + 2] + 1);
    else
      std::fprintf(out, "f %d %d %d\n", mesh.F(f, 0) + 1, mesh.F(f, 1) + 1, mesh.F(f, 2) + 1);
  }
  if (std::ferror(out) || std::fflush(out) != 0) throw std::runtime_error("cannot write '" + path + "'");
}

// Appends the triangles of components kept as triangles, their vertices numbered after `offset`.
void write_kept_triangles(FILE* out, const TriMesh& kept, const std::vector<int>& kept_component, int offset) {
  for (int v = 0; v < kept.num_vertices(); ++v)
    std::fprintf(out, "v %.17g %.17g %.17g\n", kept.V(v, 0), kept.V(v, 1), kept.V(v, 2));
  for (int f = 0; f < kept.num_faces(); ++f) {
    const int c = kept_component[f];
    if (f == 0 || c != kept_component[f - 1]) std::fprintf(out, "o component_%d_triangles\n", c);
    std::fprintf(out, "f %d %d %d\n", kept.F(f, 0) + offset + 1, kept.F(f, 1) + offset + 1, kept.F(f, 2) + offset + 1);
  }
}

void write_quad_obj(const std::string& path, const QuadMesh& quads, const TriMesh* kept,
                    const std::vector<int>& kept_component, const std::string& header, const UvMatrix* corner_uv) {
  if (corner_uv && corner_uv->rows() != 4 * quads.num_quads())
    throw std::runtime_error("uv array does not match the quad mesh");
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "w"), &std::fclose);
  if (!file) throw std::runtime_error("cannot write '" + path + "': " + std::strerror(errno));
  FILE* out = file.get();
  std::istringstream lines(header);
  for (std::string line; std::getline(lines, line);) std::fprintf(out, "# %s\n", line.c_str());
  for (int v = 0; v < quads.num_vertices(); ++v)
    std::fprintf(out, "v %.17g %.17g %.17g\n", quads.V(v, 0), quads.V(v, 1), quads.V(v, 2));
  std::vector<int> corner_vertex(4 * quads.num_quads());
  for (size_t c = 0; c < corner_vertex.size(); ++c) corner_vertex[c] = quads.Q(c / 4, c % 4);
  const std::vector<int> vt = corner_uv ? write_corner_vt(out, corner_vertex, *corner_uv) : std::vector<int>();
  // One object per input component (quads of a component are contiguous).
  for (int q = 0; q < quads.num_quads(); ++q) {
    const int c = quads.component.empty() ? 0 : quads.component[q];
    if (q == 0 || (!quads.component.empty() && c != quads.component[q - 1])) std::fprintf(out, "o component_%d\n", c);
    if (corner_uv)
      std::fprintf(out, "f %d/%d %d/%d %d/%d %d/%d\n", quads.Q(q, 0) + 1, vt[4 * q] + 1, quads.Q(q, 1) + 1,
                   vt[4 * q + 1] + 1, quads.Q(q, 2) + 1, vt[4 * q + 2] + 1, quads.Q(q, 3) + 1, vt[4 * q + 3] + 1);
    else
      std::fprintf(out, "f %d %d %d %d\n", quads.Q(q, 0) + 1, quads.Q(q, 1) + 1, quads.Q(q, 2) + 1, quads.Q(q, 3) + 1);
  }
  if (kept) write_kept_triangles(out, *kept, kept_component, quads.num_vertices());
  if (std::ferror(out) || std::fflush(out) != 0) throw std::runtime_error("cannot write '" + path + "'");
}

}  // namespace qgp::cli
