#include "simulation/energies/contact_energy.hpp"

#include <cmath>

#include "collision/barrier.hpp"

namespace papersim::simulation {

using collision::barrier;
using collision::barrier_first_derivative;
using collision::barrier_second_derivative;

ObstacleContactEnergy::ObstacleContactEnergy(
    Eigen::VectorXd vertex_areas, std::vector<std::shared_ptr<const collision::Collider>> obstacles,
    const ContactParams& params)
    : m_area(std::move(vertex_areas)), m_obstacles(std::move(obstacles)), m_params(params) {}

bool ObstacleContactEnergy::near_bounds(int o, const Eigen::Vector3d& p) const {
  const auto& b = m_bounds[o];
  return (p.array() >= b.lo.array()).all() && (p.array() <= b.hi.array()).all();
}

void ObstacleContactEnergy::begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0) {
  m_t1 = ctx.time_t1();
  m_eps = m_params.eps_velocity * ctx.h;
  m_bounds.clear();
  for (const auto& o : m_obstacles) {
    collision::Aabb b = o->bounds(m_t1);
    b.lo.array() -= m_params.dhat;
    b.hi.array() += m_params.dhat;
    m_bounds.push_back(b);
  }
  // Lagged friction: normal force and tangent plane at the step start (IPC Sec. 5).
  m_friction.clear();
  m_normal_force = 0.0;
  const int nv = static_cast<int>(m_area.size());
  for (int o = 0; o < num_obstacles(); ++o) {
    const auto& obs = *m_obstacles[o];
    for (int v = 0; v < nv; ++v) {
      const Eigen::Vector3d p = x_t0.segment<3>(3 * v);
      if (!near_bounds(o, p)) continue;
      Eigen::Vector3d n;
      const double d = obs.distance(p, ctx.time_t0, &n);
      if (d >= m_params.dhat || d <= 0) continue;
      const double lambda = -kappa(v) * barrier_first_derivative(d, m_params.dhat);
      m_normal_force += lambda;
      if (obs.friction <= 0) continue;
      FrictionPoint fp;
      fp.vertex = v;
      fp.obstacle = o;
      fp.mu_lambda = obs.friction * lambda;
      const Eigen::Vector3d a = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
      fp.T.col(0) = n.cross(a).normalized();
      fp.T.col(1) = n.cross(fp.T.col(0));
      fp.origin = p + ctx.h * obs.velocity(p, ctx.time_t0);
      m_friction.push_back(fp);
    }
  }
}

namespace {

/// IPC friction smoothing: f0(y) = -y^3/(3 eps^2) + y^2/eps + eps/3 below eps, y above.
double f0(double y, double eps) {
  return y >= eps ? y : -y * y * y / (3 * eps * eps) + y * y / eps + eps / 3;
}

}  // namespace

double ObstacleContactEnergy::value(const Eigen::VectorXd& x) const {
  double e = 0;
  const int nv = static_cast<int>(m_area.size());
  for (int o = 0; o < num_obstacles(); ++o)
    for (int v = 0; v < nv; ++v) {
      const Eigen::Vector3d p = x.segment<3>(3 * v);
      if (!near_bounds(o, p)) continue;
      const double d = m_obstacles[o]->distance(p, m_t1);
      if (d <= 0) return INF;
      if (d < m_params.dhat) e += kappa(v) * barrier(d, m_params.dhat);
    }
  for (const auto& fp : m_friction) {
    const Eigen::Vector2d u = fp.T.transpose() * (x.segment<3>(3 * fp.vertex) - fp.origin);
    e += fp.mu_lambda * f0(u.norm(), m_eps);
  }
  return e;
}

void ObstacleContactEnergy::add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& g,
                                            BlockSymmetricMatrix* H) const {
  const int nv = static_cast<int>(m_area.size());
  Eigen::VectorXd diag_dummy;
  for (int o = 0; o < num_obstacles(); ++o)
    for (int v = 0; v < nv; ++v) {
      const Eigen::Vector3d p = x.segment<3>(3 * v);
      if (!near_bounds(o, p)) continue;
      Eigen::Vector3d n;
      const double d = m_obstacles[o]->distance(p, m_t1, &n);
      if (d >= m_params.dhat || d <= 0) continue;
      g.segment<3>(3 * v) += kappa(v) * barrier_first_derivative(d, m_params.dhat) * n;
      if (H) {
        const Eigen::Matrix3d local =
            kappa(v) * barrier_second_derivative(d, m_params.dhat) * n * n.transpose();
        H->add_element<1>({v}, local);
      }
    }
  for (const auto& fp : m_friction) {
    const Eigen::Vector2d u = fp.T.transpose() * (x.segment<3>(3 * fp.vertex) - fp.origin);
    const double y = u.norm();
    // f1(y)/y with f1 = f0': 1/y above eps, -y/eps^2 + 2/eps below (finite at y = 0).
    const double f1_over_y = y >= m_eps ? 1 / y : -y / (m_eps * m_eps) + 2 / m_eps;
    g.segment<3>(3 * fp.vertex) += fp.mu_lambda * f1_over_y * (fp.T * u);
    if (!H) continue;
    // d/du (f1/y u) = f1/y I + (d(f1/y)/dy / y) u u^T; PSD in both regimes (see header).
    Eigen::Matrix2d M = f1_over_y * Eigen::Matrix2d::Identity();
    if (y > 0) {
      const double slope = y >= m_eps ? -1 / (y * y * y) : -1 / (m_eps * m_eps * y);
      M += slope * u * u.transpose();
    }
    const Eigen::Matrix3d local = fp.mu_lambda * fp.T * M * fp.T.transpose();
    H->add_element<1>({fp.vertex}, local);
  }
}

double ObstacleContactEnergy::max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const {
  double alpha = 1.0;
  const int nv = static_cast<int>(m_area.size());
  for (int o = 0; o < num_obstacles(); ++o) {
    const auto& obs = *m_obstacles[o];
    for (int v = 0; v < nv; ++v) {
      const Eigen::Vector3d p = x.segment<3>(3 * v), d = dx.segment<3>(3 * v);
      const double len = d.norm();
      if (len == 0) continue;
      double dist = obs.distance(p, m_t1);
      if (dist >= alpha * len) continue;  // cannot reach the surface within this step
      // Sphere tracing: phi is 1-Lipschitz, so advancing by (phi - stop) / len keeps every
      // point passed over at phi >= stop. The vertex may close at most 90% of its gap.
      const double stop = 0.1 * dist;
      double t = 0;
      for (int it = 0; it < 64; ++it) {
        const double advance = (dist - stop) / len;
        if (advance <= 0) break;
        t += advance;
        if (t >= alpha) break;
        dist = obs.distance(p + t * d, m_t1);
      }
      alpha = std::min(alpha, t);
    }
  }
  return alpha;
}

double ObstacleContactEnergy::min_distance(int o, const Eigen::VectorXd& x) const {
  double m = INF;
  for (int v = 0; v < m_area.size(); ++v)
    m = std::min(m, m_obstacles[o]->distance(x.segment<3>(3 * v), m_t1));
  return m;
}

}  // namespace papersim::simulation
