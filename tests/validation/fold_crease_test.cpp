// measure_fold_crease: the residual rest angle across a fold line, piece by piece, on grids whose
// plastic curvature is a known band across the line.
#include "validation/fold_crease.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/validation/test_meshes.hpp"

namespace papersim::validation {
namespace {

using test::Grid;
using test::make_grid;
using test::PI;

constexpr double W = 0.21, H = 0.297;  // A4 [m]

/// Plastic curvature theta * g(s) d d^T per face, g a unit-integral Gaussian of width sigma in the
/// distance s of the face's centroid from the line, zero where `keep` says no.
template <class Keep>
Eigen::MatrixX3d band(const Grid& g, const FoldLine& line, double theta, double sigma, Keep keep) {
  Eigen::MatrixX3d K = Eigen::MatrixX3d::Zero(g.faces.rows(), 3);
  const Eigen::Vector2d t(-line.d.y(), line.d.x());
  for (Eigen::Index f = 0; f < g.faces.rows(); ++f) {
    const Eigen::Vector2d c = (g.material.row(g.faces(f, 0)) + g.material.row(g.faces(f, 1)) +
                               g.material.row(g.faces(f, 2)))
                                  .transpose() /
                              3;
    const double s = (c - line.centre).dot(line.d), along = (c - line.centre).dot(t);
    if (!keep(along)) continue;
    const double k = theta * std::exp(-0.5 * s * s / (sigma * sigma)) / (sigma * std::sqrt(2 * PI));
    K.row(f) << k * line.d.x() * line.d.x(), k * line.d.y() * line.d.y(),
        k * line.d.x() * line.d.y();
  }
  return K;
}

TEST(FoldCrease, LineIsClippedToTheRectangle) {
  const Eigen::Vector2d centre(0.5 * W, 0.5 * H);
  const FoldLine across = fold_line_in_rectangle(centre, Eigen::Vector2d(0, 2), W, H);
  EXPECT_NEAR(across.chord, W, 1e-12);
  EXPECT_NEAR(across.d.norm(), 1.0, 1e-12);
  // Diagonal through the centre: the line x - y = const leaves through the short sides first.
  const FoldLine diagonal = fold_line_in_rectangle(centre, Eigen::Vector2d(1, 1), W, H);
  EXPECT_NEAR(diagonal.chord, W * std::sqrt(2.0), 1e-12);
  // Off-centre: both ends on the boundary, the stored centre at the chord's midpoint.
  const FoldLine off =
      fold_line_in_rectangle(Eigen::Vector2d(0.05, 0.1), Eigen::Vector2d(1, 2), W, H);
  const Eigen::Vector2d t(-off.d.y(), off.d.x());
  for (int side : {-1, 1}) {
    const Eigen::Vector2d end = off.centre + side * 0.5 * off.chord * t;
    const double to_boundary = std::min({end.x(), W - end.x(), end.y(), H - end.y()});
    EXPECT_NEAR(to_boundary, 0.0, 1e-12) << "end " << side;
    EXPECT_GE(std::min(end.x(), end.y()), -1e-12);
  }
}

// A crease of 90 degrees along the whole line, across the grid's rows: every 10 mm piece holds
// exactly 10 columns of 1 mm cells, and the Gaussian (sigma 3 mm) is integrated by the centroid
// rule on 1 mm faces to well under 1%.
TEST(FoldCrease, GaussianBandAlongAGridRowGivesItsAngleEverywhere) {
  const Grid g = make_grid(211, 298, W, H);
  const FoldLine line =
      fold_line_in_rectangle(Eigen::Vector2d(0.5 * W, 0.1485), Eigen::Vector2d(0, 1), W, H);
  const double theta = PI / 2;
  const Eigen::MatrixX3d K = band(g, line, theta, 0.003, [](double) { return true; });
  const FoldCrease c = measure_fold_crease(g.material, g.faces, K, line);
  EXPECT_EQ(c.lines, 1);
  EXPECT_NEAR(c.longest, W, 1e-9);
  EXPECT_NEAR(c.creased, W, 1e-9);
  EXPECT_NEAR(c.angle, theta, 0.01 * theta);
  EXPECT_NEAR(c.mean_all, theta, 0.01 * theta);
}

// The same crease across a slanted line, interrupted over 4 cm in the middle: two lines. The
// creased length and mean angle are within a piece of the truth: the pieces at the gap's edges
// hold part of the crease (2 of about 22 creased pieces, each up to 2/3 short: at most 6% off
// the mean), and faces are binned by their centroid, so a piece's share of the 1 mm cells along
// a slanted line varies by about a cell per 10 mm; 10% bounds both.
TEST(FoldCrease, InterruptedCreaseIsTwoLines) {
  const Grid g = make_grid(211, 298, W, H);
  const FoldLine line =
      fold_line_in_rectangle(Eigen::Vector2d(0.5 * W, 0.5 * H), Eigen::Vector2d(0.34, 0.94), W, H);
  const double theta = PI / 2;
  const Eigen::MatrixX3d K =
      band(g, line, theta, 0.003, [](double along) { return std::abs(along) > 0.02; });
  const FoldCrease c = measure_fold_crease(g.material, g.faces, K, line);
  EXPECT_EQ(c.lines, 2);
  EXPECT_LT(c.longest, 0.5 * line.chord);
  EXPECT_NEAR(c.creased, line.chord - 0.04, 0.025);
  EXPECT_NEAR(c.angle, theta, 0.1 * theta);
}

// The crease actually lies 3 cm beside the line the scenario aims at and turned by 12 degrees:
// the fit finds it (the band is symmetric about the true line, so its weighted centroid and
// axis are the line's up to the binning of 1 mm faces), and measured along the fitted line the
// crease runs the whole chord, while along the nominal line most pieces miss it. A second,
// weaker plastic patch 4 cm away inside the search band pulls the fit by well under a degree.
TEST(FoldCrease, FitFindsTheCreaseBesideTheNominalLine) {
  const Grid g = make_grid(211, 298, W, H);
  const Eigen::Vector2d centre(0.5 * W, 0.5 * H);
  const FoldLine nominal = fold_line_in_rectangle(centre, Eigen::Vector2d(0, 1), W, H);
  const double turn = 12 * PI / 180;
  const FoldLine truth = fold_line_in_rectangle(
      centre + Eigen::Vector2d(0, 0.03), Eigen::Vector2d(-std::sin(turn), std::cos(turn)), W, H);
  Eigen::MatrixX3d K = band(g, truth, PI / 2, 0.003, [](double) { return true; });
  for (Eigen::Index f = 0; f < g.faces.rows(); ++f) {  // the weak patch: 40 1/m over 1 x 1 cm
    const Eigen::Vector2d c = (g.material.row(g.faces(f, 0)) + g.material.row(g.faces(f, 1)) +
                               g.material.row(g.faces(f, 2)))
                                  .transpose() /
                              3;
    if ((c - Eigen::Vector2d(0.05, 0.1485 - 0.04)).cwiseAbs().maxCoeff() < 0.005)
      K.row(f) << 0, 40, 0;
  }
  const FoldLine fit = fit_crease_line(g.material, g.faces, K, nominal, W, H);
  EXPECT_GT(fit.d.dot(truth.d), std::cos(0.5 * PI / 180));
  EXPECT_LT(std::abs((fit.centre - truth.centre).dot(truth.d)), 1e-3);
  EXPECT_NEAR(fit.chord, truth.chord, 2e-3);
  const FoldCrease along_fit = measure_fold_crease(g.material, g.faces, K, fit);
  EXPECT_EQ(along_fit.lines, 1);
  EXPECT_NEAR(along_fit.longest, fit.chord, 1e-9);
  EXPECT_NEAR(along_fit.angle, PI / 2, 0.05 * PI / 2);
  const FoldCrease along_nominal = measure_fold_crease(g.material, g.faces, K, nominal);
  EXPECT_LT(along_nominal.longest, 0.5 * nominal.chord);
  // Nothing plastic near the line: the nominal line comes back.
  const FoldLine none = fit_crease_line(g.material, g.faces,
                                        Eigen::MatrixX3d::Zero(g.faces.rows(), 3), nominal, W, H);
  EXPECT_EQ(none.centre, nominal.centre);
  EXPECT_EQ(none.d, nominal.d);
}

// Below the threshold (20 against 30 degrees) nothing is creased; above it with the opposite
// sign (a valley instead of a mountain) the crease is found.
TEST(FoldCrease, ThresholdAndSign) {
  const Grid g = make_grid(106, 149, W, H);
  const FoldLine line =
      fold_line_in_rectangle(Eigen::Vector2d(0.5 * W, 0.5 * H), Eigen::Vector2d(0, 1), W, H);
  const auto all = [](double) { return true; };
  const FoldCrease weak =
      measure_fold_crease(g.material, g.faces, band(g, line, 20 * PI / 180, 0.004, all), line);
  EXPECT_EQ(weak.lines, 0);
  EXPECT_EQ(weak.creased, 0.0);
  EXPECT_NEAR(weak.mean_all, 20 * PI / 180, 0.02 * 20 * PI / 180);
  const FoldCrease valley =
      measure_fold_crease(g.material, g.faces, band(g, line, -PI / 3, 0.004, all), line);
  EXPECT_EQ(valley.lines, 1);
  EXPECT_NEAR(valley.angle, PI / 3, 0.02 * PI / 3);
}

}  // namespace
}  // namespace papersim::validation
