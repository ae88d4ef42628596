#include "collision/collider.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "common/format.hpp"

namespace papersim::collision {

// ---------------------------------------------------------------------------------------------
// Aabb

double Aabb::distance_to(const Aabb& other) const {
  if (is_empty() || other.is_empty()) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d gap =
      (other.lo - hi).cwiseMax(lo - other.hi).cwiseMax(Eigen::Vector3d::Zero());
  return gap.norm();
}

double Aabb::distance_to(const Eigen::Vector3d& p) const {
  if (is_empty()) return std::numeric_limits<double>::infinity();
  return (lo - p).cwiseMax(p - hi).cwiseMax(Eigen::Vector3d::Zero()).norm();
}

// ---------------------------------------------------------------------------------------------
// RigidMotion

RigidMotion::RigidMotion(std::vector<Keyframe> keyframes) : m_keyframes(std::move(keyframes)) {
  for (size_t i = 1; i < m_keyframes.size(); ++i) {
    if (!(m_keyframes[i].time > m_keyframes[i - 1].time))
      throw std::invalid_argument("RigidMotion: keyframe times must increase, but keyframe " +
                                  std::to_string(i) + " has time " +
                                  common::format_number(m_keyframes[i].time) + " after " +
                                  common::format_number(m_keyframes[i - 1].time));
  }
  for (Keyframe& k : m_keyframes) {
    if (!(std::isfinite(k.scale) && k.scale > 0.0))
      throw std::invalid_argument("RigidMotion: keyframe scale must be finite and > 0, got " +
                                  common::format_number(k.scale));
    if (!(k.rotation.norm() > 0.0))
      throw std::invalid_argument("RigidMotion: keyframe rotation quaternion has zero norm");
    k.rotation.normalize();
  }
}

int RigidMotion::segment(double t) const {
  if (m_keyframes.size() < 2 || t < m_keyframes.front().time || t >= m_keyframes.back().time)
    return -1;
  const auto it = std::upper_bound(m_keyframes.begin(), m_keyframes.end(), t,
                                   [](double x, const Keyframe& k) { return x < k.time; });
  return static_cast<int>(it - m_keyframes.begin()) - 1;
}

Eigen::Affine3d RigidMotion::pose(double t) const {
  const Keyframe k = keyframe_at(t);
  Eigen::Affine3d x = Eigen::Affine3d::Identity();
  x.linear() = k.scale * k.rotation.toRotationMatrix();
  x.translation() = k.translation;
  return x;
}

double RigidMotion::scale(double t) const {
  if (m_keyframes.empty()) return 1.0;
  const int i = segment(t);
  if (i < 0)
    return t >= m_keyframes.back().time ? m_keyframes.back().scale : m_keyframes.front().scale;
  const Keyframe& a = m_keyframes[i];
  const Keyframe& b = m_keyframes[i + 1];
  const double s = (t - a.time) / (b.time - a.time);
  return (1.0 - s) * a.scale + s * b.scale;
}

double RigidMotion::scale_rate(double t) const {
  const int i = segment(t);
  if (i < 0) return 0.0;
  return (m_keyframes[i + 1].scale - m_keyframes[i].scale) /
         (m_keyframes[i + 1].time - m_keyframes[i].time);
}

Eigen::Vector3d RigidMotion::linear_velocity(double t) const {
  const int i = segment(t);
  if (i < 0) return Eigen::Vector3d::Zero();
  const Keyframe& a = m_keyframes[i];
  const Keyframe& b = m_keyframes[i + 1];
  return (b.translation - a.translation) / (b.time - a.time);
}

// Slerp from q_a to q_b turns at a constant rate about the world axis of q_b q_a^-1 (taken on
// the short arc, as Eigen's slerp does), so omega = axis * angle / duration.
Eigen::Vector3d RigidMotion::angular_velocity(double t) const {
  const int i = segment(t);
  if (i < 0) return Eigen::Vector3d::Zero();
  const Keyframe& a = m_keyframes[i];
  const Keyframe& b = m_keyframes[i + 1];
  Eigen::Quaterniond rel = b.rotation * a.rotation.conjugate();
  if (rel.w() < 0.0) rel.coeffs() = -rel.coeffs();
  const Eigen::AngleAxisd aa(rel);
  return aa.axis() * aa.angle() / (b.time - a.time);
}

bool RigidMotion::is_static() const {
  for (size_t i = 1; i < m_keyframes.size(); ++i) {
    if (m_keyframes[i].translation != m_keyframes[0].translation) return false;
    if (m_keyframes[i].scale != m_keyframes[0].scale) return false;
    if (std::abs(m_keyframes[i].rotation.dot(m_keyframes[0].rotation)) < 1.0) return false;
  }
  return true;
}

double RigidMotion::next_keyframe_time(double t) const {
  const auto it = std::upper_bound(m_keyframes.begin(), m_keyframes.end(), t,
                                   [](double x, const Keyframe& k) { return x < k.time; });
  return it == m_keyframes.end() ? std::numeric_limits<double>::infinity() : it->time;
}

Keyframe RigidMotion::keyframe_at(double t) const {
  Keyframe k;
  k.time = t;
  if (m_keyframes.empty()) return k;
  const int i = segment(t);
  if (i < 0) {
    const Keyframe& e = t >= m_keyframes.back().time ? m_keyframes.back() : m_keyframes.front();
    k.translation = e.translation;
    k.rotation = e.rotation;
    k.scale = e.scale;
    return k;
  }
  const Keyframe& a = m_keyframes[i];
  const Keyframe& b = m_keyframes[i + 1];
  const double s = (t - a.time) / (b.time - a.time);
  k.translation = (1.0 - s) * a.translation + s * b.translation;
  k.rotation = a.rotation.slerp(s, b.rotation);
  k.scale = (1.0 - s) * a.scale + s * b.scale;
  return k;
}

size_t RigidMotion::keyframe_index(double t, const RigidMotion& turning) {
  constexpr double SAME = 1e-9;  // [s] keyframes this close count as one
  const auto it = std::lower_bound(m_keyframes.begin(), m_keyframes.end(), t - SAME,
                                   [](const Keyframe& k, double x) { return k.time < x; });
  if (it != m_keyframes.end() && it->time <= t + SAME)
    return static_cast<size_t>(it - m_keyframes.begin());
  const size_t i = static_cast<size_t>(it - m_keyframes.begin());
  Keyframe k = turning.keyframe_at(t);
  k.translation = pose(t).translation();
  m_keyframes.insert(m_keyframes.begin() + static_cast<long>(i), k);
  return i;
}

void RigidMotion::translate_from(double t0, double t1, const Eigen::Vector3d& delta,
                                 const RigidMotion& turning) {
  if (!(t1 > t0))
    throw std::invalid_argument("RigidMotion::translate_from: t1 = " + common::format_number(t1) +
                                " must be after t0 = " + common::format_number(t0));
  keyframe_index(t0, turning);
  for (size_t i = keyframe_index(t1, turning); i < m_keyframes.size(); ++i)
    m_keyframes[i].translation += delta;
}

void RigidMotion::set_translation_at(double t, const Eigen::Vector3d& translation,
                                     const RigidMotion& turning) {
  m_keyframes[keyframe_index(t, turning)].translation = translation;
}

bool RigidMotion::moves_during(double t0, double t1) const {
  if (is_static()) return false;
  for (double t = t0; t < t1; t = next_keyframe_time(t))
    if (linear_velocity(t).squaredNorm() > 0 || angular_velocity(t).squaredNorm() > 0 ||
        scale_rate(t) != 0)
      return true;
  return false;
}

// ---------------------------------------------------------------------------------------------
// Collider

double Collider::distance(const Eigen::Vector3d& p, double t, Eigen::Vector3d* gradient) const {
  return distance_at_pose(p, motion.pose(t), gradient);
}

// pose.linear() = s R with R a rotation, so s^2 = |first column|^2, the local point is
// X = (s R)^T (p - c) / s^2 and the field of the scaled shape is s phi_local(X) (distances scale
// with the shape); its gradient is R g_local = (s R) g_local / s.
double Collider::distance_at_pose(const Eigen::Vector3d& p, const Eigen::Affine3d& pose,
                                  Eigen::Vector3d* gradient) const {
  const double s2 = pose.linear().col(0).squaredNorm();
  const Eigen::Vector3d local = pose.linear().transpose() * (p - pose.translation()) / s2;
  const double s = s2 == 1.0 ? 1.0 : std::sqrt(s2);
  if (!gradient) return s * local_distance(local, nullptr);
  Eigen::Vector3d g_local;
  const double d = local_distance(local, &g_local);
  *gradient = pose.linear() * g_local / s;
  return s * d;
}

namespace {
Aabb transformed_box(const Aabb& local, const Eigen::Affine3d& pose) {
  Aabb out;
  if (local.is_empty()) return out;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((c & 1) ? local.hi.x() : local.lo.x(),
                                 (c & 2) ? local.hi.y() : local.lo.y(),
                                 (c & 4) ? local.hi.z() : local.lo.z());
    out.extend(pose * corner);
  }
  return out;
}
}  // namespace

Aabb Collider::bounds(double t) const { return transformed_box(local_bounds(), motion.pose(t)); }

// Between samples s_k the pose moves by a translation (linear, exact for boxes) and a rotation
// of angle a; a point at radius r from the local origin leaves the chord by at most
// r (1 - cos(a/2)), so padding each sampled box by that bound makes the union conservative.
Aabb Collider::swept_bounds(double t0, double t1) const {
  const Aabb local = local_bounds();
  Aabb out = transformed_box(local, motion.pose(t0));
  out.extend(transformed_box(local, motion.pose(t1)));
  if (local.is_empty() || motion.is_static() || !(t1 > t0)) return out;
  double radius = local.lo.cwiseAbs().cwiseMax(local.hi.cwiseAbs()).norm();
  constexpr int SAMPLES = 32;
  double max_angle = 0.0, max_scale = 0.0;
  for (int k = 0; k <= SAMPLES; ++k) {
    const double t = t0 + (t1 - t0) * k / SAMPLES;
    out.extend(transformed_box(local, motion.pose(t)));
    max_scale = std::max(max_scale, motion.scale(t));
    max_angle = std::max(max_angle, motion.angular_velocity(t).norm() * (t1 - t0) / SAMPLES);
  }
  // Keyframe times inside the interval are corners of the path: include them exactly.
  for (const Keyframe& k : motion.keyframes()) {
    if (!(k.time > t0 && k.time < t1)) continue;
    out.extend(transformed_box(local, motion.pose(k.time)));
    max_scale = std::max(max_scale, k.scale);
    max_angle = std::max(max_angle, motion.angular_velocity(k.time).norm() * (t1 - t0) / SAMPLES);
  }
  out.inflate(max_scale * radius * (1.0 - std::cos(0.5 * max_angle)));
  return out;
}

// x(t) = s(t) R(t) X + c(t)  =>  dx/dt = omega x (x - c) + (s'/s) (x - c) + dc/dt, analytic
// from the keyframes (x - c = s R X, so d(s R)/dt X = (s'/s + omega x) (x - c)).
Eigen::Vector3d Collider::velocity(const Eigen::Vector3d& p, double t) const {
  // One keyframe (or none): the placement never changes; no pose to evaluate per point.
  if (motion.keyframes().size() < 2) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d c = motion.pose(t).translation();
  return motion.linear_velocity(t) + motion.angular_velocity(t).cross(p - c) +
         motion.scale_rate(t) / motion.scale(t) * (p - c);
}

// Sphere tracing: phi is 1-Lipschitz, so advancing by (phi - stop) / |d| keeps every point
// passed over at phi >= stop.
double Collider::segment_step(const Eigen::Vector3d& p, const Eigen::Vector3d& d, double t,
                              double limit, double keep) const {
  const double len = d.norm();
  if (len == 0) return limit;
  const Eigen::Affine3d pose = motion.pose(t);
  double dist = distance_at_pose(p, pose);
  const double stop = keep * dist;
  double a = 0;
  for (int it = 0; it < 256; ++it) {
    const double advance = (dist - stop) / len;
    if (advance <= 0) break;
    a += advance;
    if (a >= limit) return limit;
    dist = distance_at_pose(p + a * d, pose);
  }
  return a;
}

bool Collider::distance_hessian(const Eigen::Vector3d&, double, Eigen::Matrix3d&) const {
  return false;
}

bool Collider::moves_affinely(double t0, double t1) const { return !motion.moves_during(t0, t1); }

double Collider::moving_segment_step(const Eigen::Vector3d& p, const Eigen::Vector3d& d, double t,
                                     double dt, double limit, double keep) const {
  if (!moves_affinely(t, t + limit * dt)) return -1.0;
  return segment_step(p, d, t, limit, keep);
}

double Collider::convex_piece_step(const Eigen::Vector3d& q, const Eigen::Vector3d& d, double tq,
                                   double dt, double length, double stop, double t_inside) const {
  Eigen::Vector3d n;
  const double phi = distance_at_pose(q, motion.pose(tq), &n);
  if (!(phi > stop)) return 0.0;
  const double rate = -n.dot(d - dt * motion.linear_velocity(t_inside));
  return rate > 0 ? std::min(length, (phi - stop) / rate) : length;
}

// ---------------------------------------------------------------------------------------------
// PlaneCollider

bool PlaneCollider::moves_affinely(double t0, double t1) const {
  for (double t = t0; t < t1; t = motion.next_keyframe_time(t)) {
    if (motion.scale_rate(t) != 0) return false;
    const Eigen::Vector3d omega = motion.angular_velocity(t);
    if (omega.squaredNorm() == 0) continue;
    const Eigen::Vector3d normal = motion.pose(t).linear().col(2).normalized();
    if ((omega - omega.dot(normal) * normal).norm() > 1e-9 * omega.norm()) return false;
  }
  return true;
}

double PlaneCollider::moving_segment_step(const Eigen::Vector3d& p, const Eigen::Vector3d& d,
                                          double t, double dt, double limit, double keep) const {
  if (dt == 0) return segment_step(p, d, t, limit, keep);
  if (dt < 0 || !moves_affinely(t, t + limit * dt)) return -1.0;
  return step_over_pieces(
      p, d, t, dt, limit, keep,
      [&](const Eigen::Vector3d& q, double tq, double length, double stop, double t_inside) {
        return convex_piece_step(q, d, tq, dt, length, stop, t_inside);
      });
}

double PlaneCollider::local_distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient) const {
  if (gradient) *gradient = Eigen::Vector3d::UnitZ();
  return p.z();
}

Aabb PlaneCollider::local_bounds() const {
  Aabb b;
  b.lo = Eigen::Vector3d(-half_size, -half_size, 0.0);
  b.hi = Eigen::Vector3d(half_size, half_size, 0.0);
  return b;
}

}  // namespace papersim::collision
