#pragma once
/// Material of the sheet. Defaults: 80 g/m^2 office paper (SCENARIOS.md, VALIDATION.md).

namespace papersim::simulation {

/// Discretisation of the bending energy (simulation/energies/bending_energy.hpp).
enum class BendingModel { fit, morley };

/// How the membrane measures an edge (simulation/energies/membrane_energy.hpp): `chord`, the
/// straight segment between its ends; `arc`, the arc of the surface the bending discretisation
/// describes (the chord lengthened by the face's normal curvature along the edge).
enum class MembraneModel { chord, arc };

struct Material {
  double density = 0.08;            ///< areal density rho_A [kg/m^2]
  double stretch_stiffness = 5e5;   ///< Eh, Young's modulus x thickness [N/m]
  double poisson = 0.3;             ///< Poisson ratio [-], in [0, 0.5)
  double bending_stiffness = 4e-4;  ///< D = E h^3 / (12 (1 - nu^2)) [N m]
  double damping = 0.0;             ///< mass-proportional damping coefficient [1/s]
  double strain_limit = 0.005;      ///< largest principal stretch <= 1 + strain_limit [-]
  /// smallest principal stretch >= 1 - compression_limit (0: none) [-]
  double compression_limit = 0.0;
  double thickness = 1e-4;         ///< physical thickness [m] (for reports and contact)
  double yield_curvature = 200.0;  ///< plastic yield curvature [1/m]
  double weakening = 1.0;          ///< D / (1 + weakening * damage) [-]
  BendingModel bending_model = BendingModel::morley;    ///< "fit" or "morley"
  MembraneModel membrane_model = MembraneModel::chord;  ///< "chord" or "arc"
};

}  // namespace papersim::simulation
