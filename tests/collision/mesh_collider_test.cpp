#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>

#include "collision/collider_factory.hpp"
#include "collision/errors.hpp"
#include "collision/level_set_collider.hpp"
#include "collision/triangle_mesh.hpp"

namespace pc = papersim::collision;

namespace {

/// Writes a closed box [-e, e] as an OBJ with quad faces (outward, counter-clockwise).
std::string write_box_obj(const std::string& name, const Eigen::Vector3d& e, bool drop_face) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream out(path);
  out << "# test box\n";
  for (int k = 0; k < 8; ++k)
    out << "v " << ((k & 1) ? e.x() : -e.x()) << ' ' << ((k & 2) ? e.y() : -e.y()) << ' '
        << ((k & 4) ? e.z() : -e.z()) << '\n';
  out << "vt 0 0\nvn 0 0 1\n";
  out << "f 1/1/1 3/1/1 4/1/1 2/1/1\n";                       // z-
  if (!drop_face) out << "f 5 6 8 7\n";                       // z+
  out << "f 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf -7 -5 -1 -3\n";  // y-, y+, x-, x+ (relative)
  return path;
}

}  // namespace

TEST(MeshCollider, ReadsObjAndMatchesBoxDistance) {
  const Eigen::Vector3d e(0.03, 0.02, 0.015);
  const std::string path = write_box_obj("box.obj", e, false);
  const pc::TriangleMesh mesh = pc::read_obj(path);
  EXPECT_EQ(mesh.vertices.size(), 8u);
  EXPECT_EQ(mesh.triangles.size(), 12u);
  EXPECT_NO_THROW(pc::check_closed(mesh, path));

  pc::ColliderSpec spec;
  spec.kind = pc::ColliderKind::mesh;
  spec.obj_path = path;
  spec.friction = 0.4;
  const auto c = pc::make_collider(spec);
  EXPECT_DOUBLE_EQ(c->friction, 0.4);
  const auto& grid = dynamic_cast<const pc::LevelSetCollider&>(*c);
  const double h = grid.voxel_size();
  pc::Shape box;
  box.kind = pc::ShapeKind::box;
  box.half_extents = e;
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double max_error = 0.0;
  int samples = 0;
  while (samples < 20000) {
    const Eigen::Vector3d p = (e.array() + grid.exact_range())
                                  .matrix()
                                  .cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng)));
    const double exact = pc::shape_distance(box, p, nullptr);
    if (std::abs(exact) >= grid.exact_range()) continue;
    ++samples;
    Eigen::Vector3d g;
    max_error = std::max(max_error, std::abs(c->distance(p, 0.0, &g) - exact));
    ASSERT_NEAR(g.norm(), 1.0, 1e-9);
  }
  std::printf("[ figures  ] mesh box  h = %.3g mm, %zu voxels, max |error| = %.3g mm = %.3f h\n",
              h * 1e3, grid.active_voxel_count(), max_error * 1e3, max_error / h);
  EXPECT_LT(max_error, 0.5 * h);
  // Scale applies to the file's coordinates.
  spec.obj_scale = 2.0;
  EXPECT_NEAR(pc::make_collider(spec)->distance({0.07, 0.0, 0.0}, 0.0), 0.01, 0.5 * h);
}

TEST(MeshCollider, ErrorsNameTheFile) {
  const std::string open_path = write_box_obj("open_box.obj", {0.01, 0.01, 0.01}, true);
  try {
    pc::LevelSetCollider::from_obj(open_path);
    FAIL() << "expected ColliderIoError";
  } catch (const pc::ColliderIoError& e) {
    EXPECT_NE(std::string(e.what()).find("open_box.obj"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not closed"), std::string::npos) << e.what();
  }
  EXPECT_THROW(pc::read_obj("/nonexistent/dir/x.obj"), pc::ColliderIoError);
  const std::string bad = ::testing::TempDir() + "bad.obj";
  std::ofstream(bad) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n";
  try {
    pc::read_obj(bad);
    FAIL() << "expected ColliderIoError";
  } catch (const pc::ColliderIoError& e) {
    EXPECT_NE(std::string(e.what()).find("line 4"), std::string::npos) << e.what();
  }
}

TEST(Factory, BuildsEveryKind) {
  for (pc::ColliderKind kind :
       {pc::ColliderKind::plane, pc::ColliderKind::sphere, pc::ColliderKind::cylinder,
        pc::ColliderKind::capsule, pc::ColliderKind::box, pc::ColliderKind::gable}) {
    pc::ColliderSpec spec;
    spec.kind = kind;
    spec.radius = 0.01;
    spec.length = 0.05;
    spec.half_extents = {0.01, 0.01, 0.01};
    spec.half_width = spec.height = 0.01;
    for (pc::FieldKind field : {pc::FieldKind::automatic, pc::FieldKind::level_set}) {
      if (kind == pc::ColliderKind::plane && field == pc::FieldKind::level_set) continue;
      spec.field = field;
      const auto c = pc::make_collider(spec);
      // The point 1 cm above the top of the shape's box is 1 cm away for every kind.
      const double top = c->bounds(0.0).hi.z();
      EXPECT_NEAR(c->distance({0.0, 0.0, top + 0.002}, 0.0), 0.002, 1e-4)
          << pc::to_string(kind) << " " << pc::to_string(field);
      EXPECT_EQ(pc::collider_kind_from_string(pc::to_string(kind)), kind);
    }
  }
  EXPECT_EQ(pc::field_kind_from_string("level_set"), pc::FieldKind::level_set);
}

TEST(Factory, ErrorsNameTheValue) {
  pc::ColliderSpec spec;
  spec.kind = pc::ColliderKind::sphere;
  spec.friction = -0.1;
  EXPECT_THROW(pc::make_collider(spec), pc::ColliderError);
  spec.friction = 0.3;
  spec.radius = std::nan("");
  try {
    pc::make_collider(spec);
    FAIL();
  } catch (const pc::ColliderError& e) {
    EXPECT_NE(std::string(e.what()).find("radius"), std::string::npos) << e.what();
  }
  spec.radius = 0.01;
  pc::Keyframe k;
  spec.keyframes = {k, k};
  EXPECT_THROW(pc::make_collider(spec), pc::ColliderError);
  spec.keyframes.clear();
  spec.kind = pc::ColliderKind::plane;
  spec.field = pc::FieldKind::level_set;
  EXPECT_THROW(pc::make_collider(spec), pc::ColliderError);
  spec.kind = pc::ColliderKind::mesh;
  spec.field = pc::FieldKind::automatic;
  spec.obj_path = "/nonexistent.obj";
  EXPECT_THROW(pc::make_collider(spec), pc::ColliderIoError);
  EXPECT_THROW(pc::collider_kind_from_string("cone"), pc::ColliderError);
}
