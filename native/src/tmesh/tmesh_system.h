// What the rest of the pipeline reads off a T-mesh: the cell system (paper eq. 4/5) with ideal
// lengths, validity figures, the JSON report, and the layout OBJ for people to look at.
#pragma once
#include <Eigen/SparseCore>
#include <ostream>
#include <string>
#include <vector>

#include "core/json.h"
#include "core/mesh.h"
#include "tmesh/tmesh.h"

namespace qgp {

// A x = 0 with x = T-edge lengths: rows 2c and 2c+1 are cell c's equations
// sum(sides[0]) - sum(sides[2]) and sum(sides[1]) - sum(sides[3]); one column per T-edge;
// entries in {-1, 0, 1} (an edge on both opposite sides of one cell cancels). Cells that are not
// four-sided give empty rows.
struct TMeshCellSystem {
  Eigen::SparseMatrix<int, Eigen::RowMajor> A;  // 2#cells x #edges
  Eigen::VectorXd ideal_lengths;                // #edges: continuous lengths at scale 1
};
TMeshCellSystem tmesh_cell_system(const TMesh& tmesh);

struct TMeshCheck {
  int singular_nodes = 0;  // nodes with index != 0
  int t_junctions = 0;
  int cells_not_four_sided = 0;
  double max_cell_equation_residual = 0;  // max over cells of |sum0 - sum2| / max(sum0, sum2), same for 1/3
  int max_abs_coefficient = 0;            // of A (1 for a proper T-mesh)
  int edges_without_cells = 0;            // interior edges missing a cell on one side, boundary edges on both
};
TMeshCheck check_tmesh(const TMesh& tmesh);

// {nodes, edges, cells, singular_nodes, t_junctions, euler_characteristic, cells_not_four_sided,
//  max_cell_equation_residual, trace_seconds, motorcycles, head_on, crossings, ...}
void to_json(Json& j, const TMesh& tmesh);

// Writes the T-mesh edges as OBJ polylines (`l` over `v` points on the surface of `mesh`) and
// its nodes as points (`p`). vertex_offset: OBJ vertices written before (updated), so several
// components can go into one file.
void write_layout_obj(std::ostream& out, const TriMesh& mesh, const TMesh& tmesh, long long& vertex_offset);
// The same into a file (throws Error(UnreadableFile) if it cannot be written).
void write_layout_obj(const std::string& path, const std::vector<const TriMesh*>& meshes,
                      const std::vector<const TMesh*>& tmeshes);

}  // namespace qgp
