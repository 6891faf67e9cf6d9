// The output quad mesh.
#pragma once
#include <Eigen/Core>
#include <vector>

namespace qgp {

struct QuadMesh {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> V;  // #V x 3 positions
  Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor> Q;     // #Q x 4, counter-clockwise
  std::vector<int> component;  // #Q: intake component each quad belongs to
};

}  // namespace qgp
