// Raw mesh as read from a file or passed through the C API, before any validation.
#pragma once
#include <array>
#include <vector>

#include "core/mesh.h"

namespace qgp {

struct PolygonSoup {
  std::vector<Vec3> positions;     // #V positions
  std::vector<int> face_start{0};  // #faces+1 offsets into face_vertices
  std::vector<int> face_vertices;  // vertex indices of all faces, concatenated
  // Texture coordinates (OBJ vt records) and, per entry of face_vertices, the one its corner uses
  // (-1: none); both empty when the file has none.
  std::vector<std::array<double, 2>> texcoords;
  std::vector<int> corner_texcoord;

  int num_vertices() const { return static_cast<int>(positions.size()); }
  int num_faces() const { return static_cast<int>(face_start.size()) - 1; }
  int face_size(int f) const { return face_start[f + 1] - face_start[f]; }
  void add_face(const int* begin, int count) {
    face_vertices.insert(face_vertices.end(), begin, begin + count);
    face_start.push_back(static_cast<int>(face_vertices.size()));
  }
};

// Builds a soup of triangles from flat arrays: vertices (n x 3, row-major) and triangles (m x 3).
PolygonSoup soup_from_triangle_arrays(const double* vertices, long long num_vertices, const int* triangles,
                                      long long num_triangles);

}  // namespace qgp
