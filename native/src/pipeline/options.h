// Options of a remesh / grid-UV job, shared by the C API, the CLI and the add-on.
#pragma once
#include <array>
#include <vector>

#include "quantization/quantization.h"
#include "symmetry/symmetry.h"

namespace qgp {

// What a session run produces: the repaired input only, quads (and their integer-grid map), or the
// integer-grid map on the input's own triangles (grid UVs).
enum class Job { Intake, Remesh, GridUV };

struct RemeshOptions {
  double target_faces = 0;                        // desired quad count; <= 0: unset
  double edge_length = 0;                         // desired quad edge length (model units); <= 0: unset
  double sharp_angle_deg = -1;                    // dihedral angle above which an edge is a feature; < 0: off
  std::vector<std::array<int, 2>> feature_edges;  // input vertex index pairs (marked sharp)
  Quantizer quantizer = Quantizer::Greedy;
  bool drop_bad_components = false;  // drop parts intake cannot repair instead of refusing the mesh
  double weld_tolerance = 1e-6;      // weld boundary vertices closer than this times the diagonal; 0: off
  bool refuse_non_manifold = false;  // refuse non-manifold edges instead of cutting them into sheets
  // Where the integer-grid map stays flipped, also build the fallback cell map on the mesh with the
  // T-mesh inserted (igm/cell_map; for maps written as files, qgp --uv-out).
  bool fallback_uv_map = false;
  // Mirror symmetry about the input's coordinate planes (Remesh only): the positive half is remeshed
  // with target_faces / copies quads, then mirrored and welded (symmetry/symmetry.h).
  SymmetryAxes symmetry;
  // The sizing field (sizing/sizing.h): curvature-adaptive size in [0, 1] (0: uniform), and a linear
  // quad density per input vertex (2: quads half as long there; empty: none).
  double adaptive = 0;
  std::vector<double> density;

  static constexpr double kDefaultTargetFaces = 2000;
};

}  // namespace qgp
