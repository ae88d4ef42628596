// Self-contact end to end: scenes in which the sheet meets itself, checked for intersecting
// triangle pairs (exact predicates) after every step.
#include "collision/self_contact.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>

#include "collision/self_intersection.hpp"
#include "simulation/simulate.hpp"
#include "tests/simulation/folded_sheet_scene.hpp"

using namespace papersim;
using namespace papersim::simulation;

namespace {

struct Watched {
  int steps = 0;
  int max_intersections = 0;  ///< largest count of intersecting triangle pairs at any step
  int first_bad_step = -1;
  double min_separation = INF;  ///< smallest distance between two parts of the sheet [m]
  double min_ground = INF;      ///< smallest vertex height above the ground [m]
  double min_extra = INF;       ///< smallest value of the test's own measure
  double seconds = 0;
  RunResult result;
};

/// Runs the scene and counts self-intersections after every step; `extra`, when set, is a
/// measure of the positions whose smallest value over the steps is kept.
Watched watch(const Scene& scene, const std::function<double(const Eigen::VectorXd&)>& extra = {}) {
  remesh::SheetMesh mesh;
  SheetState initial;
  initial_sheet(scene, mesh, initial);
  const Eigen::MatrixX3i faces = mesh.faces();
  const collision::SelfContactMesh contact_mesh =
      collision::SelfContactMesh::from_faces(faces, mesh.num_vertices());
  Watched w;
  RunOptions options;
  options.on_step = [&](const StepReport& r) {
    ++w.steps;
    const int n = collision::count_self_intersections(r.state->positions_matrix(), faces);
    if (n > 0 && w.first_bad_step < 0) w.first_bad_step = r.step;
    w.max_intersections = std::max(w.max_intersections, n);
    w.min_separation = std::min(
        w.min_separation, collision::min_self_distance(contact_mesh, r.state->positions, 0.01));
    if (extra) w.min_extra = std::min(w.min_extra, extra(r.state->positions));
    if (scene.ground && !r.obstacle_distance.empty())
      w.min_ground = std::min(w.min_ground, r.obstacle_distance[0]);
  };
  const auto t0 = std::chrono::steady_clock::now();
  w.result = run_scene(scene, options);
  w.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return w;
}

void report(const char* name, const Watched& w) {
  const SelfContactStatistics sc = w.result.self_contact.value_or(SelfContactStatistics{});
  std::printf(
      "%s: %d steps, %.2f s, min separation %.3g m, max active pairs %d, self-contact %.2f s, "
      "pattern changes %d, Newton iterations %d, most intersecting pairs %d, min height %.3g m\n",
      name, w.steps, w.seconds, w.min_separation, sc.max_active_pairs, sc.seconds,
      sc.pattern_changes, w.result.totals.newton_iterations, w.max_intersections, w.min_ground);
}

}  // namespace

TEST(SelfContact, StripOverRodEndsCrossWithoutIntersecting) {
  // A 30 x 3 cm strip of soft paper (D = 1e-5 N m) released flat over a rod (radius 5 mm, axis
  // along y), its centre 3 cm off the rod and turned by 8 degrees: the two ends fall, swing under
  // the rod and the short one runs into the long one there (about 10 cm below the rod).
  Scene s;
  s.name = "strip over rod";
  s.sheet.width = 0.30;
  s.sheet.height = 0.03;
  s.sheet.edge_length = 0.01;
  s.sheet.material.bending_stiffness = 1e-5;
  s.sheet.position = Eigen::Vector3d(0.03, 0, 0.2 + 0.005 + 0.001);
  s.sheet.rotation_deg = Eigen::Vector3d(0, 0, 8);
  s.ground = false;
  collision::ColliderSpec rod;
  rod.kind = collision::ColliderKind::cylinder;
  rod.radius = 0.005;
  rod.length = 0.12;
  rod.friction = 0.3;
  collision::Keyframe k;
  k.translation = Eigen::Vector3d(0, 0, 0.2);
  k.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  rod.keyframes.push_back(k);
  s.obstacles.push_back(rod);
  // Until the ends have met and parted again (later the strip slides off the rod).
  s.duration = 0.5;
  s.time_step = 0.005;
  // How close the short end (first 5 cm) comes to the long end (last 10 cm): vertices of one
  // against faces of the other.
  remesh::SheetMesh mesh;
  SheetState initial;
  initial_sheet(s, mesh, initial);
  const Eigen::MatrixX2d X = mesh.material_coords();
  const Eigen::MatrixX3i F = mesh.faces();
  const collision::SelfContactMesh cm =
      collision::SelfContactMesh::from_faces(F, mesh.num_vertices());
  const auto ends_distance = [&](const Eigen::VectorXd& x) {
    auto P = [&](int v) { return Eigen::Vector3d(x.segment<3>(3 * v)); };
    auto region = [&](int v) { return X(v, 0) < 0.05 ? 0 : (X(v, 0) > 0.2 ? 1 : -1); };
    double d2 = INF;
    for (const auto& [v, f] :
         collision::find_self_contact_candidates(cm, x, x, 0.01).point_triangle) {
      const int r = region(v);
      if (r < 0 || region(F(f, 0)) != 1 - r || region(F(f, 1)) != 1 - r || region(F(f, 2)) != 1 - r)
        continue;
      d2 = std::min(d2, collision::point_triangle_distance_squared(
                            {P(v), P(F(f, 0)), P(F(f, 1)), P(F(f, 2))}));
    }
    return std::sqrt(d2);
  };
  const Watched w = watch(s, ends_distance);
  report("strip over rod", w);
  std::printf("strip over rod: closest approach of the two ends %.3g m\n", w.min_extra);
  EXPECT_LT(w.min_extra, s.contact.dhat) << "the ends met under the rod";
  EXPECT_EQ(w.max_intersections, 0) << "first at step " << w.first_bad_step;
  EXPECT_EQ(w.result.quality.self_intersections, 0);
  // The ends did meet: pairs came within the contact thickness.
  EXPECT_GT(w.result.self_contact.value_or(SelfContactStatistics{}).max_active_pairs, 0);
  EXPECT_GT(w.min_separation, 0.0);
  EXPECT_LT(w.min_separation, s.contact.dhat);
}

TEST(SelfContact, SheetFoldedOntoItself) {
  // The top half of a sheet carried over its bottom half and let go there falls onto it and
  // rests on it (test_scenes::sheet_folded_onto_itself).
  const Scene s = test_scenes::sheet_folded_onto_itself(0.004, 0.8);
  const Watched w = watch(s);
  report("fold", w);
  EXPECT_EQ(w.max_intersections, 0) << "first at step " << w.first_bad_step;
  EXPECT_GT(w.min_ground, 0.0) << "no vertex below the ground";
  EXPECT_GT(w.result.self_contact.value_or(SelfContactStatistics{}).max_active_pairs, 0);
  EXPECT_GT(w.min_separation, 0.0);
  EXPECT_LT(w.min_separation, s.contact.dhat);
  // Folded: the lifted edge lies over the left half at the end, above the layer under it.
  const Eigen::MatrixX3d x = w.result.state.positions_matrix();
  const Eigen::MatrixX2d X = w.result.mesh.material_coords();
  for (int v = 0; v < X.rows(); ++v)
    if (X(v, 0) > 0.12 - 1e-9) {
      EXPECT_LT(x(v, 0), -0.04) << "vertex " << v << " of the lifted edge is over the left half";
      EXPECT_LT(x(v, 2), 0.003) << "vertex " << v << " rests on the bottom layer";
    }
}
