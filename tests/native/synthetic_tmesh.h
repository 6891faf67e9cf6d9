// Synthetic T-meshes for tests and benchmarks of the quantizer (no surface embedding: node points
// and edge traces are left empty).
//
// A PatchLayout is a quad layout: rectangular patches with integer side lengths (in ticks) glued
// along equal-length sides; corners are abstract ids listed counter-clockwise starting at the
// patch's (0,0). Sides with no partner are boundary. build_patch_tmesh() optionally subdivides
// every patch by random axis-aligned splits (creating T-junctions, also on patch sides seen from
// the neighbours) and returns the T-mesh with nodes (kinds, indices, CCW incidences), oriented
// edges with lengths ticks * unit, and cells with four counter-clockwise sides.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "tmesh/tmesh.h"

namespace qgp {

struct PatchLayout {
  struct Patch {
    std::array<int, 4> corner{};    // ids of the corners at (0,0), (W,0), (W,H), (0,H)
    int64_t width = 1, height = 1;  // in ticks
  };
  std::vector<Patch> patches;
  std::vector<char> feature_side;  // 4 * #patches (optional): side s of patch p is a feature curve
  double unit = 1;                 // length of one tick
};

// nu x nv patches of the given widths (nu) and heights (nv); periodic directions wrap around
// (a torus if both; then nu, nv >= 3 so that the gluing is unambiguous).
PatchLayout make_grid_layout(const std::vector<int64_t>& widths, const std::vector<int64_t>& heights, bool periodic_u,
                             bool periodic_v);

// Surface of a union of voxels of a rectilinear grid with cell sizes dx, dy, dz (ticks): one patch
// per boundary voxel face. `voxels` lists (i,j,k). Sharp edges become feature sides if requested.
PatchLayout make_polycube_layout(const std::vector<std::array<int, 3>>& voxels, const std::vector<int64_t>& dx,
                                 const std::vector<int64_t>& dy, const std::vector<int64_t>& dz,
                                 bool sharp_edges_are_features);

// A random connected voxel set of `count` voxels whose surface is a 2-manifold, in a grid of
// n x n x n cells.
std::vector<std::array<int, 3>> random_manifold_polycube(int count, int n, unsigned seed);

// The T-mesh of the layout after `splits` random splits (seeded). Throws Error(InvalidArgument) if
// the layout is not a closed-or-bounded 2-manifold gluing.
TMesh build_patch_tmesh(const PatchLayout& layout, int splits, unsigned seed);

// The T-mesh whose cells are the given rectangles (patch coordinates, ticks); the rectangles of
// each patch must tile it.
struct PatchRect {
  int patch = 0;
  int64_t u0 = 0, v0 = 0, u1 = 0, v1 = 0;
};
TMesh build_patch_tmesh(const PatchLayout& layout, const std::vector<PatchRect>& cells);

}  // namespace qgp
