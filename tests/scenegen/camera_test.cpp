#include "scenegen/camera.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "scenegen/decode.hpp"
#include "scenegen/example_sheets.hpp"
#include "scenegen/resting_pose.hpp"

namespace papersim::scenegen {
namespace {

TEST(Camera, TwentySixCandidates) {
  const auto c = candidate_directions();
  ASSERT_EQ(c.size(), 26u);
  EXPECT_EQ(c[0], Eigen::Vector2d(5, 0));
  EXPECT_EQ(c[1], Eigen::Vector2d(12, -120));
  EXPECT_EQ(c[25], Eigen::Vector2d(28, 120));
}

TEST(Camera, ReferenceLensGivesThirtyNinePointSixDegrees) {
  const Stage s;
  const Camera cam = make_camera(s, Eigen::Vector3d::Zero(), 5, 0, 0, 1024, 1440, CameraParams{});
  EXPECT_NEAR(cam.vertical_fov_deg(), 39.5978, 1e-3);
  EXPECT_NEAR((cam.position).norm(), 0.6, 1e-12);
}

TEST(Camera, ProjectAndRayAgree) {
  const Stage s;
  const Camera cam = make_camera(s, Eigen::Vector3d::Zero(), 20, 60, 5, 128, 180, CameraParams{});
  const Eigen::Vector3d p(0.03, -0.05, 0.01);
  const Eigen::Vector2d q = cam.project(p);
  const Eigen::Vector3d d = cam.ray(q.x(), q.y());
  EXPECT_LT((cam.position + d * cam.depth(p) - p).norm(), 1e-12);
  EXPECT_NEAR(cam.project(Eigen::Vector3d::Zero()).x(), 64.0, 1e-9);  // target at the centre
}

TEST(Camera, FlatSheetHasValidDirectionsAndIsUpright) {
  const SheetMesh m = make_example_sheet("flat");
  Rng rng(3);
  const CameraChoice c = choose_camera(m, find_resting_pose(m), 128, 180, CameraParams{}, rng);
  ASSERT_TRUE(c.valid);
  EXPECT_TRUE(c.candidates[0].valid);
  // The page's top edge (material y = +h/2) appears above its bottom edge.
  EXPECT_LT(c.camera.project({0, 0.14, 0}).y(), c.camera.project({0, -0.14, 0}).y());
}

TEST(Camera, SheetFoldedOverItselfHasNoValidCamera) {
  ExampleSheetParams p;
  p.fold_angle_deg = 178.0;
  p.fold_x = -0.01;
  const SheetMesh m = make_example_sheet("fold", p);
  Rng rng(3);
  const CameraChoice c = choose_camera(m, find_resting_pose(m), 128, 180, CameraParams{}, rng);
  EXPECT_FALSE(c.valid);
  for (const auto& k : c.candidates) EXPECT_GT(k.occluded_points + (k.in_frame ? 0 : 1), 0);
}

TEST(Camera, RaisedFlapHidesPartOfTheSheetFromSomeDirections) {
  ExampleSheetParams p;
  p.fold_angle_deg = 120.0;
  const SheetMesh m = make_example_sheet("fold", p);
  Rng rng(3);
  const CameraChoice c = choose_camera(m, find_resting_pose(m), 128, 180, CameraParams{}, rng);
  int occluding = 0;
  for (const auto& k : c.candidates) occluding += k.occluded_points > 0;
  EXPECT_GT(occluding, 0);
}

TEST(Camera, VignettingIsTheFourthPowerOfTheCosineToTheAxis) {
  // Against the angle of each pixel's ray to the optical axis, computed from the ray itself.
  Camera cam;
  cam.width = 64;
  cam.height = 90;
  cam.focal_px = 80.0;
  cam.forward = Eigen::Vector3d(0, 0, -1);
  cam.right = Eigen::Vector3d(1, 0, 0);
  cam.up = Eigen::Vector3d(0, 1, 0);
  ImageF img(cam.width, cam.height, 3);
  std::fill(img.data.begin(), img.data.end(), 0.5f);
  apply_vignetting(img, cam);
  for (int y = 0; y < cam.height; y += 7)
    for (int x = 0; x < cam.width; x += 5) {
      const Eigen::Vector3d ray = cam.ray(x + 0.5, y + 0.5).normalized();
      const double c = ray.dot(cam.forward);
      EXPECT_NEAR(img.at(x, y, 1), 0.5 * c * c * c * c, 1e-6) << x << " " << y;
    }
  EXPECT_LT(img.at(0, 0, 0), 0.5f * 0.7f);  // corner of a wide lens: 0.47 of the centre
}

}  // namespace
}  // namespace papersim::scenegen
