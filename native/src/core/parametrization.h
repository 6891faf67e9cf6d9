// Seamless parametrizations of a TriMesh: the continuous (double) form every solver produces and
// the exact fixed-point form that tracing (T-mesh) and quad extraction work on.
//
// Charts: every face has its own (u,v) chart given by its three corner coordinates. Across an
// interior halfedge h (face f = h/3, opposite o in face g) the transition maps f's chart to g's:
//     p_g = R^rotation[h] * p_f + translation[h],   R = rotation by +90 degrees (u,v) -> (-v,u).
// Non-cut edges have rotation 0 and translation 0, i.e. the corner coordinates agree.
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/mesh.h"

namespace qgp {

// Rotates (u,v) by r quarter turns counter-clockwise. Works for double and integer vectors.
template <class T>
inline std::array<T, 2> rotate_quarter(const std::array<T, 2>& p, int r) {
  switch (((r % 4) + 4) % 4) {
    case 0: return {p[0], p[1]};
    case 1: return {-p[1], p[0]};
    case 2: return {-p[0], -p[1]};
    default: return {p[1], -p[0]};
  }
}
inline Vec2 rotate_quarter(const Vec2& p, int r) {
  const auto q = rotate_quarter(std::array<double, 2>{p.x(), p.y()}, r);
  return Vec2(q[0], q[1]);
}

struct Parametrization {
  Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor> uv;  // 3#F x 2: row 3f+k = corner k of f
  std::vector<int8_t> rotation;  // 3#F: transition rotation of each halfedge (0..3); -1 style
                                 // inverse on the opposite: rotation[o] = (4 - rotation[h]) % 4
  std::vector<char> is_cut;      // #E: edges where charts may disagree (rotation or translation)

  Vec2 corner(int f, int k) const { return uv.row(3 * f + k).transpose(); }
  // Translation of the transition across interior halfedge h, read from its first vertex.
  Vec2 translation(const TriMesh& mesh, int h) const;
};

// Largest |transition(p_f) - p_g| over both endpoints of every interior edge (0 for an exactly
// seamless map up to rounding); the transition is taken from each edge's first endpoint.
double max_transition_residual(const TriMesh& mesh, const Parametrization& param);

// Signed parametric area of each face (positive = same orientation as the surface).
std::vector<double> parametric_areas(const Parametrization& param);

// ---------------------------------------------------------------------------------------------
// Exact form: coordinates are integers in units of 2^-fraction_bits. Transitions hold exactly.

using IVec2 = std::array<int64_t, 2>;

struct ExactParametrization {
  int fraction_bits = 0;           // coordinate = integer * 2^-fraction_bits
  std::vector<IVec2> uv;           // 3#F corners
  std::vector<int8_t> rotation;    // 3#F, as in Parametrization
  std::vector<IVec2> translation;  // 3#F (0 on non-cut and boundary halfedges)
  std::vector<char> is_cut;        // #E

  int64_t one() const { return int64_t(1) << fraction_bits; }  // the integer that means 1.0
  double to_double(int64_t c) const { return std::ldexp(static_cast<double>(c), -fraction_bits); }
  IVec2 corner(int f, int k) const { return uv[3 * f + k]; }
  // p in face(h)'s chart -> the opposite face's chart.
  IVec2 transfer(int h, const IVec2& p) const {
    const IVec2 r = rotate_quarter(p, rotation[h]);
    return {r[0] + translation[h][0], r[1] + translation[h][1]};
  }
  Parametrization to_double() const;
};

struct SanitizeOptions {
  int fraction_bits = 24;
  // Optional per-vertex snapping: coordinates of singular vertices / of vertices whose wedge is
  // listed are rounded to multiples of 2^-snap_bits (0 = integers) in every chart. Used by the
  // integer-grid map to make singularities and transitions integral.
  std::vector<char> snap_vertex;  // #V flags (may be empty)
  int snap_bits = 0;
  // Per-corner axis snapping for feature isolines: bit 0 = u, bit 1 = v must be a multiple of
  // 2^-snap_bits. Size 3#F or empty.
  std::vector<uint8_t> snap_corner_axes;
};

struct SanitizeResult {
  ExactParametrization param;
  double max_change = 0;         // largest |exact - continuous| over all corners (uv units)
  int unresolved_equations = 0;  // transition equations that could not be satisfied (0 expected)
  // sanitize_with_isolines only, of the faces positive in the continuous map: those whose rounded
  // corners were not positively oriented and that moving free unknowns on the grid made positive,
  // and those still not positive after that (0 expected).
  int reoriented_faces = 0;
  int non_positive_faces = 0;
};

// Rounds a continuous seamless parametrization to the fixed-point grid such that every transition
// holds exactly: a rotation by rotation[h] plus a translation on the grid. The per-corner values
// change by at most a few grid units (more where snapping is requested).
SanitizeResult sanitize_parametrization(const TriMesh& mesh, const Parametrization& param,
                                        const SanitizeOptions& options);

// Largest |transfer(corner) - corner on the other side| in grid units; 0 means exactly seamless.
int64_t exact_transition_residual(const TriMesh& mesh, const ExactParametrization& param);

// Signed angle (radians) of corner c (= 3f + k) in its face's chart.
double exact_corner_angle(const ExactParametrization& param, int c);
// Angle sum of every vertex in quarter turns, rounded (4 at a regular interior vertex of a locally
// injective map, 2 on a straight boundary; the corner angles do not depend on the chart).
std::vector<int> exact_angle_sums(const TriMesh& mesh, const ExactParametrization& param);

// Exact orientation test on grid points: sign of (b - a) x (c - a). Inputs must stay below
// 2^61 in magnitude (products are formed in 128-bit integers).
int orient2d_exact(const IVec2& a, const IVec2& b, const IVec2& c);

}  // namespace qgp
