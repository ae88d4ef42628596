#include "collision/barrier.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace pc = papersim::collision;

namespace {

/// Central difference of f at x with step h.
template <class F>
double central_difference(F f, double x, double h) {
  return (f(x + h) - f(x - h)) / (2.0 * h);
}

}  // namespace

TEST(Barrier, ValueAndSupport) {
  const double dhat = 1e-3;
  EXPECT_EQ(pc::barrier(dhat, dhat), 0.0);
  EXPECT_EQ(pc::barrier(2 * dhat, dhat), 0.0);
  EXPECT_TRUE(std::isinf(pc::barrier(0.0, dhat)));
  EXPECT_TRUE(std::isinf(pc::barrier(-1e-4, dhat)));
  const double d = 0.25e-3;
  EXPECT_NEAR(pc::barrier(d, dhat), -(d - dhat) * (d - dhat) * std::log(d / dhat), 1e-20);
  EXPECT_GT(pc::barrier(d, dhat), 0.0);
  EXPECT_EQ(pc::barrier_first_derivative(2 * dhat, dhat), 0.0);
  EXPECT_EQ(pc::barrier_second_derivative(2 * dhat, dhat), 0.0);
}

TEST(Barrier, DerivativesMatchFiniteDifferences) {
  const double dhat = 1e-3;
  for (double d : {1e-6, 1e-5, 1e-4, 3e-4, 5e-4, 9e-4, 0.999e-3}) {
    const double h = 1e-4 * std::min(d, dhat - d);
    const double fd1 = central_difference([&](double x) { return pc::barrier(x, dhat); }, d, h);
    const double fd2 =
        central_difference([&](double x) { return pc::barrier_first_derivative(x, dhat); }, d, h);
    const double a1 = pc::barrier_first_derivative(d, dhat);
    const double a2 = pc::barrier_second_derivative(d, dhat);
    EXPECT_NEAR(a1, fd1, 1e-6 * std::abs(a1) + 1e-12) << "d = " << d;
    EXPECT_NEAR(a2, fd2, 1e-6 * std::abs(a2) + 1e-9) << "d = " << d;
    EXPECT_LT(a1, 0.0);
    EXPECT_GT(a2, 0.0);
  }
}

TEST(Barrier, SmoothAtDhat) {
  const double dhat = 2e-3;
  const double d = dhat * (1.0 - 1e-6);
  EXPECT_NEAR(pc::barrier_first_derivative(d, dhat), 0.0, 1e-10);
  EXPECT_NEAR(pc::barrier_second_derivative(d, dhat), 0.0, 1e-4);
}

TEST(Friction, F1Values) {
  const double eps = 1e-4;
  EXPECT_EQ(pc::friction_f1(0.0, eps), 0.0);
  EXPECT_DOUBLE_EQ(pc::friction_f1(0.5 * eps, eps), 0.75);
  EXPECT_DOUBLE_EQ(pc::friction_f1(eps, eps), 1.0);
  EXPECT_DOUBLE_EQ(pc::friction_f1(3 * eps, eps), 1.0);
  EXPECT_DOUBLE_EQ(pc::friction_f1_over_y(0.0, eps), 2.0 / eps);
  for (double y : {1e-7, 3e-5, 0.9e-4, 2e-4})
    EXPECT_NEAR(pc::friction_f1_over_y(y, eps), pc::friction_f1(y, eps) / y, 1e-9 / y);
}

TEST(Friction, F0IsIntegralOfF1) {
  const double eps = 1e-4;
  EXPECT_DOUBLE_EQ(pc::friction_f0(0.0, eps), eps / 3.0);
  EXPECT_DOUBLE_EQ(pc::friction_f0(eps, eps), eps);
  EXPECT_DOUBLE_EQ(pc::friction_f0(5 * eps, eps), 5 * eps);
  for (double y : {1e-6, 3e-5, 0.7e-4, 1.5e-4}) {
    const double fd =
        central_difference([&](double x) { return pc::friction_f0(x, eps); }, y, 1e-4 * y);
    EXPECT_NEAR(fd, pc::friction_f1(y, eps), 1e-7) << "y = " << y;
  }
}

TEST(Friction, F2TermMatchesDerivativeOfF1OverY) {
  const double eps = 1e-4;
  for (double y : {1e-6, 3e-5, 0.7e-4, 1.5e-4, 1e-3}) {
    const double fd =
        central_difference([&](double x) { return pc::friction_f1_over_y(x, eps); }, y, 1e-5 * y);
    const double expected = fd / y;
    EXPECT_NEAR(pc::friction_f2_term(y, eps), expected, 1e-6 * std::abs(expected)) << y;
  }
  EXPECT_EQ(pc::friction_f2_term(0.0, eps), 0.0);
}

TEST(Friction, GradientAndHessianMatchFiniteDifferences) {
  const double eps = 1e-4;
  const auto f0 = [&](const Eigen::Vector2d& u) { return pc::friction_f0(u.norm(), eps); };
  for (const Eigen::Vector2d& u :
       {Eigen::Vector2d(3e-5, -2e-5), Eigen::Vector2d(2e-4, 1e-4), Eigen::Vector2d(1e-7, 0.0)}) {
    const double h = 1e-8;
    const Eigen::Vector2d g = pc::friction_gradient(u, eps);
    const Eigen::Matrix2d H = pc::friction_hessian(u, eps);
    for (int i = 0; i < 2; ++i) {
      const Eigen::Vector2d e = Eigen::Vector2d::Unit(i) * h;
      EXPECT_NEAR(g[i], (f0(u + e) - f0(u - e)) / (2 * h), 1e-6) << u.transpose();
      const Eigen::Vector2d dg =
          (pc::friction_gradient(u + e, eps) - pc::friction_gradient(u - e, eps)) / (2 * h);
      EXPECT_NEAR((H.col(i) - dg).norm(), 0.0, 1e-5 * H.norm()) << u.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(H);
    EXPECT_GE(es.eigenvalues().minCoeff(), -1e-9 * H.norm());
  }
  EXPECT_TRUE(pc::friction_hessian(Eigen::Vector2d::Zero(), eps)
                  .isApprox(2.0 / eps * Eigen::Matrix2d::Identity()));
}
