#pragma once
/// Synthetic sheets with exact material UV, for tests, benchmarks and trying scenegen without
/// the simulator: flat, bent on a cylinder, folded along a line, with a bump.
#include <string>

#include "scenegen/sheet_obj.hpp"

namespace papersim::scenegen {

/// Parameters of an example sheet.
struct ExampleSheetParams {
  double width = 0.210;           ///< [m]
  double height = 0.297;          ///< [m]
  int nx = 36, ny = 50;           ///< grid vertices along x and y
  double cylinder_radius = 0.15;  ///< [m] (cylinder)
  double fold_angle_deg = 60.0;   ///< rotation of the flap (fold; 175 folds it over)
  double fold_x = 0.04;           ///< fold line, material x from the centre [m]
  double fold_radius = 0.004;     ///< crease radius [m]
  double bump_height = 0.02;      ///< [m] (bump)
  double bump_sigma = 0.04;       ///< [m]
};

/// kind: flat | cylinder | fold | bump. Isometric except the bump. Sheet centred at the
/// origin, long side along y, resting on z = 0 (z up). @throw InputError for an unknown kind.
SheetMesh make_example_sheet(const std::string& kind, const ExampleSheetParams& params = {});

}  // namespace papersim::scenegen
