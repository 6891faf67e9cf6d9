// Mirror symmetry about the object's own coordinate planes (x = 0, y = 0, z = 0, any combination).
//
// The input is cut to its positive side of each plane asked (faces crossing a plane are clipped, so
// the cut runs through new vertices exactly on the plane and becomes an open boundary), that half is
// remeshed like any mesh (a boundary is a feature: quad edges run along it), then the quads are
// mirrored back across each plane and welded there. The output is symmetric to the last bit; on an
// input that is not symmetric, the negative side is the mirror of the positive one.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "core/quad_mesh.h"
#include "intake/polygon_soup.h"

namespace qgp {

struct SymmetryAxes {
  std::array<bool, 3> axis{{false, false, false}};  // x, y, z

  bool any() const { return axis[0] || axis[1] || axis[2]; }
  int copies() const { return (axis[0] ? 2 : 1) * (axis[1] ? 2 : 1) * (axis[2] ? 2 : 1); }
  std::string name() const;  // "x", "yz", "" ...
  bool operator==(const SymmetryAxes& other) const { return axis == other.axis; }
  bool operator!=(const SymmetryAxes& other) const { return axis != other.axis; }
};

// "", "x", "xz", "XYZ" ... (letters in any order, each at most once); throws Error(InvalidArgument).
SymmetryAxes parse_symmetry_axes(const std::string& text);

// The part of a soup on the positive side of the planes asked.
struct HalfSoup {
  PolygonSoup soup;                               // compact: only the vertices its faces use
  std::vector<int> input_face;                    // per soup face: the input face it was cut from
  std::vector<int> input_vertex;                  // per soup vertex: its input vertex, -1 if made by a cut
  std::vector<std::array<int, 2>> feature_edges;  // the input's feature edges on the half (soup indices)
  std::vector<double> vertex_values;              // the input's per-vertex values on the half (cut points
                                                  // interpolated along their edge); empty if none given
  int cut_faces = 0;                              // input faces clipped by a plane
  int dropped_faces = 0;                          // input faces wholly on the negative side (or on a plane)
  int snapped_vertices = 0;                       // input vertices moved onto a plane (within tolerance)
};

// Vertices within snap_tolerance (model units) of a plane are moved onto it before cutting, so that
// the cut makes no sliver next to them. feature_edges: input vertex pairs (as RemeshOptions has
// them); an edge cut by a plane keeps its positive part. vertex_values: one per input vertex, or empty.
HalfSoup cut_to_positive_half(const PolygonSoup& input, const std::vector<std::array<int, 2>>& feature_edges,
                              const SymmetryAxes& axes, double snap_tolerance,
                              const std::vector<double>& vertex_values = {});

struct MirrorStats {
  int welded_vertices = 0;      // vertices on a plane, shared by a face and its mirror image
  int dissolved_doublets = 0;   // quads: two quads sharing two edges at a welded vertex made one
  int open_edges_on_plane = 0;  // boundary edges left on a plane (the welding missed them)
};

// Mirrors a polygon mesh (faces of K corners, counter-clockwise) across each plane asked, in z, y, x
// order (the reverse of the cut), with the copies' orientation reversed. Boundary vertices within
// weld_tolerance of a plane are moved onto it and shared by both sides; for quads, a welded vertex
// left with two quads sharing two edges is dissolved (the two become one). face_origin: per face,
// the face it copies or was merged into (itself for the originals), resized and filled.
template <int K>
MirrorStats mirror_across_planes(Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& V,
                                 Eigen::Matrix<int, Eigen::Dynamic, K, Eigen::RowMajor>& faces,
                                 const SymmetryAxes& axes, double weld_tolerance, std::vector<int>& face_origin);

}  // namespace qgp
