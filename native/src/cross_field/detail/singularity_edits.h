// Edits of a cross field's singularities (internal to compute_cross_field): pairs that no layout
// keeps apart, and tori whose field no seamless map follows without folds.
//
// Both change matchings by whole quarter turns and then move the field angles to the smoothest
// field with the new matchings (sum over ordinary edges of w_e eps_e^2, w_e as in the power field,
// constrained faces fixed). The state they edit is compute_cross_field's:
//   theta  #F  field angle of each face in its own frame (e1 along halfedge 3f),
//   eps    3#F residual rotation across each halfedge: the far side's chart angle of the edge
//              minus this side's minus matching * 90deg (eps[opposite] = -eps[h]),
//   field  matching and vertex_index (current on entry), feature_edge, constrained_face.
// After a call that changed something the caller recomputes field.direction and the indices.
#pragma once
#include <vector>

#include "core/mesh.h"
#include "cross_field/cross_field.h"

namespace qgp::cross_field_detail {

// Pairs of singularities of index +1 and -1 off features joined by a path of ordinary edges no
// longer than max_length (model units; <= 0: none): nearer than a quad can keep apart, they cost
// the layout whole quads between them or fold it where it collapses them (a scan's bumps make
// many). Candidates nearest first (then by vertex ids), each vertex in one pair at most; each pair
// is cancelled by one quarter turn moved along its path, and the field smoothed with the new
// matchings within a few rings of the paths. area: #F face areas. Returns the number of pairs
// cancelled. keep_near: vertices (where a seamless map with these pairs folded) near which no pair
// is cancelled; field.num_pairs_kept_near_folds counts the pairs that spares.
int cancel_close_pairs(const TriMesh& mesh, const std::vector<double>& area, double max_length,
                       const std::vector<int>& keep_near, std::vector<double>& theta, std::vector<double>& eps,
                       CrossField& field);

// A closed torus's field that no seamless map follows without folds, made one that does (the
// paper's footnote to §4; Jucovic and Trenkler 1973; Campen, Shen, Zhou and Zorin 2019):
//   - exactly one singularity of index +1 and one of -1: cancelled along the shortest path;
//   - no singularity and a quarter turn around a handle loop (a flat torus turns nothing around
//     any loop): untwisted along the tree-cotree loop that crosses it once (not on fields with
//     feature edges, whose matchings their isoline sectors fix).
// Then the field is smoothed with the new matchings everywhere. Sets field.num_cancelled_pairs and
// num_untwisted_loops. Returns true when it changed the field.
bool make_torus_field_admissible(const TriMesh& mesh, const std::vector<double>& area, std::vector<double>& theta,
                                 std::vector<double>& eps, CrossField& field);

}  // namespace qgp::cross_field_detail
