#include "intake/polygon_soup.h"

namespace qgp {

PolygonSoup soup_from_triangle_arrays(const double* vertices, long long num_vertices, const int* triangles,
                                      long long num_triangles) {
  PolygonSoup soup;
  soup.positions.resize(static_cast<size_t>(num_vertices));
  for (long long i = 0; i < num_vertices; ++i)
    soup.positions[i] = Vec3(vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]);
  soup.face_vertices.assign(triangles, triangles + 3 * num_triangles);
  soup.face_start.resize(static_cast<size_t>(num_triangles) + 1);
  for (long long f = 0; f <= num_triangles; ++f) soup.face_start[f] = static_cast<int>(3 * f);
  return soup;
}

}  // namespace qgp
