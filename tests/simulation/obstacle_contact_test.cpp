// Obstacle contact end to end: a keyframed sphere presses a sheet onto the ground and drags it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "collision/barrier.hpp"
#include "collision/collider_factory.hpp"
#include "simulation/energies/contact_energy.hpp"
#include "simulation/errors.hpp"
#include "simulation/integrator.hpp"
#include "simulation/run.hpp"
#include "simulation/simulate.hpp"

using namespace papersim;
using namespace papersim::simulation;

namespace {

/// A 10 x 10 cm sheet (5 mm edges) on the ground; a 2 cm sphere comes down over 0.25 s until
/// its bottom is 0.07 mm above the ground (the sheet rests at about 0.16 mm: it is squeezed
/// between both barriers), then moves 2 cm along x in 0.25 s. 10 ms steps.
Scene press_and_drag(double sphere_friction, double ground_friction, BendingModel model) {
  const double gap = 7e-5;
  Scene s;
  s.sheet.material.bending_model = model;
  s.sheet.width = s.sheet.height = 0.1;
  s.sheet.edge_length = 5e-3;
  s.sheet.position = Eigen::Vector3d(0, 0, 2e-4);
  s.duration = 0.5;
  s.time_step = 1e-2;
  s.ground = true;
  s.ground_friction = ground_friction;
  s.contact.faces = true;
  collision::ColliderSpec sphere;
  sphere.kind = collision::ColliderKind::sphere;
  sphere.radius = 0.02;
  sphere.friction = sphere_friction;
  collision::Keyframe k;
  k.time = 0.0;
  k.translation = Eigen::Vector3d(0, 0, 0.025);
  sphere.keyframes.push_back(k);
  k.time = 0.25;
  k.translation = Eigen::Vector3d(0, 0, 0.02 + gap);
  sphere.keyframes.push_back(k);
  k.time = 0.5;
  k.translation = Eigen::Vector3d(0.02, 0, 0.02 + gap);
  sphere.keyframes.push_back(k);
  s.obstacles.push_back(sphere);
  return s;
}

double mean_x(const RunResult& r) {
  double m = 0;
  for (int v = 0; v < r.state.num_vertices(); ++v) m += r.state.positions[3 * v];
  return m / r.state.num_vertices();
}

}  // namespace

// Friction 0.8 on the sphere against 0.1 on the ground: the squeezed sheet goes with the sphere
// (most of its 2 cm); with the coefficients swapped it stays. Neither obstacle is ever entered.
// The sheet goes along when the squeeze force N exceeds 0.1 W / (0.8 - 0.1), W its weight; N
// comes from the indentation of a dimple narrower than the 5 mm mesh, so its value depends on
// the bending discretisation (docs/elastica_30deg_diagnosis.md section 6). A 0.07 mm gap
// squeezes hard enough for both models (measured: 18.9 / 18.0 mm dragged, 0.01 / 0.8 mm held
// under fit / morley); at 0.1 mm morley drags only 9.9 mm.
TEST(ObstacleContact, MovingSphereSqueezesAndDragsTheSheet) {
  for (BendingModel model : {BendingModel::fit, BendingModel::morley}) {
    SCOPED_TRACE(model == BendingModel::fit ? "fit" : "morley");
    const RunResult dragged = run_scene(press_and_drag(0.8, 0.1, model), {});
    const RunResult held = run_scene(press_and_drag(0.1, 0.8, model), {});
    for (const RunResult* r : {&dragged, &held}) {
      const std::vector<double>& d = r->quality.min_obstacle_distance;
      ASSERT_EQ(d.size(), 2u);
      EXPECT_GT(d[0], 0.0);   // ground
      EXPECT_GT(d[1], 0.0);   // sphere
      EXPECT_LT(d[1], 3e-4);  // it did press the sheet (within the contact thickness)
      EXPECT_EQ(r->quality.self_intersections, 0);
    }
    EXPECT_GT(mean_x(dragged), 0.015);
    EXPECT_LT(std::abs(mean_x(held)), 0.002);
  }
}

namespace {

/// A 4 x 4 cm sheet (1 cm edges) resting under gravity on a sphere of radius 5 cm (or on the
/// bottom of a cavity of radius 10 cm) whose scale goes from 1 to `end_scale` between 0.05 and
/// 0.25 s and then holds until 0.35 s; 5 ms steps, no ground.
Scene resting_on_scaled(papersim::collision::ColliderKind kind, double end_scale) {
  const bool cavity = kind == papersim::collision::ColliderKind::inverted_sphere;
  const double radius = cavity ? 0.1 : 0.05;
  Scene s;
  s.sheet.width = s.sheet.height = 0.04;
  s.sheet.edge_length = 0.01;
  s.sheet.position = Eigen::Vector3d(0, 0, cavity ? -radius + 6e-3 : radius + 2e-4);
  s.duration = 0.35;
  s.time_step = 5e-3;
  s.ground = false;
  s.contact.faces = true;
  // In the cavity the sheet's corners carry its weight; the automatic stiffness (the resting
  // pressure rho_A g) holds them micrometres from the wall, less than the wall moves in a step,
  // and every step would be split until it does not (see the crumple scenario).
  if (cavity) s.contact.stiffness = 40.0;
  papersim::collision::ColliderSpec c;
  c.kind = kind;
  c.radius = radius;
  c.friction = 0.5;
  papersim::collision::Keyframe k;
  k.time = 0.05;
  c.keyframes.push_back(k);
  k.time = 0.25;
  k.scale = end_scale;
  c.keyframes.push_back(k);
  s.obstacles.push_back(c);
  return s;
}

/// Smallest distance of the final sheet's vertices to the scene's first obstacle at the end [m].
double final_gap(const Scene& scene, const RunResult& r) {
  const auto obstacle = papersim::collision::make_collider(scene.obstacles[0]);
  double gap = INFINITY;
  for (int v = 0; v < r.state.num_vertices(); ++v)
    gap = std::min(gap, obstacle->distance(r.state.positions.segment<3>(3 * v), scene.duration));
  return gap;
}

}  // namespace

// A sheet resting on a growing or shrinking sphere, or on the bottom of a shrinking cavity, is
// carried with the surface (the barrier is evaluated against the obstacle at the step end and
// the impact rule sees the surface's radial velocity): never inside the obstacle at any step,
// and at the end it rests on the surface at its final size, within the contact thickness.
TEST(ObstacleContact, SheetIsCarriedByAGrowingOrShrinkingSphere) {
  using papersim::collision::ColliderKind;
  struct Case {
    ColliderKind kind;
    double end_scale;
  };
  for (const Case& c : {Case{ColliderKind::sphere, 1.4}, Case{ColliderKind::sphere, 0.6},
                        Case{ColliderKind::inverted_sphere, 0.5}}) {
    SCOPED_TRACE(std::string(papersim::collision::to_string(c.kind)) + " to scale " +
                 std::to_string(c.end_scale));
    const Scene scene = resting_on_scaled(c.kind, c.end_scale);
    const RunResult r = run_scene(scene, {});
    ASSERT_EQ(r.quality.min_obstacle_distance.size(), 1u);
    EXPECT_GT(r.quality.min_obstacle_distance[0], 0.0);
    EXPECT_EQ(r.quality.self_intersections, 0);
    EXPECT_LE(r.quality.max_principal_stretch, 1 + scene.sheet.material.strain_limit);
    // At the end the sheet rests on the surface at its final size: its nearest vertex is within
    // the contact thickness, where the barrier holds its weight (a flat 4 cm sheet in a 5 cm
    // bowl touches it with its corners, on a sphere with its centre).
    const double gap = final_gap(scene, r);
    EXPECT_GT(gap, 0.0);
    EXPECT_LT(gap, scene.contact.dhat);
    int centre = 0;
    for (int v = 0; v < r.state.num_vertices(); ++v)
      if (r.state.positions.segment<2>(3 * v).norm() <
          r.state.positions.segment<2>(3 * centre).norm())
        centre = v;
    const double z = r.state.positions[3 * centre + 2];
    // It did move with the surface: the surface moved by at least 2 cm.
    EXPECT_GT(std::abs(z - scene.sheet.position.z()), 0.019);
  }
}

// Following moving obstacles (Integrator::follow_obstacles): the sheet resting on the bottom of a
// shrinking cavity at the automatic stiffness (its resting pressure rho_A g), which holds its
// corners micrometres from the wall while the wall moves 0.5 mm per 5 ms step. A step that
// starts against the wall at its end starts with the corners outside the cavity; halving cannot
// catch up (the corners rest closer to the wall than it moves in a halved step) and the run
// fails when the wall starts to move. Following the wall within the step takes every step whole:
// the sheet is never inside the wall, and it ends resting on the smaller cavity.
TEST(ObstacleContact, ShrinkingCavityIsFollowedWithinTheStep) {
  using papersim::collision::ColliderKind;
  Scene scene = resting_on_scaled(ColliderKind::inverted_sphere, 0.5);
  scene.contact.stiffness = 0.0;  // automatic: rho_A g
  const RunResult r = run_scene(scene, {});
  std::printf("followed: %d Newton iterations (%d following), %d split solves, %d substeps\n",
              r.totals.newton_iterations, r.totals.following_iterations, r.totals.failed_solves,
              r.totals.substeps);
  ASSERT_EQ(r.quality.min_obstacle_distance.size(), 1u);
  EXPECT_GT(r.quality.min_obstacle_distance[0], 0.0);
  EXPECT_EQ(r.quality.self_intersections, 0);
  EXPECT_LE(r.quality.max_principal_stretch, 1 + scene.sheet.material.strain_limit);
  EXPECT_GT(r.totals.following_iterations, 0);
  EXPECT_EQ(r.totals.failed_solves, 0);
  // It rests on the cavity at its final size (radius 5 cm): its lowest vertex within the
  // contact thickness of the wall, 5 cm below the centre.
  const double gap = final_gap(scene, r);
  EXPECT_GT(gap, 0.0);
  EXPECT_LT(gap, scene.contact.dhat);
  scene.newton.follow_obstacles = false;
  EXPECT_THROW(run_scene(scene, {}), NumericError);
}

// The check of a state the integrator has not produced (a remeshed sheet, Run::remesh_pass)
// starts the step as a step does: an obstacle that closes in on the sheet during the step is
// where it is at the step's start. Mid-run in the shrinking cavity, the sheet's corners rest
// closer to the wall than it moves in a step: against the wall's end-of-step pose the state is
// infeasible, so every remeshing pass while a roller or a cavity presses the sheet was undone.
TEST(ObstacleContact, StartOfAStepIsFeasibleWhereAMovingObstacleClosesIn) {
  using papersim::collision::ColliderKind;
  const Scene scene = resting_on_scaled(ColliderKind::inverted_sphere, 0.5);
  papersim::simulation::Run run(scene);
  while (run.state().time < 0.1) run.step();  // the wall moves from t = 0.05 s on
  const auto start = [&](bool follow) {
    SheetState initial;
    initial.positions = run.state().positions;
    initial.velocities = Eigen::VectorXd::Zero(initial.positions.size());
    const PhysicsSetup setup = physics_setup(scene, run.mesh(), initial);
    Terms terms = build_terms(run.mesh(), setup);
    NewtonParams params = scene.newton;
    params.follow_obstacles = follow;
    Integrator integrator(run.mesh().num_vertices(), std::move(terms.list), params);
    return integrator.start_energy(run.state(), run.time_step());
  };
  EXPECT_TRUE(std::isfinite(start(true)));
  // Evaluated against the wall where it is at the step's end, the same state is inside it.
  EXPECT_FALSE(std::isfinite(start(false)));
}

// A coupled body (ObstacleContactEnergy::set_rigid_block): the sheet's contact depends on the
// body's vertical displacement q_z (x's entries after the sheet's) through r = p - q_z e_z. Under
// the flat bottom of a box the field's gradient is constant, so the term's Hessian is exact; the
// gradient and the Hessian in (vertices, q) match central differences of the value, and collision
// detection stops a body coming down before any vertex gap closes.
TEST(ObstacleContact, CoupledBodyDerivativesMatchFiniteDifferences) {
  collision::ColliderSpec spec;
  spec.kind = collision::ColliderKind::box;
  spec.half_extents = Eigen::Vector3d::Constant(0.05);  // bottom face at z = -0.05
  spec.friction = 0.0;
  std::vector<std::shared_ptr<const collision::Collider>> obstacles{collision::make_collider(spec)};
  ContactParams params;  // dhat 0.3 mm
  const int nv = 3, block = nv;
  ObstacleContactEnergy e(Eigen::Vector3d(1e-4, 2e-4, 1.5e-4), obstacles, params);
  e.set_rigid_block(0, block);
  Eigen::VectorXd x(3 * (nv + 1));
  x << 0.01, 0.0, -0.0502, -0.01, 0.01, -0.05015, 0.0, -0.02, -0.05026, 0.0, 0.0, -2e-5;
  StepContext ctx;
  ctx.h = 1e-2;
  const Eigen::VectorXd v0 = Eigen::VectorXd::Zero(x.size());
  ctx.x_t0 = &x;
  ctx.v_t0 = &v0;
  e.begin_step(ctx, x);
  SparsityBuilder pattern(nv + 1);
  e.add_pattern(pattern);
  BlockSymmetricMatrix H(pattern.finish());
  Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
  e.add_derivatives(x, g, &H, HessianProjection::psd);
  ASSERT_LT(g[3 * block + 2], 0.0);  // the sheet below pushes the body up
  const double step = 1e-9;
  for (int i = 0; i < x.size(); ++i) {
    Eigen::VectorXd a = x, b = x;
    a[i] += step;
    b[i] -= step;
    const double fd = (e.value(a) - e.value(b)) / (2 * step);
    EXPECT_NEAR(g[i], fd, 1e-5 * std::abs(g[i]) + 1e-9) << "gradient entry " << i;
    Eigen::VectorXd ga = Eigen::VectorXd::Zero(x.size()), gb = Eigen::VectorXd::Zero(x.size());
    e.add_gradient(a, ga);
    e.add_gradient(b, gb);
    const Eigen::VectorXd column = (ga - gb) / (2 * step);
    const Eigen::VectorXd unit = Eigen::VectorXd::Unit(x.size(), i);
    const Eigen::VectorXd h = H.multiply(unit);
    EXPECT_LT((h - column).norm(), 1e-4 * column.norm() + 1e-6) << "Hessian column " << i;
  }
  // The body coming down by 1 mm while the sheet holds still: stopped short of every gap.
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(x.size());
  dx[3 * block + 2] = -1e-3;
  const double alpha = e.max_step(x, dx);
  EXPECT_GT(alpha, 0.0);
  EXPECT_TRUE(std::isfinite(e.value(x + alpha * dx)));
  EXPECT_LT(alpha * 1e-3, 0.05026 - 0.05 - 2e-5);  // within the smallest gap (0.04 mm)
}

// The load rule (ObstacleContactEnergy, "Load rule"): the stiffness carried in from the last
// step moves to the one that holds the present contact force at dhat / 100: it falls that far
// at once, rises by at most ContactParams::load_raise per step (and to at most raise_limit times
// the scene's stiffness), and falls to the scene's
// stiffness when the sheet is out of contact or the rule off.
TEST(ObstacleContact, CarriedStiffnessMovesToHoldTheLoadAtAHundredthOfTheThickness) {
  collision::ColliderSpec spec;
  spec.kind = collision::ColliderKind::box;
  spec.half_extents = Eigen::Vector3d::Constant(0.05);  // top face at z = 0.05
  spec.friction = 0.0;
  const std::vector<std::shared_ptr<const collision::Collider>> obstacles{
      collision::make_collider(spec)};
  ContactParams params;  // dhat 0.3 mm, stiffness 1 Pa
  const double dhat = params.dhat, carried = 1000.0, area = 1e-4;
  const auto stiffness_at = [&](double gap, bool hold_load, Eigen::VectorXd* force = nullptr,
                                double load_raise = 2.0, double raise_limit = 1e6) {
    ContactParams p = params;
    p.hold_load = hold_load;
    p.load_raise = load_raise;
    p.raise_limit = raise_limit;
    ObstacleContactEnergy e(Eigen::VectorXd::Constant(1, area), obstacles, p);
    Eigen::VectorXd x(3);
    x << 0.0, 0.0, 0.05 + gap;
    const Eigen::VectorXd v0 = Eigen::VectorXd::Zero(3);
    StepContext ctx;
    ctx.h = 1e-3;
    ctx.x_t0 = &x;
    ctx.v_t0 = &v0;
    ctx.contact_stiffness = carried;
    e.begin_step(ctx, x);
    SheetState end;
    e.end_step(end);
    EXPECT_EQ(end.contact_stiffness, e.step_stiffness())
        << "end_step carries the step's stiffness on";
    if (force) {  // the barrier's force on the vertex at dhat / 100 with this step's stiffness
      Eigen::VectorXd y = x;
      y[2] = 0.05 + dhat / 100;
      *force = Eigen::VectorXd::Zero(3);
      e.add_gradient(y, *force);
    }
    return e.step_stiffness();
  };
  // The carried stiffness's force on the vertex at a gap.
  const auto force_now = [&](double gap) {
    return carried / dhat * area * std::abs(collision::barrier_first_derivative(gap, dhat));
  };
  // At half the thickness the carried stiffness is more than the load needs: it falls, to the
  // stiffness whose force at dhat / 100 is the carried stiffness's force now.
  Eigen::VectorXd held;
  const double k = stiffness_at(dhat / 2, true, &held);
  EXPECT_LT(k, carried);
  EXPECT_GT(k, params.stiffness);
  EXPECT_NEAR(-held[2], force_now(dhat / 2),
              1e-9 * force_now(dhat / 2));  // the gaps are z - 0.05, rounded
  // At dhat / 200 the load needs 1.93 times the carried stiffness to be held at dhat / 100: it
  // rises that far, within the bound of 2.
  const double k200 = stiffness_at(dhat / 200, true, &held);
  EXPECT_GT(k200, 1.5 * carried);
  EXPECT_LT(k200, 2 * carried);
  EXPECT_NEAR(-held[2], force_now(dhat / 200), 1e-9 * force_now(dhat / 200));
  // At dhat / 2000 it would need about 19 times: it rises by the bound, per step.
  EXPECT_NEAR(stiffness_at(dhat / 2000, true), 2 * carried, 1e-12 * carried);
  EXPECT_NEAR(stiffness_at(dhat / 2000, true, nullptr, 4.0), 4 * carried, 1e-12 * carried);
  // With a bound of 1 the rule keeps the carried stiffness there, it does not raise it.
  EXPECT_EQ(stiffness_at(dhat / 200, true, nullptr, 1.0), carried);
  // A raise stops at raise_limit times the scene's stiffness (1 Pa here), and a limit below the
  // carried stiffness keeps the carried one.
  EXPECT_EQ(stiffness_at(dhat / 2000, true, nullptr, 2.0, 1500.0), 1500.0);
  EXPECT_EQ(stiffness_at(dhat / 2000, true, nullptr, 2.0, 10.0), carried);
  // Out of contact, or the rule off: the scene's stiffness.
  EXPECT_EQ(stiffness_at(1.5 * dhat, true), params.stiffness);
  EXPECT_EQ(stiffness_at(dhat / 200, false), params.stiffness);
}

// Many spheres against a sheet by its faces: with 8 or more such obstacles the term finds the
// faces near each sphere through the faces sorted along x instead of testing every face
// (ObstacleContactEnergy::FaceBoxes). The barriers add up over the obstacles, so the energy and
// the gradient with all twelve spheres must be the sums of those with each sphere alone (the
// plain loop over every face), and the largest step the smallest of theirs: a face the search
// missed would be missing from the sum, or let the step through a sphere. The spheres are
// spread along x and sit 0.05-0.27 mm above the rippled sheet (the barrier reaches 0.3 mm), some
// across face boxes' edges.
TEST(ObstacleFaceSearch, ManySpheresFindTheFacesEachSphereAloneFinds) {
  const int n = 41;  // 41 x 41 vertices, 5 mm apart
  const double a = 5e-3;
  Eigen::MatrixX2d X(n * n, 2);
  Eigen::VectorXd x(3 * n * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int v = j * n + i;
      X.row(v) << i * a, j * a;
      x.segment<3>(3 * v) << i * a + 3e-4 * std::sin(7.0 * j), j * a + 3e-4 * std::cos(5.0 * i),
          2e-4 * std::sin(1.3 * i + 0.7 * j);
    }
  Eigen::MatrixX3i faces(2 * (n - 1) * (n - 1), 3);
  for (int j = 0, f = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int v = j * n + i;
      faces.row(f++) << v, v + 1, v + n + 1;
      faces.row(f++) << v, v + n + 1, v + n;
    }
  const Eigen::VectorXd areas = Eigen::VectorXd::Constant(n * n, a * a);
  ContactParams params;  // dhat 0.3 mm
  params.faces = true;
  params.stiffness = 100.0;
  const auto sphere = [](double cx, double cy, double r, double cz) {
    collision::ColliderSpec spec;
    spec.kind = collision::ColliderKind::sphere;
    spec.radius = r;
    spec.friction = 0.3;
    collision::Keyframe key;
    key.translation = Eigen::Vector3d(cx, cy, cz);
    spec.keyframes.push_back(key);
    return collision::make_collider(spec);
  };
  std::vector<std::shared_ptr<const collision::Collider>> spheres;
  for (int k = 0; k < 12; ++k) {
    const double cx = 0.013 + 0.0161 * k, cy = 0.02 + 0.0117 * ((k * 5) % 12),
                 r = 0.004 + 0.001 * (k % 3);
    const double gap = 5e-5 + 2e-5 * k;
    // Lowered until the sheet's surface is `gap` below it (the distance changes about one to
    // one with the height over the sheet's lowest point under the sphere).
    double cz = r + 1e-3;
    for (int it = 0; it < 6; ++it) {
      ObstacleContactEnergy probe(Eigen::VectorXd::Constant(n * n, a * a), {sphere(cx, cy, r, cz)},
                                  params);
      probe.set_faces(faces, X);
      cz -= probe.surface_distance(0, x, 0.0) - gap;
    }
    spheres.push_back(sphere(cx, cy, r, cz));
  }
  const Eigen::VectorXd v0 = Eigen::VectorXd::Zero(x.size());
  StepContext ctx;
  ctx.h = 1e-3;
  ctx.x_t0 = &x;
  ctx.v_t0 = &v0;
  const auto term = [&](std::vector<std::shared_ptr<const collision::Collider>> obstacles) {
    auto e = std::make_unique<ObstacleContactEnergy>(areas, std::move(obstacles), params);
    e->set_faces(faces, X);
    e->begin_step(ctx, x);
    return e;
  };
  Eigen::VectorXd dx(x.size());  // up towards the spheres, and sideways
  for (int v = 0; v < n * n; ++v) dx.segment<3>(3 * v) << 1e-4 * std::cos(0.3 * v), 2e-4, 1e-3;
  const auto all = term(spheres);
  const double e_all = all->value(x);
  Eigen::VectorXd g_all = Eigen::VectorXd::Zero(x.size());
  all->add_gradient(x, g_all);
  const double step_all = all->max_step(x, dx);
  double e_sum = 0, step_min = 1.0;
  Eigen::VectorXd g_sum = Eigen::VectorXd::Zero(x.size());
  int touching = 0;
  for (const auto& s : spheres) {
    const auto one = term({s});
    const double e = one->value(x);
    ASSERT_TRUE(std::isfinite(e));
    touching += e > 0;
    e_sum += e;
    one->add_gradient(x, g_sum);
    step_min = std::min(step_min, one->max_step(x, dx));
  }
  EXPECT_EQ(touching, 12);  // every sphere is within the barrier of some face
  EXPECT_NEAR(e_all, e_sum, 1e-12 * e_sum);
  EXPECT_LT((g_all - g_sum).norm(), 1e-12 * g_sum.norm());
  EXPECT_LT(step_min, 0.5);  // the spheres do stop the motion
  EXPECT_NEAR(step_all, step_min, 1e-9 * step_min);
  // A NaN position (a diverged trial) cannot be sorted: the faces are then tested one by one,
  // and the faces at the NaN vertex are out of contact in both searches.
  Eigen::VectorXd y = x;
  y[3 * (n * n / 2) + 2] = std::numeric_limits<double>::quiet_NaN();
  double y_sum = 0;
  for (const auto& s : spheres) y_sum += term({s})->value(y);
  EXPECT_NEAR(all->value(y), y_sum, 1e-12 * y_sum);
}
