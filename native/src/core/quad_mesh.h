// The output quad mesh.
#pragma once
#include <Eigen/Core>
#include <vector>

namespace qgp {

struct QuadMesh {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> V;  // #V x 3 positions
  Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor> Q;     // #Q x 4, counter-clockwise
  std::vector<int> component;  // #Q: intake component each quad belongs to (may be empty)

  // Filled by quad extraction (may be empty for quad meshes from elsewhere):
  std::vector<int> vertex_face;       // #V: working-mesh triangle containing the vertex
  std::vector<char> vertex_singular;  // #V: 1 if the vertex sits on a singularity of the map
                                      //     (valence != 4 inside, != 3 on the boundary)

  int num_vertices() const { return static_cast<int>(V.rows()); }
  int num_quads() const { return static_cast<int>(Q.rows()); }
};

}  // namespace qgp
