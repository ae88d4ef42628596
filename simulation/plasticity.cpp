#include "simulation/plasticity.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "simulation/errors.hpp"

namespace papersim::simulation {

namespace {
constexpr double YIELD_SLACK = 1e-9;  // [-] relative
}  // namespace

double curvature_norm(const Eigen::Vector3d& k) {
  // The off-diagonal entry k_xy appears twice in the 2x2 tensor.
  return std::sqrt(k[0] * k[0] + k[1] * k[1] + 2 * k[2] * k[2]);
}

PlasticUpdate return_mapping(const Eigen::MatrixX3d& curvature, double yield_curvature,
                             Eigen::MatrixX3d& plastic_curvature, Eigen::VectorXd& damage) {
  if (!(yield_curvature > 0) || !std::isfinite(yield_curvature))
    throw NumericError("plasticity: the yield curvature must be positive and finite");
  if (plastic_curvature.rows() != curvature.rows() || damage.size() != curvature.rows())
    throw NumericError("plasticity: " + std::to_string(curvature.rows()) + " face curvatures for " +
                       std::to_string(plastic_curvature.rows()) + " plastic curvatures and " +
                       std::to_string(damage.size()) + " damage values");
  PlasticUpdate u;
  for (int f = 0; f < curvature.rows(); ++f) {
    const Eigen::Vector3d elastic = (curvature.row(f) - plastic_curvature.row(f)).transpose();
    const double norm = curvature_norm(elastic);
    if (!std::isfinite(norm))
      throw NumericError("plasticity: the curvature of face " + std::to_string(f) +
                         " is not finite");
    // A face left on the yield surface by the last update measures k_y up to rounding; the
    // relative slack keeps it from yielding again by 1e-16 (and re-factoring Morley's slopes).
    if (norm <= yield_curvature * (1 + YIELD_SLACK)) continue;
    const Eigen::Vector3d increment = (1 - yield_curvature / norm) * elastic;
    const double size = curvature_norm(increment);
    plastic_curvature.row(f) += increment.transpose();
    damage[f] += size / yield_curvature;
    ++u.yielded_faces;
    u.max_increment = std::max(u.max_increment, size);
    u.damage_added += size / yield_curvature;
  }
  return u;
}

bool plasticity_enabled(const Material& material) {
  return material.bending_model == BendingModel::morley;
}

PlasticUpdate apply_plasticity(BendingEnergy& bending, const Eigen::VectorXd& x,
                               double yield_curvature, remesh::SheetMesh& mesh) {
  Eigen::MatrixX3d plastic = mesh.plastic_curvature();
  Eigen::VectorXd damage = mesh.damage();
  const PlasticUpdate u =
      return_mapping(bending.yield_curvatures(x), yield_curvature, plastic, damage);
  if (u.yielded_faces == 0) return u;
  bending.set_plastic_state(plastic, damage);
  mesh.set_plastic_curvature(plastic);
  mesh.set_damage(damage);
  return u;
}

}  // namespace papersim::simulation
