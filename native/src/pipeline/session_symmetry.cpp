// Session: the symmetric output (symmetry/symmetry.h) made from the remeshed positive half.
#include <utility>

#include "pipeline/policy.h"
#include "pipeline/session.h"
#include "quad_extraction/surface_projection.h"

namespace qgp {
namespace {

// The input's faces for nearest-face queries: each face fanned into triangles; triangle_face: per
// triangle its input face.
TriangleBvh input_face_bvh(const PolygonSoup& input, std::vector<int>& triangle_face) {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> V(input.num_vertices(), 3);
  for (int v = 0; v < input.num_vertices(); ++v) V.row(v) = input.positions[v].transpose();
  std::vector<std::array<int, 3>> triangles;
  for (int f = 0; f < input.num_faces(); ++f) {
    const int* c = input.face_vertices.data() + input.face_start[f];
    for (int k = 1; k + 1 < input.face_size(f); ++k) {
      triangles.push_back({c[0], c[k], c[k + 1]});
      triangle_face.push_back(f);
    }
  }
  return TriangleBvh(V, std::move(triangles));
}

// Per face of V / faces, the input face nearest its centre.
template <int K>
std::vector<int> input_faces_under_centres(const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& V,
                                           const Eigen::Matrix<int, Eigen::Dynamic, K, Eigen::RowMajor>& faces,
                                           const TriangleBvh& bvh, const std::vector<int>& triangle_face) {
  std::vector<int> source_face = triangles_under_centres<K>(V, faces, bvh);
  for (int& f : source_face) f = f < 0 ? -1 : triangle_face[f];
  return source_face;
}

// Quad or triangle boundary vertices this close to a plane are welded to their mirror image.
double weld_tolerance(const IntakeResult& intake) {
  return kSymmetryWeldTolerance * intake.mesh.bounding_box_diagonal();
}

template <class T>
std::vector<T> copied_by_origin(const std::vector<T>& values, const std::vector<int>& origin) {
  std::vector<T> out;
  out.reserve(origin.size());
  for (int o : origin) out.push_back(values[o]);
  return out;
}

}  // namespace

void Session::mirror_results() {
  const double tolerance = weld_tolerance(*intake_);
  std::vector<int> triangle_face;
  const TriangleBvh input_faces = input_face_bvh(input_, triangle_face);
  QuadMesh& quads = *quads_;
  const int half_quads = quads.num_quads();
  const bool has_components = quads.component.size() == static_cast<size_t>(quads.num_quads());
  std::vector<int> origin;
  const MirrorStats mirrored = mirror_across_planes<4>(quads.V, quads.Q, options_.symmetry, tolerance, origin);
  if (has_components) quads.component = copied_by_origin(quads.component, origin);
  quads.vertex_face.clear(), quads.vertex_singular.clear();  // the copies have no working-mesh face
  // Every quad's source face from the whole input (doublets merged across the plane move quads).
  quad_source_face_ = input_faces_under_centres<4>(quads.V, quads.Q, input_faces, triangle_face);
  if (kept_triangles_) mirror_kept_triangles(input_faces, triangle_face);
  // The counts promised are the half's times the copies, less the quads merged (a doublet merged
  // before a later plane's mirror is copied merged).
  const int64_t merged = static_cast<int64_t>(half_quads) * options_.symmetry.copies() - quads.num_quads();
  if (merged > 0) {
    Json& quantization = report_["quantization"];
    quantization["quads_expected"] = quantization["quads_expected"].get<int64_t>() - merged;
    quantization["count"]["quads"] = quantization["count"]["quads"].get<int64_t>() - merged;
  }
  report_["symmetry"] = {{"axes", options_.symmetry.name()},
                         {"copies", options_.symmetry.copies()},
                         {"cut_faces", half_->cut_faces},
                         {"dropped_faces", half_->dropped_faces},
                         {"snapped_vertices", half_->snapped_vertices},
                         {"welded_vertices", mirrored.welded_vertices},
                         {"dissolved_doublets", mirrored.dissolved_doublets},
                         {"open_edges_on_plane", mirrored.open_edges_on_plane}};
}

void Session::mirror_kept_triangles(const TriangleBvh& input_faces, const std::vector<int>& triangle_face) {
  TriMesh& kept = *kept_triangles_;
  std::vector<int> origin;
  mirror_across_planes<3>(kept.V, kept.F, options_.symmetry, weld_tolerance(*intake_), origin);
  kept_component_ = copied_by_origin(kept_component_, origin);
  kept_source_face_ = input_faces_under_centres<3>(kept.V, kept.F, input_faces, triangle_face);
}

TriMesh Session::mirrored_reference(const TriMesh& reference, std::vector<int>& component_of) const {
  TriMesh whole;
  whole.V = reference.V;
  whole.F = reference.F;
  std::vector<int> origin;
  mirror_across_planes<3>(whole.V, whole.F, options_.symmetry, weld_tolerance(*intake_), origin);
  component_of = copied_by_origin(component_of, origin);
  return whole;
}

}  // namespace qgp
