#pragma once
/// The smooth surface scenegen renders through a sheet mesh's vertices: the modified butterfly
/// interpolating subdivision (Zorin, Schroeder and Sweldens 1996; C1 in the limit, also at
/// vertices of any valence), a few levels of it, with material coordinates carried exactly
/// (each new vertex takes its edge's UV midpoint, so UV stays linear in every original triangle)
/// so every ground-truth pass is exact for the surface actually rendered. The refined mesh
/// keeps the original vertices (same indices first) and the face orientation (positive UV area).
#include "scenegen/sheet_obj.hpp"

namespace papersim::scenegen {

/// Refinement of the render surface.
struct SurfaceParams {
  int level = 2;  ///< butterfly steps; 0: the mesh as it is; L: 4^L faces per original face
};

/// Largest accepted refinement level (level 4 is 256 faces per original face).
constexpr int MAX_SURFACE_LEVEL = 4;

/// `params.level` steps of the modified butterfly scheme. Interior edges: the 8-point stencil
/// (1/2, 1/8, -1/16) between regular vertices, Zorin's rule at an extraordinary vertex;
/// boundary edges: the four-point rule (corners of the UV outline keep straight sides).
/// @throw InputError when the level is outside [0, MAX_SURFACE_LEVEL]
SheetMesh refine_surface(const SheetMesh& mesh, const SurfaceParams& params);

/// The interpolating subdivision overshoots where the sheet leaves the table (a flat part
/// meeting a fold); points below the support plane would sink into the table and let it show
/// through the sheet. Vertices below the plane (point `origin`, unit normal `up`) are moved
/// onto it along `up` (UV unchanged). The rendered surface is lift_above_plane(refine_surface
/// (mesh), stage.origin, stage.up) with the stage of meta.json.
SheetMesh lift_above_plane(SheetMesh surface, const Eigen::Vector3d& origin,
                           const Eigen::Vector3d& up);

/// Shading normals of the refined surface's vertices: the mesh's area-weighted vertex normals
/// interpolated linearly at each refined vertex's material point (what the raw mesh's smooth
/// triangles show), normalised. #refined.V by 3. The refined surface's own facet normals wiggle
/// where the subdivision undulates, which moves the shading terminator; these do not.
/// @throw InputError when a refined vertex's UV is outside the mesh's UV domain
Eigen::MatrixX3d carried_normals(const SheetMesh& mesh, const SheetMesh& refined);

/// The sheet seen from its other side, as the reference's flipped samples: the mesh mirrored
/// (world x -> -x), u -> 1 - u, faces re-oriented so the printed side keeps a positive UV area.
/// A material point (x, y) of the result is the material point (width - x, y) of `mesh`.
SheetMesh flip_sheet(const SheetMesh& mesh);

}  // namespace papersim::scenegen
