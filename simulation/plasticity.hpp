#pragma once
/// Bending plasticity and damage (Narain, Pfaff, O'Brien 2013, "Folding and crumpling adaptive
/// sheets", section 4): a return mapping applied per face after every accepted time step.
///
/// Per face f, with K_f the face's curvature tensor (BendingEnergy::yield_curvatures: a measure
/// of the shape alone, under Morley the least-squares fit of the hinge angles) and Kp_f
/// its plastic curvature (both 2x2 symmetric in material coordinates, Voigt (k_xx, k_yy, k_xy)
/// [1/m]), the elastic curvature is Ke_f = K_f - Kp_f. Its norm is the Frobenius norm of the
/// tensor, |Ke| = sqrt(k_xx^2 + k_yy^2 + 2 k_xy^2) [1/m]. Where |Ke| > k_y (the yield
/// curvature), perfect plasticity moves the plastic curvature by the excess along Ke:
///   dKp = (1 - k_y / |Ke|) Ke,   so that afterwards |K - Kp| = k_y exactly;
/// below yield (|Ke| <= k_y (1 + 1e-9), the slack absorbing rounding) nothing changes. Damage
/// (dimensionless) accumulates the plastic curvature increment measured in yield curvatures:
///   damage += |dKp| / k_y,
/// and the bending energies divide the face's stiffness by (1 + weakening damage).
///
/// Only the Morley model carries plasticity in a run (plasticity_enabled): the fit model's
/// hourglass penalty is measured from the flat angle pattern, so it would resist a plastic
/// crease elastically; it stays the elastic reference model (it still honours a plastic state
/// read from a mesh file).
#include <Eigen/Core>

#include "remesh/sheet_mesh.hpp"
#include "simulation/energies/bending_energy.hpp"

namespace papersim::simulation {

/// Frobenius norm of a symmetric 2x2 curvature tensor in Voigt form (k_xx, k_yy, k_xy) [1/m].
double curvature_norm(const Eigen::Vector3d& k);

/// What one return mapping changed.
struct PlasticUpdate {
  int yielded_faces = 0;       ///< faces whose elastic curvature exceeded the yield [-]
  double max_increment = 0.0;  ///< largest |dKp| over the faces [1/m]
  double damage_added = 0.0;   ///< sum over the faces of the damage increments [-]
};

/// The return mapping on arrays: updates `plastic_curvature` (#F by 3) [1/m] and `damage` (#F)
/// [-] from the face curvatures `curvature` (#F by 3) [1/m].
/// @param yield_curvature k_y > 0 [1/m]
/// @throw NumericError when the sizes differ, k_y is not positive or a curvature is not finite
PlasticUpdate return_mapping(const Eigen::MatrixX3d& curvature, double yield_curvature,
                             Eigen::MatrixX3d& plastic_curvature, Eigen::VectorXd& damage);

/// Whether a run of this material updates its plastic state after every step: true under the
/// Morley bending model.
bool plasticity_enabled(const Material& material);

/// One plastic update of a sheet: measures the yield curvatures of `bending` at the world
/// positions x (3N) [m], applies the return mapping to the plastic state of `mesh`, and hands
/// the new state to `bending` when a face yielded (the state is left untouched otherwise).
/// @throw NumericError as return_mapping, or when `bending` cannot take the new state
PlasticUpdate apply_plasticity(BendingEnergy& bending, const Eigen::VectorXd& x,
                               double yield_curvature, remesh::SheetMesh& mesh);

}  // namespace papersim::simulation
