// Cylinder wrap (VALIDATION.md section 3): a sheet wrapped isometrically on a cylinder of radius
// R stores D A / (2 R^2), whatever the triangulation and its orientation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <tuple>

#include "remesh/sheet_generator.hpp"
#include "simulation/energies/bending_energy.hpp"

using namespace papersim;
using namespace papersim::simulation;

namespace {

/// Wrap material point p on a cylinder of radius R whose axis makes angle `phi` with material x
/// (bending direction d = (cos phi', sin phi') perpendicular to the axis).
Eigen::VectorXd wrap(const Eigen::MatrixX2d& X, double R, double phi) {
  const Eigen::Vector2d axis(std::cos(phi), std::sin(phi));
  const Eigen::Vector2d d(-axis.y(), axis.x());
  Eigen::VectorXd x(3 * X.rows());
  for (int v = 0; v < X.rows(); ++v) {
    const Eigen::Vector2d p = X.row(v);
    const double s = p.dot(d), a = p.dot(axis);
    const Eigen::Vector2d in_plane = a * axis + R * std::sin(s / R) * d;
    x.segment<3>(3 * v) << in_plane.x(), in_plane.y(), R * (1 - std::cos(s / R));
  }
  return x;
}

double relative_error(const remesh::RectangleOptions& o, double R, double phi,
                      BendingModel model = BendingModel::fit) {
  const remesh::SheetMesh mesh = remesh::make_rectangle(o);
  Material m;
  m.bending_model = model;
  const std::unique_ptr<BendingEnergy> e = make_bending_energy(mesh, m);
  const double expected = m.bending_stiffness * o.width * o.height / (2 * R * R);
  return e->value(wrap(mesh.material_coords(), R, phi)) / expected - 1;
}

}  // namespace

class CylinderWrap
    : public ::testing::TestWithParam<std::tuple<BendingModel, remesh::Triangulation>> {};

TEST_P(CylinderWrap, EnergyMatchesThePlateForEveryOrientation) {
  remesh::RectangleOptions o;
  o.width = 0.1;
  o.height = 0.15;
  o.nx = 21;  // 5 mm edges
  o.ny = 31;
  o.triangulation = std::get<1>(GetParam());
  o.seed = 11;
  for (double jitter : {0.0, 0.25}) {
    o.jitter = jitter;
    for (double phi_deg : {0.0, 17.0, 30.0, 45.0, 90.0}) {
      const double err = relative_error(o, 0.05, phi_deg * M_PI / 180, std::get<0>(GetParam()));
      EXPECT_LT(std::abs(err), 0.03) << "jitter " << jitter << " angle " << phi_deg;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Triangulations, CylinderWrap,
                         ::testing::Combine(::testing::Values(BendingModel::fit,
                                                              BendingModel::morley),
                                            ::testing::Values(remesh::Triangulation::regular,
                                                              remesh::Triangulation::alternating,
                                                              remesh::Triangulation::random)));

TEST(CylinderWrapConvergence, ErrorShrinksWithTheMesh) {
  // Fit model: the error comes from the chord approximation (theta vs curvature) and shrinks as
  // h^2 / R^2. Morley model: the boundary faces add an error of first order in h / size (their
  // slopes are tied to the neighbours' curvature by a penalty, not given exactly).
  remesh::RectangleOptions coarse, fine;
  coarse.width = fine.width = 0.1;
  coarse.height = fine.height = 0.15;
  coarse.nx = 11;
  coarse.ny = 16;
  fine.nx = 41;
  fine.ny = 61;
  coarse.jitter = fine.jitter = 0.2;
  const double e_coarse = std::abs(relative_error(coarse, 0.03, 0.3));
  const double e_fine = std::abs(relative_error(fine, 0.03, 0.3));
  EXPECT_LT(e_fine, e_coarse);
  EXPECT_LT(e_fine, 0.005);
  const double m_coarse = std::abs(relative_error(coarse, 0.03, 0.3, BendingModel::morley));
  const double m_fine = std::abs(relative_error(fine, 0.03, 0.3, BendingModel::morley));
  std::printf("cylinder wrap, Morley: |error| %.4f at 10 mm, %.4f at 2.5 mm\n", m_coarse, m_fine);
  EXPECT_LT(m_fine, 0.4 * m_coarse) << "at least first order (a factor 4 in h)";
  EXPECT_LT(m_fine, 0.01);
}
