// The intake readers against OpenMesh's readers, used here as an oracle on every shared mesh.
#include <gtest/gtest.h>

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include "intake/read_mesh_file.h"
#include "test_support.h"

namespace qgp {
namespace {

namespace OM = OpenMesh;

// Collects what OpenMesh's readers hand over, as a polygon soup.
class SoupImporter final : public OM::IO::BaseImporter {
 public:
  explicit SoupImporter(PolygonSoup& soup) : soup_(soup) {}
  OM::VertexHandle add_vertex(const OM::Vec3f& p) override { return add_vertex(OM::Vec3d(p)); }
  OM::VertexHandle add_vertex(const OM::Vec3d& p) override {
    soup_.positions.emplace_back(p[0], p[1], p[2]);
    return OM::VertexHandle(static_cast<int>(soup_.positions.size()) - 1);
  }
  OM::VertexHandle add_vertex() override { return add_vertex(OM::Vec3d(0, 0, 0)); }
  OM::FaceHandle add_face(const VHandles& idx) override {
    std::vector<int> f;
    for (const auto& vh : idx) f.push_back(vh.idx());
    soup_.add_face(f.data(), static_cast<int>(f.size()));
    return OM::FaceHandle(soup_.num_faces() - 1);
  }
  void set_point(OM::VertexHandle vh, const OM::Vec3f& p) override {
    soup_.positions[vh.idx()] = Vec3(p[0], p[1], p[2]);
  }
  size_t n_vertices() const override { return soup_.positions.size(); }
  size_t n_faces() const override { return static_cast<size_t>(soup_.num_faces()); }
  size_t n_edges() const override { return 0; }
  OM::HalfedgeHandle add_edge(OM::VertexHandle, OM::VertexHandle) override { return OM::HalfedgeHandle(); }
  OM::FaceHandle add_face(OM::HalfedgeHandle) override { return OM::FaceHandle(); }
  void add_face_texcoords(OM::FaceHandle, OM::VertexHandle, const std::vector<OM::Vec2f>&) override {}
  void add_face_texcoords(OM::FaceHandle, OM::VertexHandle, const std::vector<OM::Vec3f>&) override {}
  void set_face_texindex(OM::FaceHandle, int) override {}
  void set_halfedge(OM::VertexHandle, OM::HalfedgeHandle) override {}
  void set_normal(OM::VertexHandle, const OM::Vec3f&) override {}
  void set_normal(OM::VertexHandle, const OM::Vec3d&) override {}
  void set_color(OM::VertexHandle, const OM::Vec3uc&) override {}
  void set_color(OM::VertexHandle, const OM::Vec4uc&) override {}
  void set_color(OM::VertexHandle, const OM::Vec3f&) override {}
  void set_color(OM::VertexHandle, const OM::Vec4f&) override {}
  void set_texcoord(OM::VertexHandle, const OM::Vec2f&) override {}
  void set_status(OM::VertexHandle, const OM::Attributes::StatusInfo&) override {}
  void set_next(OM::HalfedgeHandle, OM::HalfedgeHandle) override {}
  void set_face(OM::HalfedgeHandle, OM::FaceHandle) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(OM::HalfedgeHandle, const OM::Vec2f&) override {}
  void set_texcoord(OM::VertexHandle, const OM::Vec3f&) override {}
  void set_texcoord(OM::HalfedgeHandle, const OM::Vec3f&) override {}
  void set_status(OM::HalfedgeHandle, const OM::Attributes::StatusInfo&) override {}
  void set_color(OM::EdgeHandle, const OM::Vec3uc&) override {}
  void set_color(OM::EdgeHandle, const OM::Vec4uc&) override {}
  void set_color(OM::EdgeHandle, const OM::Vec3f&) override {}
  void set_color(OM::EdgeHandle, const OM::Vec4f&) override {}
  void set_status(OM::EdgeHandle, const OM::Attributes::StatusInfo&) override {}
  void set_normal(OM::FaceHandle, const OM::Vec3f&) override {}
  void set_normal(OM::FaceHandle, const OM::Vec3d&) override {}
  void set_color(OM::FaceHandle, const OM::Vec3uc&) override {}
  void set_color(OM::FaceHandle, const OM::Vec4uc&) override {}
  void set_color(OM::FaceHandle, const OM::Vec3f&) override {}
  void set_color(OM::FaceHandle, const OM::Vec4f&) override {}
  void set_status(OM::FaceHandle, const OM::Attributes::StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}

 private:
  PolygonSoup& soup_;
};

class ReaderOracle : public ::testing::TestWithParam<std::string> {};

TEST_P(ReaderOracle, SameSoupAsOpenMesh) {
  const std::string name = GetParam();
  const PolygonSoup ours = read_mesh_file(test::mesh_path(name));
  if (name == "igea.ply") {  // triangle strips: OpenMesh's PLY reader cannot read them
    EXPECT_EQ(ours.num_faces(), 268686);
    return;
  }
  PolygonSoup theirs;
  SoupImporter importer(theirs);
  OM::IO::Options options;
  omerr().disable();
  ASSERT_TRUE(OM::IO::IOManager().read(test::mesh_path(name), importer, options)) << name;
  ASSERT_EQ(ours.num_vertices(), theirs.num_vertices()) << name;
  ASSERT_EQ(ours.num_faces(), theirs.num_faces()) << name;
  EXPECT_EQ(ours.face_start, theirs.face_start) << name;
  EXPECT_EQ(ours.face_vertices, theirs.face_vertices) << name;
  double worst = 0;
  for (int v = 0; v < ours.num_vertices(); ++v)
    worst = std::max(worst, (ours.positions[v] - theirs.positions[v]).norm() / (1 + ours.positions[v].norm()));
  EXPECT_LT(worst, 1e-6) << name;  // OpenMesh reads some formats in single precision
}

INSTANTIATE_TEST_SUITE_P(SharedMeshes, ReaderOracle, ::testing::ValuesIn(test::all_mesh_files()),
                         [](const auto& info) { return test::identifier(info.param); });

}  // namespace
}  // namespace qgp
