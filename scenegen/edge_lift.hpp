#pragma once
/// Edge curl of the rendered surface. Cut paper never lies perfectly flat: along its edges and
/// at its corners it curls up by a few tenths of a millimetre to a few millimetres, and the
/// thin wedge of shadow under that curl is the soft dark line a photo shows where a sheet
/// touches a table. Simulated sheets rest their flat parts exactly on the support plane, so
/// scenegen draws such a curl and adds it to the surface it renders: where the sheet rests
/// (a point at most a few millimetres above the table), points within a band along the sheet's
/// boundary (distance in material coordinates) are lifted along the table's normal by
///   amplitude * (1 - d / width)^2 * rest(h),
/// a constant-curvature curl (radius width^2 / (2 amplitude)) tangent to the table where it
/// starts, times rest(h) = 1 up to `rest_low` above the table and smoothly 0 from `rest_high`.
/// UV is unchanged, so the ground-truth passes stay exact for the surface rendered.
#include <Eigen/Core>

#include "scenegen/random.hpp"
#include "scenegen/smooth_surface.hpp"

namespace papersim::scenegen {

/// Drawn edge curl of a sheet. amplitude 0 turns it off.
struct EdgeLift {
  double amplitude = 0.0;   ///< lift at the boundary of a resting part [m]
  double width = 8e-3;      ///< band along the boundary that curls (material distance) [m]
  double rest_low = 1e-3;   ///< points at most this high above the table lift fully [m]
  double rest_high = 3e-3;  ///< points at least this high above the table do not lift [m]
};

/// Ranges of the drawn curl (office paper cut from a ream, lying on a table).
constexpr double EDGE_LIFT_AMPLITUDE_MIN = 0.5e-3;  ///< [m]
constexpr double EDGE_LIFT_AMPLITUDE_MAX = 2.0e-3;  ///< [m]
constexpr double EDGE_LIFT_WIDTH_MIN = 10e-3;       ///< [m]
constexpr double EDGE_LIFT_WIDTH_MAX = 25e-3;       ///< [m]

/// Amplitude U[0.5, 2.0] mm, width U[10, 25] mm (two draws from `rng`, in that order).
EdgeLift draw_edge_lift(Rng& rng);

/// `surface` with its edges curled as EdgeLift says (table plane through `origin`, unit normal
/// `up`). The lift at a vertex is at most half the free space above it (the first hit of the
/// sheet along `up`), so a curl under another layer of a folded sheet cannot reach it; it only
/// moves points up, so nothing goes below the table. With amplitude 0 the surface is returned
/// unchanged. @throw InputError when width <= 0, amplitude < 0 or rest_high <= rest_low
SheetMesh lift_edges(SheetMesh surface, const Eigen::Vector3d& origin, const Eigen::Vector3d& up,
                     const EdgeLift& lift);

/// Shading normals after a move of the surface: `normals` (#V by 3) turned by the change of the
/// surface's own vertex normals from `before` to `after` (same connectivity), normalised. Rows
/// whose faces did not move are returned bit for bit.
Eigen::MatrixX3d moved_normals(const Eigen::MatrixX3d& normals, const SheetMesh& before,
                               const SheetMesh& after);

/// The surface scenegen renders and its shading normals.
struct RenderedSurface {
  SheetMesh surface;         ///< lift_edges(lift_above_plane(refine_surface(mesh)))
  Eigen::MatrixX3d normals;  ///< moved_normals(carried_normals(mesh, refined and lifted), ...)
};

/// The rendered surface of `mesh` on the table plane (origin, up): refined at `params.level`,
/// lifted above the plane, its edges curled by `lift`. Every pass of a sample is of this surface.
RenderedSurface rendered_surface(const SheetMesh& mesh, const Eigen::Vector3d& origin,
                                 const Eigen::Vector3d& up, const SurfaceParams& params,
                                 const EdgeLift& lift);

}  // namespace papersim::scenegen
