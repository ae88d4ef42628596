#include "simulation/energies/dihedral_angle.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

namespace papersim::simulation {
namespace {

using Vec3 = Eigen::Vector3d;
using Vec12 = Eigen::Matrix<double, 12, 1>;
using Mat12 = Eigen::Matrix<double, 12, 12>;

struct Hinge {
  Vec3 x0, x1, xa, xb;
};

Vec12 stack(const Hinge& h) {
  Vec12 x;
  x << h.x0, h.x1, h.xa, h.xb;
  return x;
}

Hinge unstack(const Vec12& x) {
  return {x.segment<3>(0), x.segment<3>(3), x.segment<3>(6), x.segment<3>(9)};
}

double angle(const Vec12& x) {
  const Hinge h = unstack(x);
  return dihedral_angle(h.x0, h.x1, h.xa, h.xb);
}

Vec12 gradient(const Vec12& x) {
  const Hinge h = unstack(x);
  return dihedral_angle_gradient(h.x0, h.x1, h.xa, h.xb);
}

/// Edge from (0,0,0) to (1,0,0); wing A flat at +y; wing B rotated by `fold` about the edge,
/// starting from -y. n_a = +z, so fold > 0 lifts xb to the n_a side.
Hinge folded_hinge(double fold) {
  return {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.4, 1.0, 0.0),
          Vec3(0.6, -std::cos(fold), std::sin(fold))};
}

/// Random non-degenerate hinge with |theta| spread over (0, ~3.05] rad: edge of length
/// 0.5..2, apexes at heights 0.3..1.5 with feet anywhere from -0.5 to 1.5 along the edge
/// (obtuse wings included), then a random rigid motion and a small random offset.
Hinge random_hinge(std::mt19937& rng) {
  std::uniform_real_distribution<double> len(0.5, 2.0), height(0.3, 1.5), foot(-0.5, 1.5),
      fold(-3.05, 3.05), unit(-1.0, 1.0);
  const double l = len(rng);
  const double phi = fold(rng);
  Hinge h{Vec3(0, 0, 0), Vec3(l, 0, 0), Vec3(foot(rng) * l, height(rng), 0), Vec3::Zero()};
  const double hb = height(rng);
  h.xb = Vec3(foot(rng) * l, -hb * std::cos(phi), hb * std::sin(phi));
  const Eigen::Matrix3d r =
      Eigen::Quaterniond(Eigen::Vector4d(unit(rng), unit(rng), unit(rng), unit(rng)).normalized())
          .toRotationMatrix();
  const Vec3 t(unit(rng), unit(rng), unit(rng));
  for (Vec3* p : {&h.x0, &h.x1, &h.xa, &h.xb}) *p = r * *p + t;
  return h;
}

std::vector<Hinge> random_hinges(int count) {
  std::mt19937 rng(20240611u);
  std::vector<Hinge> hinges;
  for (int i = 0; i < count; ++i) hinges.push_back(random_hinge(rng));
  return hinges;
}

TEST(DihedralAngle, FlatIsZero) {
  EXPECT_NEAR(dihedral_angle(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.3, 1, 0), Vec3(0.7, -2, 0)), 0.0,
              1e-15);
}

TEST(DihedralAngle, SignConvention) {
  // xb lifted to the side of n_a (valley seen from the normals): positive.
  const Hinge up = folded_hinge(0.3);
  EXPECT_GT((up.xb - up.x0).dot((up.x1 - up.x0).cross(up.xa - up.x0)), 0.0);
  EXPECT_NEAR(dihedral_angle(up.x0, up.x1, up.xa, up.xb), 0.3, 1e-14);
  // Folded the other way: negative.
  const Hinge down = folded_hinge(-0.3);
  EXPECT_NEAR(dihedral_angle(down.x0, down.x1, down.xa, down.xb), -0.3, 1e-14);
  // Lifting wing A towards its own normal folds the same way as lifting xb: positive.
  EXPECT_GT(dihedral_angle(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.4, 1, 0.2), Vec3(0.6, -1, 0)), 0.0);
  // Swapping the wings (and so the edge direction, to keep both faces counter-clockwise)
  // describes the same hinge: same angle.
  EXPECT_NEAR(dihedral_angle(up.x1, up.x0, up.xb, up.xa), 0.3, 1e-14);
}

TEST(DihedralAngle, KnownFolds) {
  EXPECT_NEAR(angle(stack(folded_hinge(M_PI / 2))), M_PI / 2, 1e-15);
  EXPECT_NEAR(angle(stack(folded_hinge(-M_PI / 2))), -M_PI / 2, 1e-15);
  for (double fold : {0.1, 1.0, 2.0, 3.0, 3.1, 3.14, M_PI - 1e-6, M_PI - 1e-10}) {
    EXPECT_NEAR(angle(stack(folded_hinge(fold))), fold, 1e-14) << fold;
    EXPECT_NEAR(angle(stack(folded_hinge(-fold))), -fold, 1e-14) << fold;
  }
  // Fully folded (the wings lie on top of each other): +pi, never -pi.
  EXPECT_EQ(dihedral_angle(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.4, 1, 0), Vec3(0.6, 2, 0)), M_PI);
  EXPECT_EQ(dihedral_angle(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.4, 1, 0), Vec3(0.6, 2, -0.0)),
            M_PI);
}

TEST(DihedralAngle, ScaleInvariance) {
  // theta does not change under uniform scaling; gradient ~ 1/s and Hessian ~ 1/s^2. Guards
  // against a length factor left in one atan2 argument only (unit-edge hinges would not see it).
  for (double fold : {0.7, -2.5, 3.0}) {
    const Hinge h = folded_hinge(fold);
    const Vec12 g = gradient(stack(h));
    const Mat12 hess = dihedral_angle_hessian(h.x0, h.x1, h.xa, h.xb);
    for (double s : {1e-3, 0.37, 25.0}) {
      const Hinge k{s * h.x0, s * h.x1, s * h.xa, s * h.xb};
      EXPECT_NEAR(dihedral_angle(k.x0, k.x1, k.xa, k.xb), fold, 1e-13) << s;
      EXPECT_LT((s * gradient(stack(k)) - g).norm(), 1e-13 * g.norm()) << s;
      EXPECT_LT((s * s * dihedral_angle_hessian(k.x0, k.x1, k.xa, k.xb) - hess).norm(),
                1e-12 * hess.norm())
          << s;
    }
  }
}

TEST(DihedralAngle, PiMinusInteriorAngle) {
  for (const Hinge& h : random_hinges(50)) {
    const Vec3 e = (h.x1 - h.x0).normalized();
    // In-plane directions from the edge towards each apex; their angle is the interior angle.
    const Vec3 da = (h.xa - h.x0) - (h.xa - h.x0).dot(e) * e;
    const Vec3 db = (h.xb - h.x0) - (h.xb - h.x0).dot(e) * e;
    const double interior = std::atan2(da.cross(db).norm(), da.dot(db));
    EXPECT_NEAR(std::abs(dihedral_angle(h.x0, h.x1, h.xa, h.xb)), M_PI - interior, 1e-12);
  }
}

TEST(DihedralAngle, RigidMotionInvariance) {
  const Eigen::Matrix3d r =
      Eigen::AngleAxisd(1.234, Vec3(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  const Vec3 t(10.0, -3.0, 7.5);
  for (const Hinge& h : random_hinges(50)) {
    const double theta = dihedral_angle(h.x0, h.x1, h.xa, h.xb);
    Hinge m = h;
    for (Vec3* p : {&m.x0, &m.x1, &m.xa, &m.xb}) *p = r * *p + t;
    EXPECT_NEAR(dihedral_angle(m.x0, m.x1, m.xa, m.xb), theta, 1e-12);
    // The gradient rotates with the hinge.
    const Vec12 g = gradient(stack(h));
    const Vec12 gm = gradient(stack(m));
    for (int i = 0; i < 4; ++i)
      EXPECT_LT((gm.segment<3>(3 * i) - r * g.segment<3>(3 * i)).norm(), 1e-10 * g.norm());
  }
}

TEST(DihedralAngle, DerivativesAgreeWithSeparateCalls) {
  for (const Hinge& h : random_hinges(20)) {
    double theta = 0.0;
    Vec12 g;
    Mat12 hess;
    dihedral_angle_derivatives(h.x0, h.x1, h.xa, h.xb, theta, &g, &hess);
    EXPECT_EQ(theta, dihedral_angle(h.x0, h.x1, h.xa, h.xb));
    EXPECT_EQ(g, dihedral_angle_gradient(h.x0, h.x1, h.xa, h.xb));
    EXPECT_EQ(hess, dihedral_angle_hessian(h.x0, h.x1, h.xa, h.xb));
    double theta_only = 0.0;
    dihedral_angle_derivatives(h.x0, h.x1, h.xa, h.xb, theta_only, nullptr, nullptr);
    EXPECT_EQ(theta_only, theta);
  }
}

// Central differences err by ~ step^2 |f'''| / 6 (truncation) plus ~ eps |f| / step (round-off).
// theta varies on the length scale of the hinge (edge length and heights >= 0.3 m in
// random_hinge), so relative truncation error ~ (step / 0.3)^2 and round-off ~ 1e-16 / step:
// the sum is smallest near step = eps^(1/3) * 0.3 ~ 2e-6. Step 1e-5 is a little larger, for a
// safety margin against round-off, and gives ~1e-9 relative error on these hinges (about 1e-7
// even on uniformly random, skinny hinges), well under the 1e-6 (gradient) and 1e-5 (Hessian)
// tolerances. Errors are relative to the norm of the whole exact gradient / Hessian, so
// near-zero entries do not inflate them.
constexpr double FD_STEP = 1e-5;  // [m]

TEST(DihedralAngle, GradientMatchesFiniteDifferences) {
  for (const Hinge& h : random_hinges(400)) {
    const Vec12 x = stack(h);
    const double theta = angle(x);
    if (std::abs(theta) > M_PI - 1e-3) continue;  // keep the stencil away from the +-pi jump
    Vec12 fd;
    for (int i = 0; i < 12; ++i) {
      Vec12 xp = x, xm = x;
      xp[i] += FD_STEP;
      xm[i] -= FD_STEP;
      fd[i] = (angle(xp) - angle(xm)) / (2.0 * FD_STEP);
    }
    const Vec12 g = gradient(x);
    EXPECT_LT((g - fd).norm() / g.norm(), 1e-6) << "theta = " << theta;
  }
}

TEST(DihedralAngle, HessianMatchesFiniteDifferencesOfGradient) {
  double max_abs_theta = 0.0;
  for (const Hinge& h : random_hinges(400)) {
    const Vec12 x = stack(h);
    max_abs_theta = std::max(max_abs_theta, std::abs(angle(x)));
    Mat12 fd;
    for (int i = 0; i < 12; ++i) {
      Vec12 xp = x, xm = x;
      xp[i] += FD_STEP;
      xm[i] -= FD_STEP;
      fd.col(i) = (gradient(xp) - gradient(xm)) / (2.0 * FD_STEP);
    }
    const Mat12 hess = dihedral_angle_hessian(h.x0, h.x1, h.xa, h.xb);
    EXPECT_LT((hess - fd).norm() / hess.norm(), 1e-5) << "theta = " << angle(x);
  }
  EXPECT_GT(max_abs_theta, 3.0);  // the sample does include strongly folded hinges
}

TEST(DihedralAngle, HessianIsExactlySymmetric) {
  for (const Hinge& h : random_hinges(100)) {
    const Mat12 hess = dihedral_angle_hessian(h.x0, h.x1, h.xa, h.xb);
    EXPECT_EQ(hess, hess.transpose());
    EXPECT_TRUE(hess.allFinite());
  }
}

TEST(DihedralAngle, GradientTranslationAndRotationInvariance) {
  for (const Hinge& h : random_hinges(100)) {
    const Vec12 x = stack(h);
    const Vec12 g = gradient(x);
    Vec3 force_sum = Vec3::Zero();
    Vec3 torque_sum = Vec3::Zero();
    for (int i = 0; i < 4; ++i) {
      force_sum += g.segment<3>(3 * i);
      torque_sum += x.segment<3>(3 * i).cross(g.segment<3>(3 * i));
    }
    const double scale = g.norm() * x.norm();
    EXPECT_LT(force_sum.norm(), 1e-13 * g.norm());
    EXPECT_LT(torque_sum.norm(), 1e-13 * scale);
  }
}

TEST(DihedralAngle, HessianTranslationInvariance) {
  // Every 3-row block of the Hessian sums to zero over the four vertices (the gradient is
  // translation invariant), and by symmetry every 3-column block too.
  for (const Hinge& h : random_hinges(100)) {
    const Mat12 hess = dihedral_angle_hessian(h.x0, h.x1, h.xa, h.xb);
    Eigen::Matrix<double, 12, 3> sum = Eigen::Matrix<double, 12, 3>::Zero();
    for (int j = 0; j < 4; ++j) sum += hess.middleCols<3>(3 * j);
    EXPECT_LT(sum.norm(), 1e-12 * hess.norm());
  }
}

}  // namespace
}  // namespace papersim::simulation
