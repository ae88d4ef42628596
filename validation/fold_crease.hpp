#pragma once
// The plastic crease along a known fold line, measured the same way on any mesh (uniform or
// remeshed): the residual rest angle across the line, piece by piece along it.
#include <Eigen/Core>

namespace papersim::validation {

/// A straight fold line in material space: through `centre`, perpendicular to the unit vector
/// `d` (the direction across the fold), `chord` long (the part inside the sheet).
struct FoldLine {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  Eigen::Vector2d d = Eigen::Vector2d::UnitX();
  double chord = 0.0;  ///< [m]
};

/// The line through `centre` perpendicular to `d` (normalised here), clipped to the rectangle
/// [0, width] x [0, height] that contains `centre`.
FoldLine fold_line_in_rectangle(const Eigen::Vector2d& centre, const Eigen::Vector2d& d,
                                double width, double height);

/// The straight line that best fits the plastic crease near `nominal`: the faces whose material
/// centroid lies within `search` of the nominal line, each weighted by its area times the square
/// of its plastic curvature's largest principal value, give a weighted centroid and principal
/// axis; the line runs through the centroid along that axis (its normal d on the side of the
/// nominal d), clipped to the rectangle [0, width] x [0, height]. Where the sheet actually
/// folded can lie some centimetres from, and turned against, the line a scenario aims at. With
/// no plastic curvature near the line, returns `nominal`.
FoldLine fit_crease_line(const Eigen::MatrixX2d& material_coords, const Eigen::MatrixX3i& faces,
                         const Eigen::MatrixX3d& plastic_curvature, const FoldLine& nominal,
                         double width, double height, double search = 0.05);

struct FoldCreaseOptions {
  double threshold =
      0.5235987755982988;  ///< rest angle a piece must exceed to be creased [rad] (30 deg)
  double band = 0.02;      ///< half-width of the band about the line [m]
  double piece = 0.01;     ///< length the line is cut into (rounded to divide the chord) [m]
};

struct FoldCrease {
  int lines = 0;          ///< runs of consecutive creased pieces
  double longest = 0.0;   ///< longest run [m]
  double creased = 0.0;   ///< total length of the creased pieces [m]
  double angle = 0.0;     ///< mean rest angle of the creased pieces [rad]
  double mean_all = 0.0;  ///< mean rest angle over the whole line [rad]
};

/// Each piece's rest angle is the plastic normal curvature across the line, d^T Kp d (Kp rows
/// kxx, kyy, kxy per face, as SheetMesh stores it), integrated over the faces whose material
/// centroid lies within `band` of the line and beside the piece, divided by the piece's length;
/// its absolute value is compared with the threshold. Unlike the plastic network of
/// compute_metrics, which thresholds each edge's own rest angle, this does not split a crease
/// that remeshing has spread over several thin faces.
FoldCrease measure_fold_crease(const Eigen::MatrixX2d& material_coords,
                               const Eigen::MatrixX3i& faces,
                               const Eigen::MatrixX3d& plastic_curvature, const FoldLine& line,
                               const FoldCreaseOptions& options = {});

}  // namespace papersim::validation
