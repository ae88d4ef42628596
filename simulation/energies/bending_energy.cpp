#include "simulation/energies/bending_energy.hpp"

#include "simulation/energies/fit_bending_energy.hpp"
#include "simulation/energies/morley_bending_energy.hpp"

namespace papersim::simulation {

std::unique_ptr<BendingEnergy> make_bending_energy(const remesh::SheetMesh& mesh,
                                                   const Material& material,
                                                   BendingHessian hessian,
                                                   const std::vector<int>& clamped_faces) {
  if (material.bending_model == BendingModel::morley)
    return std::make_unique<MorleyBendingEnergy>(mesh, material, hessian, clamped_faces);
  return std::make_unique<FitBendingEnergy>(mesh, material, hessian);
}

}  // namespace papersim::simulation
