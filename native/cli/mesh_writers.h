// Output files of the qgp CLI.
#pragma once
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/parametrization.h"
#include "core/quad_mesh.h"

namespace qgp::cli {

using UvMatrix = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;

// Writes a triangle mesh as Wavefront OBJ. With corner_uv (3#F x 2, row 3f + k = corner k of
// face f) every face corner gets a texture coordinate (vt); corners of one vertex with equal
// coordinates share one vt line. header: comment lines written first (without '#').
// Throws std::runtime_error if the file cannot be written.
void write_obj(const std::string& path, const TriMesh& mesh, const UvMatrix* corner_uv, const std::string& header);

// Writes a quad mesh as Wavefront OBJ (faces counter-clockwise), one object per component
// ("component_N"), header as for write_obj. kept (may be null): triangles of components that could
// not be quadded, written after the quads as objects "component_N_triangles" (kept_component: #F of
// kept, the component of each). With corner_uv (4#Q x 2, row 4q + k = corner k of quad q) every quad
// corner gets a vt, as for write_obj. Throws std::runtime_error if the file cannot be written.
void write_quad_obj(const std::string& path, const QuadMesh& quads, const TriMesh* kept,
                    const std::vector<int>& kept_component, const std::string& header,
                    const UvMatrix* corner_uv = nullptr);

}  // namespace qgp::cli
