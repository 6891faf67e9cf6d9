// The sizing field: where quads are to be smaller or larger than the target edge length, from the
// surface's curvature (adaptive size) and a density the caller paints per vertex. The seamless map
// follows it (its target gradient per face is the field's direction over the edge length times the
// face's size); quantization and everything after it stay exact.
#pragma once
#include <vector>

#include "core/mesh.h"

namespace qgp {

struct SizingOptions {
  // 0: uniform; 1: strongly curvature-adaptive (edge length proportional to the radius of curvature,
  // within kMaxCurvatureRatio either way of the surface's typical radius).
  double adaptive = 0;
  // Per mesh vertex, the linear quad density asked there (2: quads half as long; empty: 1
  // everywhere), within kMaxDensityRatio either way.
  std::vector<double> vertex_density;
};

constexpr double kMaxCurvatureRatio = 4;
constexpr double kMaxDensityRatio = 16;

// Per face of `mesh`, its quad edge length as a multiple of the target: the curvature's share
// (feature edges, which quads follow rather than resolve, bend nothing) over the painted density,
// scaled so that the quad count at the target stays the uniform one (sum of area / size^2 = area).
// Empty when the options ask for uniform quads. feature_edges: #E flags, or empty.
std::vector<double> face_sizes(const TriMesh& mesh, const std::vector<char>& feature_edges,
                               const SizingOptions& options);

// A hash of face sizes (0 for none), for stage keys.
uint64_t sizes_hash(const std::vector<double>& sizes);

}  // namespace qgp
