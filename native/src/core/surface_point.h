// A point on the surface of a TriMesh, with its coordinates in the parametrization chart of the
// face it lies in (charts as in core/parametrization.h).
#pragma once
#include "core/mesh.h"

namespace qgp {

struct SurfacePoint {
  int face = -1;
  Vec3 barycentric = Vec3::Zero();  // weights of F(face,0..2)
  Vec2 uv = Vec2::Zero();           // in face's chart

  Vec3 position(const TriMesh& mesh) const {
    return barycentric[0] * mesh.position(mesh.F(face, 0)) + barycentric[1] * mesh.position(mesh.F(face, 1)) +
           barycentric[2] * mesh.position(mesh.F(face, 2));
  }
};

}  // namespace qgp
