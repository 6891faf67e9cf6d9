// Benchmark (not a test): quantization time against the number of T-edges on synthetic
// T-meshes (torus grids, planar rectangles with boundary, polycubes with many singularities),
// randomly split into T-junction-rich layouts. Prints a table; never fails on timing.
//
//   quantization_bench [max_edges [family [fine_limit [min_edges]]]]
// max_edges (default 120000): largest T-mesh; family: torus | planar | polycube (default all);
// fine_limit (default 40000): T-meshes above this many edges run the coarse density only;
// min_edges (default 0): skip smaller T-meshes.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include "core/progress.h"
#include "core/timer.h"
#include "quantization/quantization.h"
#include "synthetic_tmesh.h"

using namespace qgp;

namespace {

std::vector<int64_t> sizes(int n, std::mt19937& rng) {
  std::vector<int64_t> v(n);
  for (auto& x : v) x = std::uniform_int_distribution<int64_t>(200, 600)(rng);
  return v;
}

TMesh make(const std::string& family, int splits, unsigned seed) {
  std::mt19937 rng(seed);
  PatchLayout layout;
  if (family == "torus") {
    layout = make_grid_layout(sizes(6, rng), sizes(5, rng), true, true);
  } else if (family == "planar") {
    layout = make_grid_layout(sizes(6, rng), sizes(5, rng), false, false);
    layout.feature_side.assign(4 * layout.patches.size(), 0);
    for (size_t p = 0; p < layout.patches.size(); p += 7) layout.feature_side[4 * p + 1] = 1;  // interior features
  } else {
    const auto voxels = random_manifold_polycube(60, 8, seed);
    layout = make_polycube_layout(voxels, sizes(8, rng), sizes(8, rng), sizes(8, rng), true);
  }
  layout.unit = 0.01;
  return build_patch_tmesh(layout, splits, seed);
}

}  // namespace

int main(int argc, char** argv) {
  const int max_edges = argc > 1 ? std::atoi(argv[1]) : 120000;
  const std::string only = argc > 2 ? argv[2] : "";
  const int fine_limit = argc > 3 ? std::atoi(argv[3]) : 40000;
  const int min_edges = argc > 4 ? std::atoi(argv[4]) : 0;
  std::printf("%-8s %8s %7s %5s %8s | %6s %7s %6s %7s %9s %8s %7s | %7s %7s %7s\n", "family", "edges", "cells", "sing",
              "quads", "st1", "st2", "rej", "zero", "objective", "searches", "checks", "st1 s", "st2 s", "total s");
  for (const std::string family : {"torus", "planar", "polycube"}) {
    if (!only.empty() && family != only) continue;
    for (int splits : {300, 1000, 3000, 10000, 35000, 40000}) {
      const TMesh tm = make(family, splits, 1);
      if (static_cast<int>(tm.edges.size()) > max_edges) break;
      if (static_cast<int>(tm.edges.size()) < min_edges) continue;
      int singular = 0;
      for (const auto& n : tm.nodes) singular += n.singular();
      for (double quads_per_cell : {1.0, 10.0}) {
        if (quads_per_cell > 1 && static_cast<int>(tm.edges.size()) > fine_limit) continue;
        QuantizationOptions options;
        options.scale = quantization_scale_for_quads(tm, quads_per_cell * tm.cells.size());
        Progress progress;
        const QuantizationResult r = quantize(tm, options, progress);
        std::printf("%-8s %8zu %7zu %5d %8lld | %6d %7d %6d %7d %9.1f %8lld %7lld | %7.3f %7.3f %7.3f%s\n",
                    family.c_str(), tm.edges.size(), tm.cells.size(), singular,
                    static_cast<long long>(r.quads_expected), r.stage1_steps, r.stage2_steps, r.stage2_rejected_invalid,
                    r.zero_edges, r.objective, static_cast<long long>(r.searches),
                    static_cast<long long>(r.validity_checks), r.stage1_seconds, r.stage2_seconds, r.seconds,
                    r.valid && r.consistency_residual == 0 ? "" : "  INVALID");
        std::printf("         not improving %lld, labelled nodes per search %.0f, validity %.3f s\n",
                    static_cast<long long>(r.stage2_not_improving),
                    static_cast<double>(r.searched_nodes) / std::max<long long>(1, r.searches), r.validity_seconds);
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
