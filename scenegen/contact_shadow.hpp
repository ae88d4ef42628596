#pragma once
/// Contact shadow of the sheet on the table: how much of the sky above each point of the table
/// the sheet hides (ambient occlusion, Zhukov et al. 1998 "obscurance"), computed by scenegen
/// from the rendered surface and multiplied into the table's lit colour in the photo scene.
/// Radiosity at the photo's settings is far too coarse to see a 0.3 mm gap, so without it a
/// sheet looks laid on the table rather than touching it (docs/scenegen.md, "Realism").
#include <string>
#include <vector>

#include "scenegen/image_io.hpp"
#include "scenegen/resting_pose.hpp"
#include "scenegen/sheet_obj.hpp"

namespace papersim::scenegen {

/// Settings of the occlusion map.
struct ContactParams {
  double cell = 5e-4;   ///< side of a map cell [m]
  double reach = 0.04;  ///< how far from a table point the sheet is looked for [m]
  int azimuths = 24;    ///< directions per table point
  double gap = 3e-4;    ///< the table lies this far below the support plane [m]
};

/// Settings for a sheet whose positions span `extent` [m] (the largest side of their bounding
/// box): the defaults for sheets up to 0.8 m; larger sheets get coarser cells (at most 1,600
/// across the sheet) and a reach of at least 80 cells, so the map's size and cost stay bounded
/// for every sheet the limits accept (up to 1,000 m).
ContactParams contact_params_for(double extent);

/// The sheet as a height field over the table: for each cell of a grid in the stage's (x, y)
/// plane, the lowest and highest height of the sheet above the table surface [m] among the
/// points of the sheet above the cell, +inf / -inf where no part of the sheet is above it.
/// Cell (i, j) spans x0 + [i, i + 1) cell, y0 + [j, j + 1) cell (stage coordinates [m]).
struct SheetHeightField {
  double x0 = 0.0, y0 = 0.0, cell = 1.0;  ///< [m]
  int width = 0, height = 0;              ///< [cells]
  std::vector<float> lo, hi;              ///< row-major, row j = y0 + j cell
  bool covered(int i, int j) const {
    return lo[std::size_t(j) * width + i] <= hi[std::size_t(j) * width + i];
  }
};

/// Rasterise `surface` (world positions [m]) over the stage's plane: cell centres inside a
/// triangle's projection take its interpolated height, and points along every edge (at half a
/// cell apart) are added too so that parts of the sheet standing steeply up still mark their
/// cells. Heights are measured from the table: stage height + params.gap. The grid covers the
/// sheet's projection plus params.reach on every side.
/// @throw InputError when the mesh is empty or the grid would exceed 4096 cells per side
SheetHeightField sheet_height_field(const SheetMesh& surface, const Stage& stage,
                                    const ContactParams& params);

/// Occlusion of the table by the sheet, one value per cell of `field` (row-major, row j at
/// y0 + j cell): the fraction of the cosine-weighted irradiance of a uniform sky that the sheet
/// blocks at the cell's centre, in [0, 1] (0: the whole sky is seen).
/// Along each of params.azimuths directions, marched out to params.reach, the sheet is taken as
/// a height field between its lowest and highest layer: a ray from the table at elevation phi
/// is blocked when tan(phi) lies between a = min(lo / r) and b = max(hi / r) over the cells it
/// passes (r the distance along the table), and the blocked part of the direction's cosine-
/// weighted half-disc is cos^2(atan a) - cos^2(atan b) = 1 / (1 + a^2) - 1 / (1 + b^2).
/// Deterministic: the same field gives the same values whatever `threads` (0: one per core).
std::vector<float> contact_occlusion(const SheetHeightField& field, const ContactParams& params,
                                     int threads = 0);

/// The occlusion as a 16-bit grey PNG of field.width x field.height, linear, row 0 = the
/// highest y (POV-Ray's image_map puts an image's bottom row at y = 0 of the unit square).
/// @throw common::OutputError
void write_contact_png(const std::string& path, const SheetHeightField& field,
                       const std::vector<float>& occlusion);

}  // namespace papersim::scenegen
