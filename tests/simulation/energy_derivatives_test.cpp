// Finite-difference tests of the gradient and Hessian of every energy term.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <functional>
#include <memory>
#include <random>
#include <vector>

#include "collision/collider.hpp"
#include "collision/shapes.hpp"
#include "remesh/remesh.hpp"
#include "remesh/sheet_generator.hpp"
#include "simulation/energies/bending_energy.hpp"
#include "simulation/energies/contact_energy.hpp"
#include "simulation/energies/handle_energy.hpp"
#include "simulation/energies/membrane_energy.hpp"
#include "simulation/energies/self_contact_energy.hpp"
#include "simulation/energies/vertex_energies.hpp"

using namespace papersim;
using namespace papersim::simulation;

namespace {

struct Fixture {
  remesh::SheetMesh mesh;
  Eigen::VectorXd x0;  // initial world positions
  Eigen::VectorXd x;   // a deformed state
};

/// A 5 x 6 sheet, 10 x 12 cm, lifted to z = 2 mm and deformed smoothly (bent, slightly
/// stretched so that the strain-limit barrier and tension are active on some faces).
Fixture make_fixture(double stretch = 1.0, double bend = 8.0, double noise = 2e-4) {
  remesh::RectangleOptions o;
  o.width = 0.1;
  o.height = 0.12;
  o.nx = 5;
  o.ny = 6;
  o.jitter = 0.2;
  o.seed = 7;
  Fixture f{remesh::make_rectangle(o), {}, {}};
  const Eigen::MatrixX2d X = f.mesh.material_coords();
  f.x0.resize(3 * X.rows());
  f.x.resize(3 * X.rows());
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int v = 0; v < X.rows(); ++v) {
    const double s = X(v, 0), t = X(v, 1);
    f.x0.segment<3>(3 * v) << s, t, 2e-3;
    // Cylinder of curvature `bend` about the y axis, stretched along y, plus noise.
    f.x.segment<3>(3 * v) << std::sin(bend * s) / bend, stretch * t,
        2e-3 + (1 - std::cos(bend * s)) / bend;
    f.x.segment<3>(3 * v) += noise * Eigen::Vector3d(u(rng), u(rng), u(rng));
  }
  return f;
}

Eigen::MatrixXd dense(const BlockSymmetricMatrix& A) {
  const int n = A.size();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
  for (int c = 0; c < n; ++c)
    for (int k = A.column_starts()[c]; k < A.column_starts()[c + 1]; ++k) {
      const int r = A.row_indices()[k];
      M(r, c) = M(c, r) = A.values()[k];
    }
  return M;
}

/// Central differences of value against the gradient, and of the gradient against the
/// Hessian. Step 1e-7 m: truncation O(h^2 f''') and round-off O(eps f / h) both far below
/// the tolerances for positions of order 0.1 m. Terms with a log barrier near its singularity
/// have large third derivatives and take a smaller step. The Hessian checked is the exact one
/// (HessianProjection::none): a projected one matches only where projecting changes nothing.
void check_derivatives(EnergyTerm& term, int nv, const Eigen::VectorXd& x, double tol_grad = 1e-6,
                       double tol_hess = 1e-5, bool check_hessian = true, double step = 1e-7) {
  // Auxiliary unknowns (the bending energy's edge slopes) follow the vertex blocks; the
  // condensed Hessian is the Schur complement of their block.
  term.set_auxiliary_offset(nv);
  SparsityBuilder pattern(nv + term.auxiliary_blocks(), nv);
  term.add_pattern(pattern);
  term.update_pattern(x);  // terms with a dynamic pattern (self-contact) choose it at x
  term.add_dynamic_pattern(pattern);
  BlockSymmetricMatrix H(pattern.finish());
  Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
  term.add_derivatives(x, g, &H, HessianProjection::none);
  // The factorisation takes only the declared structure: nothing may be written outside it.
  int outside = 0;
  for (std::size_t k = 0; k < H.values().size(); ++k)
    outside += H.values()[k] != 0.0 && !H.in_structure()[k];
  EXPECT_EQ(outside, 0) << term.name() << " writes outside its declared sparsity";
  Eigen::VectorXd g_fd(x.size());
  Eigen::MatrixXd H_fd(x.size(), x.size());
  for (int i = 0; i < x.size(); ++i) {
    Eigen::VectorXd xp = x, xm = x;
    xp[i] += step;
    xm[i] -= step;
    g_fd[i] = (term.value(xp) - term.value(xm)) / (2 * step);
    Eigen::VectorXd gp = Eigen::VectorXd::Zero(x.size()), gm = gp;
    term.add_gradient(xp, gp);
    term.add_gradient(xm, gm);
    H_fd.col(i) = (gp - gm) / (2 * step);
  }
  const double gscale = std::max(g.norm(), 1e-12);
  EXPECT_LT((g - g_fd).norm() / gscale, tol_grad) << term.name() << " gradient";
  if (check_hessian) {
    Eigen::MatrixXd Hd = dense(H);
    if (Hd.rows() > x.size()) {
      const int n = static_cast<int>(x.size()), m = static_cast<int>(Hd.rows()) - n;
      const Eigen::MatrixXd Haa = Hd.bottomRightCorner(m, m), Hxa = Hd.topRightCorner(n, m);
      Hd = (Hd.topLeftCorner(n, n) - Hxa * Haa.ldlt().solve(Hxa.transpose())).eval();
    }
    const double hscale = std::max(H_fd.norm(), 1e-12);
    EXPECT_LT((Hd - H_fd).norm() / hscale, tol_hess) << term.name() << " Hessian";
  }
}

}  // namespace

TEST(EnergyDerivatives, Membrane) {
  // Stretched by 0.3% along y: tension everywhere, so the clamped compressive stress is not in
  // play and the Hessian is exact; the strain-limit barrier (active above 0.25%) contributes.
  Fixture f = make_fixture(1.0028, 2.0, 2e-6);
  Material m;
  MembraneEnergy e(f.mesh.material_coords(), f.mesh.faces(), m);
  const Eigen::MatrixX2d s = e.principal_stretches(f.x);
  EXPECT_GT(s.col(0).maxCoeff(), 1.0025) << "barrier active on some face";
  EXPECT_LT(s.col(0).maxCoeff(), 1.005);
  check_derivatives(e, f.mesh.num_vertices(), f.x, 1e-6, 1e-4, true, 1e-8);
}

TEST(EnergyDerivatives, MembraneArc) {
  // The arc model on a bent sheet with the exact Hessian (hinge Hessians included): at a
  // curvature of 8 / m (faces of 2-3 cm: s = 0.2 rad, the correction nearly whole) with the
  // strain-limit barrier active on some faces, and at 25 / m (s about 0.7 rad, where the fade
  // and its derivatives are in play; the faces' chords stretch by up to 3% there, so without
  // the limit).
  for (const double bend : {8.0, 25.0}) {
    Fixture f = make_fixture(1.0005, bend, 2e-6);
    Material m;
    m.membrane_model = MembraneModel::arc;
    if (bend > 10) m.strain_limit = 0;
    MembraneEnergy e(f.mesh, m);
    ASSERT_TRUE(e.arc());
    check_derivatives(e, f.mesh.num_vertices(), f.x, 1e-6, 1e-4, true, 1e-8);
  }
}

/// A sheet of 5 mm cells at `angle` to its sides, flat and rolled isometrically onto a
/// cylinder of radius R about the material y axis.
struct RolledSheet {
  remesh::SheetMesh mesh;
  Eigen::VectorXd flat, rolled;
};
RolledSheet rolled_sheet(double width, double height, double angle, double R) {
  remesh::LatticeOptions o;
  o.width = width;
  o.height = height;
  o.edge_length = 5e-3;
  o.angle = angle;
  RolledSheet s{remesh::make_rotated_lattice(o), {}, {}};
  const Eigen::MatrixX2d X = s.mesh.material_coords();
  s.flat.resize(3 * X.rows());
  s.rolled.resize(3 * X.rows());
  for (int v = 0; v < X.rows(); ++v) {
    s.flat.segment<3>(3 * v) << X(v, 0), X(v, 1), 0;
    s.rolled.segment<3>(3 * v) << R * std::sin(X(v, 0) / R), X(v, 1),
        R * (1 - std::cos(X(v, 0) / R));
  }
  return s;
}

TEST(MembraneArc, MeasuresASheetRolledOnACylinderAsUnstretched) {
  // A 6 x 4 cm sheet of 5 mm cells at 45 degrees to its sides, rolled isometrically onto a
  // cylinder of radius 5 cm (k l = 0.1-0.14 rad). Its chords are short by (k l cos^2 a)^2 / 24:
  // the chord model sees a compression that no placement of the vertices removes (membrane
  // locking); the arc model measures the edges along the surface and sees almost none: what
  // remains is of higher order in k l and from the fade-out (measured: 4e-6 of the chord
  // model's energy). A correction whose curvature were off by 1.6% would leave 1e-3 of it.
  const double width = 0.06, height = 0.04, R = 0.05;
  const RolledSheet s = rolled_sheet(width, height, M_PI / 4, R);
  const Eigen::VectorXd &flat = s.flat, &rolled = s.rolled;
  Material chord_material, arc_material;
  // the rolled chords are not stretched anyway
  chord_material.strain_limit = arc_material.strain_limit = 0;
  arc_material.membrane_model = MembraneModel::arc;
  const MembraneEnergy chord(s.mesh, chord_material), arc(s.mesh, arc_material);
  EXPECT_EQ(arc.value(flat), chord.value(flat))
      << "flat: no curvature, no correction (both at round-off)";
  const double e_chord = chord.value(rolled), e_arc = arc.value(rolled);
  // The chord model's energy is the locking strain's: about Eh/2 (k^2 l^2 / 24)^2 per area.
  const double strain = std::pow(5e-3 / R, 2) / 24;
  EXPECT_GT(e_chord,
            0.1 * 0.5 * chord_material.stretch_stiffness * strain * strain * width * height);
  EXPECT_LT(e_arc, 1e-3 * e_chord) << "chord " << e_chord << " J, arc " << e_arc << " J";
}

TEST(MembraneArc, GreenStrainsAreWhatEachModelMeasuresAndTheSizingSeesThem) {
  // The rolled sheet of the test above, on a 3 cm cylinder (k l = 0.17-0.24 rad). Under the
  // chord model the faces' Green strains are the chords' (their principal values give
  // principal_stretches), compressed across the axis by about (k l cos^2 a)^2 / 24; under the arc
  // model they are C' - I, almost zero. A remeshing pass sizing by the arc strain therefore asks
  // for no refinement against compression where one sizing by the chords does.
  const double R = 0.03;
  const RolledSheet s = rolled_sheet(0.06, 0.04, M_PI / 4, R);
  Material chord_material, arc_material;
  arc_material.membrane_model = MembraneModel::arc;
  const MembraneEnergy chord(s.mesh, chord_material), arc(s.mesh, arc_material);
  const Eigen::MatrixX3d e_chord = chord.green_strains(s.rolled),
                         e_arc = arc.green_strains(s.rolled);
  const Eigen::MatrixX2d stretch = chord.principal_stretches(s.rolled);
  ASSERT_EQ(e_chord.rows(), s.mesh.num_faces());
  double most_chord = 0, most_arc = 0;
  for (int f = 0; f < e_chord.rows(); ++f) {
    const auto eig = [](const Eigen::RowVector3d& e) {
      return Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(
                 (Eigen::Matrix2d() << e[0], e[2], e[2], e[1]).finished())
          .eigenvalues();
    };
    const Eigen::Vector2d lc = eig(e_chord.row(f)), la = eig(e_arc.row(f));
    EXPECT_NEAR(std::sqrt(1 + 2 * lc[0]), stretch(f, 1), 1e-12);
    EXPECT_NEAR(std::sqrt(1 + 2 * lc[1]), stretch(f, 0), 1e-12);
    most_chord = std::max(most_chord, -lc[0]);
    most_arc = std::max(most_arc, la.cwiseAbs().maxCoeff());
  }
  const double locking = std::pow(5e-3 / R, 2) / 24;  // (k l)^2 / 24 at the cells' 5 mm
  EXPECT_GT(most_chord, 0.5 * locking);
  EXPECT_LT(most_arc, 0.05 * most_chord) << "chord " << most_chord << ", arc " << most_arc;
  // The sizing, with a compression criterion fine enough to see the chords' strain (ArcSim's
  // metric asks for l^2 |e| <= c^2: c = 2e-5 m against 5 mm cells; at refine_angle 0.05 rad a
  // face is refined when it holds more than (0.05 / 2 pi)^2 = 6.3e-5 of strain).
  remesh::RemeshParams p;
  p.refine_compression = 2e-5;
  p.refine_angle = 0.05;
  remesh::RemeshState rs;
  rs.positions =
      Eigen::Map<const Eigen::MatrixXd>(s.rolled.data(), 3, s.mesh.num_vertices()).transpose();
  rs.velocities = Eigen::MatrixX3d::Zero(s.mesh.num_vertices(), 3);
  // A face is refined when the criterion asks for edges shorter than the 5 mm cells.
  const auto refined = [&](const remesh::RemeshState& state) {
    int n = 0;
    for (const remesh::SizingTerms& t : remesh::sizing_terms(s.mesh, state, p))
      n += Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(t.compression).eigenvalues()[1] >
           1 / (5e-3 * 5e-3);
    return n;
  };
  const int refined_by_chords = refined(rs);
  rs.membrane_strain = e_arc;
  const int refined_by_arcs = refined(rs);
  EXPECT_GT(refined_by_chords, s.mesh.num_faces() / 2);
  EXPECT_EQ(refined_by_arcs, 0);
}

/// The Hessian term adds at x, dense.
Eigen::MatrixXd dense_hessian(EnergyTerm& term, int nv, const Eigen::VectorXd& x,
                              HessianProjection projection) {
  SparsityBuilder pattern(nv, nv);
  term.add_pattern(pattern);
  BlockSymmetricMatrix H(pattern.finish());
  Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
  term.add_derivatives(x, g, &H, projection);
  return dense(H);
}

TEST(MembraneArc, ProjectedHessianIsExactWhereNothingIsProjectedAndPsdElsewhere) {
  // The projected Hessian is assembled from factors of its PSD blocks (one triangle of a rank
  // update), the exact one as a plain product. On a sheet rolled isometrically onto a cylinder
  // (5 mm cells at 30 degrees, R = 5 cm) the arcs are nearly unstretched, so dW/dC' is small:
  // the terms that projecting changes or drops (the geometric ones, proportional to it) nearly
  // vanish, and the two agree to the order of the residual strain, about 1e-6 (measured 8.5e-7
  // of the Hessian's norm; bound 1e-5; a wrong factor is off by order one). Stretched or
  // compressed by a further 0.3% along the axis, the geometric terms are in play (compressed,
  // the chords' and the arcs' are indefinite and projected): the projected Hessian must be PSD,
  // and a rigid translation must stay in its null space (the chords and the curvatures do not
  // see it).
  const RolledSheet s = rolled_sheet(0.03, 0.02, M_PI / 6, 0.05);
  const int nv = s.mesh.num_vertices();
  const Eigen::VectorXd& rolled = s.rolled;
  Material m;
  m.strain_limit = 0;
  m.membrane_model = MembraneModel::arc;
  MembraneEnergy e(s.mesh, m);
  const Eigen::MatrixXd projected = dense_hessian(e, nv, rolled, HessianProjection::psd);
  const Eigen::MatrixXd exact = dense_hessian(e, nv, rolled, HessianProjection::none);
  EXPECT_LT((projected - exact).norm(), 1e-5 * exact.norm());

  for (const double scale : {1.003, 0.997}) {
    Eigen::VectorXd strained = rolled;
    for (int v = 0; v < nv; ++v) strained[3 * v + 1] *= scale;
    const Eigen::MatrixXd H = dense_hessian(e, nv, strained, HessianProjection::psd);
    EXPECT_LT((H - H.transpose()).norm(), 1e-12 * H.norm()) << "scale " << scale;
    const Eigen::VectorXd eigenvalues =
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H).eigenvalues();
    EXPECT_GT(eigenvalues.minCoeff(), -1e-10 * eigenvalues.maxCoeff()) << "scale " << scale;
    for (int axis = 0; axis < 3; ++axis) {
      Eigen::VectorXd t = Eigen::VectorXd::Zero(3 * nv);
      for (int v = 0; v < nv; ++v) t[3 * v + axis] = 1;
      EXPECT_LT((H * t).norm(), 1e-9 * H.norm() * t.norm())
          << "scale " << scale << ", axis " << axis;
    }
  }
}

TEST(EnergyDerivatives, MembraneRejectsStatesPastTheLimit) {
  Fixture f = make_fixture(1.006);
  MembraneEnergy e(f.mesh.material_coords(), f.mesh.faces(), Material{});
  EXPECT_EQ(e.value(f.x), INF);
}

TEST(EnergyDerivatives, MembraneUnderTheCompressionLimit) {
  // Compressed by 2.7% along y with a 5% compression limit: the barrier on the smallest
  // principal stretch is active below 2.5% on every face. The exact Hessian (no projection:
  // under compression the geometric term is indefinite) against finite differences.
  Fixture f = make_fixture(0.973, 2.0, 2e-6);
  Material m;
  m.compression_limit = 0.05;
  MembraneEnergy e(f.mesh.material_coords(), f.mesh.faces(), m);
  const Eigen::MatrixX2d s = e.principal_stretches(f.x);
  ASSERT_LT(s.col(1).maxCoeff(), 0.975) << "barrier active on every face";
  ASSERT_GT(s.col(1).minCoeff(), 0.95);
  check_derivatives(e, f.mesh.num_vertices(), f.x, 1e-6, 1e-4, true, 1e-8);
  // The barrier adds energy and pushes the faces apart along y: the same state without the
  // limit has less energy.
  Material free = m;
  free.compression_limit = 0;
  MembraneEnergy e_free(f.mesh.material_coords(), f.mesh.faces(), free);
  EXPECT_GT(e.value(f.x), e_free.value(f.x));
}

TEST(EnergyDerivatives, MembraneRejectsStatesPastTheCompressionLimit) {
  Fixture f = make_fixture(0.94, 2.0, 2e-6);
  Material m;
  m.compression_limit = 0.05;
  EXPECT_EQ(MembraneEnergy(f.mesh.material_coords(), f.mesh.faces(), m).value(f.x), INF);
  m.compression_limit = 0;  // off: a finite StVK energy
  EXPECT_TRUE(
      std::isfinite(MembraneEnergy(f.mesh.material_coords(), f.mesh.faces(), m).value(f.x)));
}

class BendingDerivatives : public ::testing::TestWithParam<BendingModel> {};

TEST_P(BendingDerivatives, ExactHessian) {
  Fixture f = make_fixture();
  Material m;
  m.bending_model = GetParam();
  remesh::SheetMesh mesh = f.mesh;
  Eigen::MatrixX3d k = Eigen::MatrixX3d::Constant(mesh.num_faces(), 3, 0.0);
  k.col(0).setConstant(3.0);  // some plastic curvature
  mesh.set_plastic_curvature(k);
  mesh.set_damage(Eigen::VectorXd::Constant(mesh.num_faces(), 0.5));
  // The Morley model condenses its slope unknowns: check_derivatives compares the Schur
  // complement of its (x, slope) Hessian with differences of the condensed gradient.
  const std::unique_ptr<BendingEnergy> e = make_bending_energy(mesh, m, BendingHessian::exact);
  check_derivatives(*e, mesh.num_vertices(), f.x);
}

TEST_P(BendingDerivatives, ExactHessianWithAVaryingPlasticStateSetAfterConstruction) {
  // Plastic curvature and damage that differ from face to face, handed to the term after it
  // was built (as the plastic update of a run does).
  Fixture f = make_fixture();
  Material m;
  m.bending_model = GetParam();
  m.weakening = 2.0;
  const std::unique_ptr<BendingEnergy> e = make_bending_energy(f.mesh, m, BendingHessian::exact);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::MatrixX3d k(f.mesh.num_faces(), 3);
  Eigen::VectorXd damage(f.mesh.num_faces());
  for (int i = 0; i < k.rows(); ++i) {
    k.row(i) << 10 * u(rng), 10 * u(rng), 5 * u(rng);  // [1/m], as large as the shape's 8 1/m
    damage[i] = 1.5 + u(rng);
  }
  e->set_plastic_state(k, damage);
  check_derivatives(*e, f.mesh.num_vertices(), f.x);
}

TEST_P(BendingDerivatives, GaussNewtonIsTheExactHessianAtRest) {
  // At the rest shape (flat, no plastic curvature) dE/dtheta = 0, so Gauss-Newton is exact.
  Fixture f = make_fixture(1.0, 1e-9);
  Material m;
  m.bending_model = GetParam();
  const std::unique_ptr<BendingEnergy> e =
      make_bending_energy(f.mesh, m, BendingHessian::gauss_newton);
  check_derivatives(*e, f.mesh.num_vertices(), f.x0, 1.0, 1e-5);
}

TEST(EnergyDerivatives, MorleyWithClampedFaces) {
  // Faces held by a clamp keep their slopes: the faces across take the whole hinge angle.
  Fixture f = make_fixture();
  Material m;
  m.bending_model = BendingModel::morley;
  const std::vector<int> clamped = remesh::faces_inside(f.mesh, Eigen::Vector4d(0, 0, 0.03, 0.12));
  ASSERT_GT(clamped.size(), 2u);
  const std::unique_ptr<BendingEnergy> e =
      make_bending_energy(f.mesh, m, BendingHessian::exact, clamped);
  check_derivatives(*e, f.mesh.num_vertices(), f.x);
}

INSTANTIATE_TEST_SUITE_P(Models, BendingDerivatives,
                         ::testing::Values(BendingModel::fit, BendingModel::morley),
                         [](const auto& info) {
                           return info.param == BendingModel::fit ? "fit" : "morley";
                         });

TEST(EnergyDerivatives, VertexTerms) {
  Fixture f = make_fixture();
  const Eigen::VectorXd m = lumped_masses(f.mesh.material_coords(), f.mesh.faces(), 0.08);
  EXPECT_NEAR(m.sum(), 0.08 * 0.1 * 0.12, 1e-15);
  const Eigen::VectorXd v = Eigen::VectorXd::Constant(f.x.size(), 0.3);
  StepContext ctx;
  ctx.h = 2e-3;
  ctx.x_t0 = &f.x0;
  ctx.v_t0 = &v;
  InertiaEnergy inertia(m);
  inertia.begin_step(ctx, f.x0);
  DampingEnergy damping(m, 2.0);
  damping.begin_step(ctx, f.x0);
  GravityEnergy gravity(m, Eigen::Vector3d(0, 0, -9.8));
  check_derivatives(inertia, f.mesh.num_vertices(), f.x);
  check_derivatives(damping, f.mesh.num_vertices(), f.x);
  check_derivatives(gravity, f.mesh.num_vertices(), f.x, 1e-6, 1.0);
}

TEST(EnergyDerivatives, Handles) {
  Fixture f = make_fixture();
  HandleSpec a;
  a.material_point << 0.031, 0.047;
  a.keyframes = {{0.0, Eigen::Vector3d::Zero()}, {1.0, Eigen::Vector3d(0, 0, 0.05)}};
  HandleSpec b;
  b.material_point << 0.1, 0.0;  // a corner
  b.axes << 0, 0, 1;             // drives the height only
  HandleEnergy e(f.mesh, f.x0, {a, b});
  StepContext ctx;
  ctx.time_t0 = 0.4;
  ctx.h = 0.1;
  e.begin_step(ctx, f.x0);
  EXPECT_NEAR((e.target(0, 0.5) - e.point(0, f.x0)).z(), 0.025, 1e-15);
  Eigen::VectorXd shifted = f.x0;
  for (int v = 0; v < f.mesh.num_vertices(); ++v) shifted[3 * v] += 0.01;  // horizontal move
  EXPECT_NEAR(e.error(1, shifted, 0.5), 0.0, 1e-15) << "a z-only handle ignores x";
  EXPECT_NEAR(e.error(0, shifted, 0.5), std::hypot(0.01, 0.025), 1e-12);
  check_derivatives(e, f.mesh.num_vertices(), f.x);
}

TEST(EnergyDerivatives, GroundContactAndFriction) {
  Fixture f = make_fixture();
  // Every vertex within the barrier range of the ground (z in (0, dhat)) and sliding.
  const double dhat = ContactParams{}.dhat;
  Eigen::VectorXd x0 = f.x0, x = f.x0;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.1, 0.9);
  for (int v = 0; v < f.mesh.num_vertices(); ++v) {
    x0[3 * v + 2] = dhat * u(rng);
    x[3 * v + 2] = dhat * u(rng);
    x[3 * v] += (v % 3) * 7e-4;  // some vertices stick (below eps), some slide
  }
  auto ground = std::make_shared<collision::PlaneCollider>();
  ground->friction = 0.4;
  // eps_velocity h = 1 mm, so that the finite-difference step (0.1 um) is far below the scale
  // on which the friction smoothing changes.
  ContactParams params;
  params.eps_velocity = 1.0;
  ObstacleContactEnergy e(Eigen::VectorXd::Constant(f.mesh.num_vertices(), 4e-4), {ground}, params);
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
  StepContext ctx;
  ctx.h = 1e-3;
  ctx.x_t0 = &x0;
  ctx.v_t0 = &v;
  e.begin_step(ctx, x0);
  EXPECT_EQ(e.active_friction(), f.mesh.num_vertices());
  check_derivatives(e, f.mesh.num_vertices(), x, 1e-6, 1e-4, true, 1e-8);
  // CCD: a step that would push vertices through the ground is cut before they reach it.
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(x.size());
  for (int k = 0; k < f.mesh.num_vertices(); ++k) dx[3 * k + 2] = -0.01;
  const double alpha = e.max_step(x, dx);
  EXPECT_GT(alpha, 0.0);
  for (int k = 0; k < f.mesh.num_vertices(); ++k)
    EXPECT_GT(x[3 * k + 2] + alpha * dx[3 * k + 2], 0.0);
}

// Vertices inside a spherical cavity of radius 2 cm that is shrinking, each within the barrier
// range of its wall (gaps 0.1-0.9 dhat) and sliding: the vertex terms' Hessian includes the
// wall's curvature term (b' Hess phi, positive semi-definite inside a cavity), so it matches
// finite differences (without that term the error would be about d / R ~ 2% of the Hessian);
// the exact segment CCD keeps every vertex inside.
TEST(EnergyDerivatives, ContactInsideAShrinkingCavity) {
  collision::Shape shape;
  shape.kind = collision::ShapeKind::inverted_sphere;
  shape.radius = 0.02;
  auto cavity = std::make_shared<collision::AnalyticCollider>(shape);
  collision::Keyframe k0, k1;
  k0.translation = k1.translation = Eigen::Vector3d(0.01, 0.02, 0.03);
  k1.time = 1.0;
  k1.scale = 0.5;
  cavity->motion = collision::RigidMotion({k0, k1});
  cavity->friction = 0.5;
  ContactParams params;
  params.dhat = 1e-3;
  params.eps_velocity = 1.0;
  const int nv = 8;
  StepContext ctx;
  ctx.time_t0 = 0.2;
  ctx.h = 1e-3;
  const double radius = 0.02 * cavity->motion.scale(ctx.time_t1());
  const Eigen::Vector3d centre = k0.translation;
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.1, 0.9);
  Eigen::VectorXd x0(3 * nv), x(3 * nv);
  for (int v = 0; v < nv; ++v) {
    const Eigen::Vector3d dir = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    x0.segment<3>(3 * v) = centre + (radius - params.dhat * u(rng)) * dir;
    Eigen::Vector3d slide = Eigen::Vector3d(n(rng), n(rng), n(rng)) * 3e-4;
    slide -= slide.dot(dir) * dir;
    x.segment<3>(3 * v) =
        centre + (radius - params.dhat * u(rng)) * (dir + slide / radius).normalized();
  }
  const Eigen::VectorXd vel = Eigen::VectorXd::Zero(3 * nv);
  ctx.x_t0 = &x0;
  ctx.v_t0 = &vel;
  ObstacleContactEnergy e(Eigen::VectorXd::Constant(nv, 4e-4), {cavity}, params);
  e.begin_step(ctx, x0);
  EXPECT_GT(e.active_friction(), 0);
  ASSERT_LT(e.value(x), INF);
  check_derivatives(e, nv, x, 1e-6, 1e-5, true, 1e-9);
  // CCD: every vertex pushed outwards by 5 mm stops inside the cavity.
  Eigen::VectorXd dx(3 * nv);
  for (int v = 0; v < nv; ++v)
    dx.segment<3>(3 * v) = 5e-3 * (x.segment<3>(3 * v) - centre).normalized();
  const double alpha = e.max_step(x, dx);
  EXPECT_GT(alpha, 0.0);
  for (int v = 0; v < nv; ++v)
    EXPECT_GT(cavity->distance(x.segment<3>(3 * v) + alpha * dx.segment<3>(3 * v), ctx.time_t1()),
              0.0);
}

// Following moving obstacles: how the contact gradient changes when the obstacles move on by dt
// (add_obstacle_motion_gradient) against central differences in time. A sphere moving along the
// line through a vertex leaves the normal at the vertex unchanged, so the term dropped (the
// change of n) is zero and the two agree to the differences' error; vertices off that line see
// the normal turn, and the model keeps the part along n (checked on the normal component).
TEST(EnergyDerivatives, ContactGradientFollowsAMovingSphere) {
  collision::Shape shape;
  shape.kind = collision::ShapeKind::sphere;
  shape.radius = 0.02;
  auto sphere = std::make_shared<collision::AnalyticCollider>(shape);
  const Eigen::Vector3d u = Eigen::Vector3d(1, 2, 2).normalized();
  collision::Keyframe k0, k1;
  k1.time = 1.0;
  k1.translation = 0.1 * u;  // 0.1 m/s along u
  sphere->motion = collision::RigidMotion({k0, k1});
  ContactParams params;
  params.dhat = 1e-3;
  StepContext ctx;
  ctx.time_t0 = 0.4;
  ctx.h = 1e-2;
  const double t = 0.405;
  const Eigen::Vector3d centre = sphere->motion.pose(t).translation();
  Eigen::VectorXd x(9);
  x.segment<3>(0) = centre + (0.02 + 4e-4) * u;                         // on the line
  x.segment<3>(3) = centre + (0.02 + 6e-4) * Eigen::Vector3d(0, 1, 0);  // off the line
  x.segment<3>(6) =
      centre + (0.02 + 2e-4) * Eigen::Vector3d(1, -1, 0.5).normalized();  // off the line
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(9);
  ctx.x_t0 = &x;
  ctx.v_t0 = &v;
  ObstacleContactEnergy e(Eigen::VectorXd::Constant(3, 4e-4), {sphere}, params);
  e.begin_step(ctx, x);
  EXPECT_EQ(e.obstacle_motion(), EnergyTerm::ObstacleMotion::follow);
  const auto gradient_at = [&](double time) {
    e.set_obstacle_time(time);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(9);
    e.add_gradient(x, g);
    return g;
  };
  const double delta = 1e-6;  // the sphere moves 0.1 micrometre
  const Eigen::VectorXd fd = (gradient_at(t + delta) - gradient_at(t - delta)) / (2 * delta);
  e.set_obstacle_time(t);
  Eigen::VectorXd model = Eigen::VectorXd::Zero(9);
  e.add_obstacle_motion_gradient(x, 1.0, model);
  ASSERT_GT(fd.segment<3>(0).norm(), 0.0);
  EXPECT_LT((model.segment<3>(0) - fd.segment<3>(0)).norm(), 1e-6 * fd.segment<3>(0).norm());
  for (int i = 1; i < 3; ++i) {
    const Eigen::Vector3d n = (x.segment<3>(3 * i) - centre).normalized();
    EXPECT_NEAR(n.dot(model.segment<3>(3 * i)), n.dot(fd.segment<3>(3 * i)),
                1e-6 * fd.segment<3>(3 * i).norm());
  }
}

namespace {

/// A flat sheet (the fixture's mesh at z = 2 mm, slightly rippled) with face contact against
/// one obstacle, its friction lagged at `x_start`; dhat = 1 mm, friction smoothing 1 mm.
struct FaceContactCase {
  Fixture f;
  Eigen::VectorXd x_start, x;
  std::unique_ptr<ObstacleContactEnergy> faces, vertices_only;
};

FaceContactCase face_contact_case(std::shared_ptr<collision::Collider> obstacle) {
  FaceContactCase c{make_fixture(), {}, {}, nullptr, nullptr};
  c.x_start = c.f.x0;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int v = 0; v < c.f.mesh.num_vertices(); ++v) c.x_start[3 * v + 2] += 5e-5 * u(rng);
  c.x = c.x_start;
  for (int v = 0; v < c.f.mesh.num_vertices(); ++v)
    c.x.segment<3>(3 * v) += 3e-4 * Eigen::Vector3d(u(rng), u(rng), 0.1 * u(rng));
  obstacle->friction = 0.5;
  ContactParams params;
  params.dhat = 1e-3;
  params.eps_velocity = 1.0;
  const Eigen::VectorXd areas = Eigen::VectorXd::Constant(c.f.mesh.num_vertices(), 4e-4);
  c.faces = std::make_unique<ObstacleContactEnergy>(
      areas, std::vector<std::shared_ptr<const collision::Collider>>{obstacle}, params);
  c.faces->set_faces(c.f.mesh.faces(), c.f.mesh.material_coords());
  c.vertices_only = std::make_unique<ObstacleContactEnergy>(
      areas, std::vector<std::shared_ptr<const collision::Collider>>{obstacle}, params);
  StepContext ctx;
  ctx.h = 1e-3;
  ctx.x_t0 = &c.x_start;
  c.faces->begin_step(ctx, c.x_start);
  c.vertices_only->begin_step(ctx, c.x_start);
  return c;
}

}  // namespace

// A 3 mm sphere under the middle of a face, 0.5 mm below the sheet: exact face distances.
TEST(EnergyDerivatives, FaceContactAgainstASmallSphere) {
  Fixture probe = make_fixture();
  const Eigen::Vector3i face = probe.mesh.faces().row(11);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) centroid += probe.x0.segment<3>(3 * face[k]) / 3;
  collision::Shape shape;
  shape.kind = collision::ShapeKind::sphere;
  shape.radius = 3e-3;
  auto sphere = std::make_shared<collision::AnalyticCollider>(shape);
  collision::Keyframe k;
  k.translation = centroid - Eigen::Vector3d(0, 0, 5e-4 + shape.radius);
  sphere->motion = collision::RigidMotion({k});
  FaceContactCase c = face_contact_case(sphere);
  EXPECT_GT(c.faces->active_friction(), 0);
  EXPECT_GT(c.faces->value(c.x), 0.0);
  EXPECT_LT(c.faces->value(c.x), INF);
  EXPECT_EQ(c.vertices_only->value(c.x), 0.0);  // the sphere is between the vertices
  check_derivatives(*c.faces, c.f.mesh.num_vertices(), c.x, 1e-6, 1e-5, true, 1e-9);
}

// A 90-degree gable ridge along y between two columns of vertices (7 mm or more from any of
// them) and 0.5 mm below the sheet, with the ridge's end corners under the sheet: edge-edge
// and corner-triangle pairs with exact distances.
TEST(EnergyDerivatives, FaceContactAgainstAGableRidge) {
  collision::Shape shape;
  shape.kind = collision::ShapeKind::gable;
  shape.half_width = 0.02;
  shape.height = 0.02;
  shape.length = 0.06;
  auto gable = std::make_shared<collision::AnalyticCollider>(shape);
  collision::Keyframe k;
  k.rotation = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
  k.translation = Eigen::Vector3d(0.0375, 0.06, 2e-3 - 5e-4 - shape.height);
  gable->motion = collision::RigidMotion({k});
  FaceContactCase c = face_contact_case(gable);
  EXPECT_GT(c.faces->active_friction(), 0);
  EXPECT_GT(c.faces->value(c.x), 0.0);
  EXPECT_LT(c.faces->value(c.x), INF);
  EXPECT_EQ(c.vertices_only->value(c.x), 0.0);
  check_derivatives(*c.faces, c.f.mesh.num_vertices(), c.x, 1e-6, 1e-5, true, 1e-9);
  // CCD: pushing the sheet 1 cm down stops it on the ridge, 0.5 mm (+-0.08 mm of ripple) below:
  // additive CCD closes 90% of the gap. Vertices alone (7 mm or more away) would let it through.
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(c.x.size());
  for (int v = 0; v < c.f.mesh.num_vertices(); ++v) dx[3 * v + 2] = -0.01;
  const double moved = 0.01 * c.faces->max_step(c.x, dx);
  EXPECT_GT(moved, 0.3e-3);
  EXPECT_LT(moved, 0.58e-3);
  EXPECT_LT(c.faces->value(c.x + moved / 0.01 * dx), INF);
  EXPECT_GT(0.01 * c.vertices_only->max_step(c.x, dx), 5e-3);
}

namespace {

/// Two separate right triangles (legs 1 cm in material space): A = (0, 1, 2) hovers over
/// B = (3, 4, 5), which lies in z = 0 with its corner at the origin and legs along x and y.
/// `a` holds A's three world positions; with dhat = 1 mm only the intended contacts are active.
struct TwoTriangles {
  Eigen::MatrixX2d X;
  Eigen::MatrixX3i F;
  Eigen::VectorXd x;
};

TwoTriangles two_triangles(const std::array<Eigen::Vector3d, 3>& a) {
  TwoTriangles t;
  t.X.resize(6, 2);
  t.X << 0, 0, 0.01, 0, 0, 0.01, 0.02, 0, 0.03, 0, 0.02, 0.01;
  t.F.resize(2, 3);
  t.F << 0, 1, 2, 3, 4, 5;
  t.x.resize(18);
  for (int k = 0; k < 3; ++k) t.x.segment<3>(3 * k) = a[k];
  t.x.segment<3>(9) << 0, 0, 0;
  t.x.segment<3>(12) << 0.01, 0, 0;
  t.x.segment<3>(15) << 0, 0.01, 0;
  return t;
}

SelfContactParams self_params() {
  SelfContactParams p;
  p.dhat = 1e-3;
  p.stiffness = 1.0;
  p.eps_velocity = 1.0;  // eps = 1 mm at h = 1 ms: the FD step is far below the smoothing scale
  return p;
}

collision::PairPoints pair_points(const Eigen::VectorXd& x, std::array<int, 4> v) {
  collision::PairPoints p;
  for (int k = 0; k < 4; ++k) p[k] = x.segment<3>(3 * v[k]);
  return p;
}

/// The barrier derivatives of a two-triangle configuration, with the exact Hessian. The log
/// barrier's third derivative near d = 0.4 mm asks for a small step: 1e-9 m.
void check_self_contact(const TwoTriangles& t) {
  SelfContactEnergy e(t.X, t.F, self_params());
  ASSERT_GT(e.value(t.x), 0.0);
  ASSERT_LT(e.value(t.x), INF);
  check_derivatives(e, 6, t.x, 1e-6, 1e-5, true, 1e-9);
  EXPECT_GT(e.active_pairs(), 0);
}

}  // namespace

TEST(EnergyDerivatives, SelfContactPointTriangleTypes) {
  using collision::DistanceType;
  const double dhat = self_params().dhat;
  // Vertex 0 of A above B's face, beside B's edge x = 0, and beyond B's corner.
  const std::array<std::array<Eigen::Vector3d, 3>, 3> configs = {{
      {{Eigen::Vector3d(0.002, 0.002, 5e-4), Eigen::Vector3d(0.004, 0.003, 0.008),
        Eigen::Vector3d(0.001, 0.004, 0.009)}},
      {{Eigen::Vector3d(-3e-4, 0.004, 4e-4), Eigen::Vector3d(-0.002, 0.005, 0.008),
        Eigen::Vector3d(-0.004, 0.003, 0.008)}},
      {{Eigen::Vector3d(-3e-4, -3e-4, 3e-4), Eigen::Vector3d(-0.003, -0.002, 0.008),
        Eigen::Vector3d(-0.001, -0.004, 0.008)}},
  }};
  const DistanceType expected[3] = {DistanceType::point_triangle, DistanceType::point_edge,
                                    DistanceType::point_point};
  for (int c = 0; c < 3; ++c) {
    const TwoTriangles t = two_triangles(configs[c]);
    const collision::PairPoints p = pair_points(t.x, {{0, 3, 4, 5}});
    EXPECT_EQ(collision::point_triangle_stencil(p).type, expected[c]);
    EXPECT_LT(collision::point_triangle_distance_squared(p), dhat * dhat);
    check_self_contact(t);
  }
}

TEST(EnergyDerivatives, SelfContactEdgeEdgeCrossingAndNearlyParallel) {
  const double dhat = self_params().dhat;
  // A's edge (0, 1) crosses above B's edge (3, 4) along x: at a right angle, then nearly
  // parallel (sin^2 of the angle 1e-4 of the rest-length product: the mollifier is at 0.1).
  const std::array<std::array<Eigen::Vector3d, 3>, 2> configs = {{
      {{Eigen::Vector3d(0.005, -0.003, 5e-4), Eigen::Vector3d(0.005, 0.003, 6e-4),
        Eigen::Vector3d(0.005, 0, 0.008)}},
      {{Eigen::Vector3d(0.002, -5e-5, 4e-4), Eigen::Vector3d(0.008, 5e-5, 4e-4),
        Eigen::Vector3d(0.005, -0.004, 0.006)}},
  }};
  for (int c = 0; c < 2; ++c) {
    const TwoTriangles t = two_triangles(configs[c]);
    const collision::PairPoints p = pair_points(t.x, {{0, 1, 3, 4}});
    EXPECT_EQ(collision::edge_edge_stencil(p).type, collision::DistanceType::edge_edge)
        << "config " << c;
    EXPECT_LT(collision::edge_edge_distance_squared(p), dhat * dhat);
    const double m = collision::edge_edge_mollifier(
        p, collision::edge_edge_mollifier_threshold(0.01, 0.01), nullptr, nullptr);
    if (c == 0) {
      EXPECT_EQ(m, 1.0);
    } else {
      EXPECT_GT(m, 0.05);
      EXPECT_LT(m, 0.5);
    }
    check_self_contact(t);
  }
}

TEST(EnergyDerivatives, SelfContactFrictionAndCcd) {
  const TwoTriangles t =
      two_triangles({{Eigen::Vector3d(0.002, 0.002, 5e-4), Eigen::Vector3d(0.004, 0.003, 0.008),
                      Eigen::Vector3d(0.001, 0.004, 0.009)}});
  SelfContactEnergy e(t.X, t.F, self_params());
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(18);
  StepContext ctx;
  ctx.h = 1e-3;
  ctx.x_t0 = &t.x;
  ctx.v_t0 = &v;
  e.begin_step(ctx, t.x);
  EXPECT_EQ(e.active_friction(), 1) << "vertex 0 over B's face";
  // A slides over B: vertex 0 by 0.3 mm (below eps = 1 mm: static-like), the rest by 2 mm.
  Eigen::VectorXd x = t.x;
  x.segment<3>(0) += Eigen::Vector3d(3e-4, 1e-4, 0);
  x.segment<3>(3) += Eigen::Vector3d(2e-3, 0, 0);
  check_derivatives(e, 6, x, 1e-6, 1e-5, true, 1e-9);
  // Friction resists the slide: the gradient on vertex 0 points along the slip.
  Eigen::VectorXd g = Eigen::VectorXd::Zero(18);
  e.add_gradient(x, g);
  EXPECT_GT(g[0], 0.0);
  // CCD: moving A down by 2 mm would put vertex 0 through B at a quarter of the step.
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(18);
  for (int k = 0; k < 3; ++k) dx[3 * k + 2] = -2e-3;
  const double alpha = e.max_step(t.x, dx);
  EXPECT_GT(alpha, 0.2);
  EXPECT_LE(alpha, 0.25 * 0.9 + 1e-12) << "at most 90% of the 0.5 mm gap is closed";
  EXPECT_LT(e.value(t.x + alpha * dx), INF);
}

// Friction's static zone in a step the solver split (ContactParams::static_whole_step): vertices
// slide 0.5 mm in a step of 1/8 ms, split from a whole step of 1 ms, with eps_velocity 1 m/s. The
// zone is the slip eps_velocity h: 0.125 mm for the split step, so the slide is past it and the
// friction force is the whole mu lambda; 1 mm for the whole step, in whose smoothing
// f1(y) = 2 y / eps - y^2 / eps^2 a slide of half the zone gets 0.75 of it. Sheet-sheet (vertex 0
// of A over B's face) and against the ground (every vertex within the barrier range); the slide
// is along x, where the barriers have no component, so the x-components are friction alone.
// The derivatives match finite differences with the whole step's zone too.
TEST(EnergyDerivatives, FrictionKeepsTheWholeStepsStaticZoneInASplitStep) {
  const Eigen::VectorXd v0 = Eigen::VectorXd::Zero(18);
  StepContext ctx;
  ctx.h = 1e-3 / 8;
  ctx.h_whole = 1e-3;
  ctx.v_t0 = &v0;
  const TwoTriangles t =
      two_triangles({{Eigen::Vector3d(0.002, 0.002, 5e-4), Eigen::Vector3d(0.004, 0.003, 0.008),
                      Eigen::Vector3d(0.001, 0.004, 0.009)}});
  Eigen::VectorXd x = t.x;
  x[0] += 5e-4;
  ctx.x_t0 = &t.x;
  auto self_friction = [&](bool whole) {
    SelfContactParams p = self_params();
    p.static_whole_step = whole;
    SelfContactEnergy e(t.X, t.F, p);
    e.begin_step(ctx, t.x);
    EXPECT_EQ(e.active_friction(), 1);
    if (whole) check_derivatives(e, 6, x, 1e-6, 1e-5, true, 1e-9);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(18);
    e.add_gradient(x, g);
    return g[0];
  };
  const double split = self_friction(false);
  EXPECT_GT(split, 0.0);
  EXPECT_NEAR(self_friction(true) / split, 0.75, 1e-12);

  Fixture f = make_fixture();
  const int nv = f.mesh.num_vertices();
  const double dhat = ContactParams{}.dhat;
  Eigen::VectorXd y0 = f.x0, y = f.x0;
  for (int k = 0; k < nv; ++k) {
    y0[3 * k + 2] = y[3 * k + 2] = 0.5 * dhat;
    y[3 * k] += 5e-4;
  }
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(y.size());
  ctx.x_t0 = &y0;
  ctx.v_t0 = &v;
  auto ground_friction = [&](bool whole) {
    auto ground = std::make_shared<collision::PlaneCollider>();
    ground->friction = 0.4;
    ContactParams p;
    p.eps_velocity = 1.0;
    p.static_whole_step = whole;
    ObstacleContactEnergy e(Eigen::VectorXd::Constant(nv, 4e-4), {ground}, p);
    e.begin_step(ctx, y0);
    EXPECT_EQ(e.active_friction(), nv);
    if (whole) check_derivatives(e, nv, y, 1e-6, 1e-4, true, 1e-8);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(y.size());
    e.add_gradient(y, g);
    double sum = 0;
    for (int k = 0; k < nv; ++k) sum += g[3 * k];
    return sum;
  };
  const double ground_split = ground_friction(false);
  EXPECT_GT(ground_split, 0.0);
  EXPECT_NEAR(ground_friction(true) / ground_split, 0.75, 1e-12);
  // Not split (h_whole unset): the zone is the step's, with the flag or without.
  ctx.h_whole = 0;
  EXPECT_NEAR(ground_friction(true) / ground_split, 1.0, 1e-12);
}

TEST(SelfContactStiffness, DoublesOnlyWhileAPairBelowTheFloorKeepsClosing) {
  // Vertex 0 of A over B's face at a gap g (the only pair nearer than 1 mm). The floor is 1e-9 of
  // the bounding-box diagonal at the step start.
  auto at_gap = [](double g) {
    return two_triangles({{Eigen::Vector3d(0.002, 0.002, g), Eigen::Vector3d(0.004, 0.003, 0.008),
                           Eigen::Vector3d(0.001, 0.004, 0.009)}})
        .x;
  };
  const TwoTriangles t =
      two_triangles({{Eigen::Vector3d(0.002, 0.002, 0), Eigen::Vector3d(0.004, 0.003, 0.008),
                      Eigen::Vector3d(0.001, 0.004, 0.009)}});
  SelfContactParams params = self_params();
  params.friction = 0;
  SelfContactEnergy e(t.X, t.F, params);
  const Eigen::VectorXd x0 = at_gap(1e-12), v = Eigen::VectorXd::Zero(18);
  Eigen::MatrixX3d p(6, 3);
  for (int k = 0; k < 6; ++k) p.row(k) = x0.segment<3>(3 * k).transpose();
  const double floor =
      SelfContactEnergy::floor_fraction * (p.colwise().maxCoeff() - p.colwise().minCoeff()).norm();
  ASSERT_GT(floor, 1e-11);  // about 1.6e-11 m: the gaps below are 1e-12 m and more apart
  StepContext ctx;
  ctx.x_t0 = &x0;
  ctx.v_t0 = &v;
  // Above the floor, a closing pair changes nothing.
  e.begin_step(ctx, at_gap(1e-6));
  for (double g : {1e-7, 1e-8, 1e-9, 1e-10}) EXPECT_FALSE(e.adapt(at_gap(g))) << g;
  EXPECT_EQ(e.stiffness(), params.stiffness);
  // Below the floor at the step start and closing: doubles, which doubles the barrier energy.
  e.begin_step(ctx, x0);
  const Eigen::VectorXd x1 = at_gap(0.5e-12);
  const double before = e.value(x1);
  EXPECT_TRUE(e.adapt(x1));
  EXPECT_EQ(e.stiffness(), 2 * params.stiffness);
  EXPECT_NEAR(e.value(x1), 2 * before, 1e-12 * before);
  EXPECT_FALSE(e.adapt(at_gap(0.8e-12))) << "opening";
  EXPECT_TRUE(e.adapt(at_gap(0.6e-12))) << "closing again, below the floor both times";
  EXPECT_FALSE(e.adapt(at_gap(1e-9))) << "above the floor";
  EXPECT_FALSE(e.adapt(at_gap(0.1e-12))) << "the iterate before was above the floor";
  EXPECT_EQ(e.stiffness(), 4 * params.stiffness);
  EXPECT_EQ(e.statistics().stiffness_doublings, 2);
  // Carried to the next step through the state, and never beyond max_stiffness_factor.
  SheetState state;
  e.end_step(state);
  EXPECT_EQ(state.self_contact_stiffness, 4 * params.stiffness);
  SelfContactEnergy next(t.X, t.F, params);
  ctx.self_contact_stiffness = state.self_contact_stiffness;
  next.begin_step(ctx, at_gap(1e-6));
  EXPECT_EQ(next.stiffness(), 4 * params.stiffness);
  next.begin_step(ctx, x0);
  double g = 1e-12;
  for (int k = 0; k < 20; ++k) next.adapt(at_gap(g *= 0.7));
  EXPECT_EQ(next.stiffness(), SelfContactEnergy::max_stiffness_factor * params.stiffness);
  EXPECT_EQ(next.statistics().max_stiffness,
            SelfContactEnergy::max_stiffness_factor * params.stiffness);
}

/// Two layers of an n x n grid of 2 mm cells, 0.7 mm apart (dhat 1 mm): every vertex is near
/// the other layer, and the mesh neighbours within a layer are candidates that are millimetres
/// apart.
struct TwoLayers {
  static constexpr int n = 9;
  static constexpr int per_layer = n * n;
  Eigen::MatrixX2d X;
  Eigen::MatrixX3i F;
  Eigen::VectorXd x0;
};

TwoLayers two_layers() {
  const int n = TwoLayers::n, per_layer = TwoLayers::per_layer;
  const double cell = 2e-3;
  TwoLayers t;
  t.X.resize(2 * per_layer, 2);
  t.x0.resize(6 * per_layer);
  std::vector<Eigen::Vector3i> faces;
  for (int layer = 0; layer < 2; ++layer)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int v = layer * per_layer + j * n + i;
        t.X.row(v) << i * cell + layer * 0.05, j * cell;  // material: the layers side by side
        t.x0.segment<3>(3 * v) << i * cell, j * cell, layer * 7e-4;
        if (i + 1 < n && j + 1 < n) {
          faces.emplace_back(v, v + 1, v + n + 1);
          faces.emplace_back(v, v + n + 1, v + n);
        }
      }
  t.F.resize(static_cast<int>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) t.F.row(static_cast<int>(f)) = faces[f].transpose();
  return t;
}

TEST(EnergyDerivatives, SelfContactBoundsKeptBetweenEvaluationsRejectOnlyFarPairs) {
  // One energy evaluated along a sequence of small motions of two layers keeps, per candidate,
  // a bound from its earlier distances; the energy, gradient and Hessian must be those of a
  // fresh energy (no bounds kept) at each position.
  const TwoLayers t = two_layers();
  const int n = TwoLayers::n, per_layer = TwoLayers::per_layer;
  const Eigen::MatrixX2d& X = t.X;
  const Eigen::MatrixX3i& F = t.F;
  const Eigen::VectorXd& x0 = t.x0;
  SelfContactParams params = self_params();
  params.friction = 0;
  SelfContactEnergy kept(X, F, params);
  std::mt19937 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXd x = x0;
  int active = 0;
  for (int k = 0; k < 12; ++k) {
    // Steps of up to about 0.1 mm per vertex: within the candidates' margin, so the set stays.
    for (int i = 0; i < x.size(); ++i) x[i] = x0[i] + 3e-5 * k * normal(rng) / 4;
    SelfContactEnergy fresh(X, F, params);
    const double e_kept = kept.value(x), e_fresh = fresh.value(x);
    ASSERT_GT(e_fresh, 0.0);
    ASSERT_NEAR(e_kept, e_fresh, 1e-12 * e_fresh) << "position " << k;
    Eigen::VectorXd g_kept = Eigen::VectorXd::Zero(x.size()), g_fresh = g_kept;
    kept.update_pattern(x);
    fresh.update_pattern(x);
    SparsityBuilder pattern_builder(2 * per_layer);
    kept.add_dynamic_pattern(pattern_builder);
    fresh.add_dynamic_pattern(pattern_builder);
    const BlockPattern pattern = pattern_builder.finish();
    BlockSymmetricMatrix H_kept(pattern), H_fresh(pattern);
    kept.add_derivatives(x, g_kept, &H_kept, HessianProjection::none);
    fresh.add_derivatives(x, g_fresh, &H_fresh, HessianProjection::none);
    ASSERT_LT((g_kept - g_fresh).norm(), 1e-12 * g_fresh.norm()) << "position " << k;
    double h_norm = 0, h_diff = 0;
    for (size_t i = 0; i < H_fresh.values().size(); ++i) {
      h_norm += H_fresh.values()[i] * H_fresh.values()[i];
      h_diff += std::pow(H_kept.values()[i] - H_fresh.values()[i], 2);
    }
    ASSERT_LT(std::sqrt(h_diff), 1e-12 * std::sqrt(h_norm)) << "position " << k;
    active = kept.active_pairs();
  }
  EXPECT_GT(active, 2 * (n - 1) * (n - 1)) << "pairs across the layers are active";
}

TEST(EnergyDerivatives, SelfContactResultsAtXDoNotDependOnWhatWasEvaluatedBefore) {
  // The candidate pairs are a cache that value, add_derivatives and max_step find again when it
  // does not cover x (self_contact_energy.hpp). What they return must not depend on it: every
  // set that covers x holds the same pairs within dhat, visited in the broad phase's sorted
  // order. A term first evaluated elsewhere (at far positions, which put the set's base there,
  // and along a long step, which sweeps it along the step) must give, at x, a fresh term's
  // energy, gradient, Hessians (exact and projected) and step bound to the bit. (The Hessian's
  // pattern is the term's state: it changes only when its pairs no longer fit, so that the
  // symbolic analysis is redone rarely; the matrices are compared entry by entry.)
  const TwoLayers t = two_layers();
  SelfContactParams params = self_params();
  params.friction = 0;
  std::mt19937 rng(11);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto jitter = [&](double scale) {
    Eigen::VectorXd y = t.x0;
    for (int i = 0; i < y.size(); ++i) y[i] += scale * normal(rng);
    return y;
  };
  const Eigen::VectorXd x = jitter(2e-5);
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(x.size());
  // The upper layer closes on the lower one.
  for (int v = TwoLayers::per_layer; v < 2 * TwoLayers::per_layer; ++v) dx[3 * v + 2] = -6e-4;
  struct Results {
    double value, step;
    Eigen::VectorXd gradient;
    Eigen::MatrixXd exact, projected;  // dense: the pattern (the matrix's structure) may differ
    int active;
  };
  const auto evaluate = [&](SelfContactEnergy& e) {
    Results r;
    r.value = e.value(x);
    e.update_pattern(x);
    SparsityBuilder builder(2 * TwoLayers::per_layer);
    e.add_dynamic_pattern(builder);
    const BlockPattern pattern = builder.finish();
    for (const HessianProjection projection : {HessianProjection::none, HessianProjection::psd}) {
      BlockSymmetricMatrix H(pattern);
      r.gradient = Eigen::VectorXd::Zero(x.size());
      e.add_derivatives(x, r.gradient, &H, projection);
      (projection == HessianProjection::none ? r.exact : r.projected) = dense(H);
    }
    r.active = e.active_pairs();
    r.step = e.max_step(x, dx);
    return r;
  };
  SelfContactEnergy fresh(t.X, t.F, params);
  const Results want = evaluate(fresh);
  ASSERT_GT(want.active, 2 * (TwoLayers::n - 1) * (TwoLayers::n - 1))
      << "pairs across the layers are active";
  ASSERT_GT(want.step, 0.0);
  ASSERT_LT(want.step, 1.0) << "the step closing the layers is cut";
  ASSERT_FALSE(want.exact == want.projected) << "projecting changes some pair's Hessian";

  const Eigen::VectorXd far = jitter(5e-4);  // moves the vertices by more than the set's margin
  Eigen::VectorXd long_step = Eigen::VectorXd::Zero(x.size());
  for (int v = 0; v < TwoLayers::per_layer; ++v) long_step.segment<3>(3 * v) << 3e-3, -2e-3, 1e-4;
  const std::vector<std::function<void(SelfContactEnergy&)>> histories = {
      [&](SelfContactEnergy& e) { e.value(far); },
      [&](SelfContactEnergy& e) { e.max_step(x, long_step); },
      [&](SelfContactEnergy& e) { e.max_step(far, x - far); },
      [&](SelfContactEnergy& e) {
        Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
        e.value(far);
        e.add_gradient(x + 0.5 * long_step, g);
        e.value(x + 1e-4 * dx);
      },
  };
  for (std::size_t k = 0; k < histories.size(); ++k) {
    SelfContactEnergy e(t.X, t.F, params);
    histories[k](e);
    const Results got = evaluate(e);
    EXPECT_EQ(got.value, want.value) << "history " << k;
    EXPECT_TRUE(got.gradient == want.gradient) << "history " << k;
    EXPECT_TRUE(got.exact == want.exact) << "history " << k;
    EXPECT_TRUE(got.projected == want.projected) << "history " << k;
    EXPECT_EQ(got.active, want.active) << "history " << k;
    EXPECT_EQ(got.step, want.step) << "history " << k;
  }
}
