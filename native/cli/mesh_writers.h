// Output files of the qgp CLI.
#pragma once
#include <string>

#include "core/mesh.h"
#include "core/parametrization.h"
#include "core/quad_mesh.h"

namespace qgp::cli {

// Writes a triangle mesh as Wavefront OBJ. With corner_uv (3#F x 2, row 3f + k = corner k of
// face f) every face corner gets a texture coordinate (vt); corners of one vertex with equal
// coordinates share one vt line. header: comment lines written first (without '#').
// Throws std::runtime_error if the file cannot be written.
void write_obj(const std::string& path, const TriMesh& mesh,
               const Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>* corner_uv, const std::string& header);

// Writes a quad mesh as Wavefront OBJ (faces counter-clockwise), header as for write_obj.
// Throws std::runtime_error if the file cannot be written.
void write_quad_obj(const std::string& path, const QuadMesh& quads, const std::string& header);

}  // namespace qgp::cli
