#pragma once
/// Stated limits of scenegen, checked before any work starts (docs/scenegen.md, "Limits").
namespace papersim::scenegen {

constexpr int MAX_IMAGE_SIDE = 8192;         ///< --size and --backward-grid, per side [pixels]
constexpr long MAX_MESH_VERTICES = 250'000;  ///< vertices of the sheet OBJ
constexpr long MAX_MESH_FACES = 500'000;  ///< triangles of the sheet OBJ (after splitting polygons)
/// |x|, |y|, |z| of a vertex and the header's size [m]
constexpr double MAX_MESH_COORDINATE = 1e3;
constexpr double MIN_SHEET_SIZE = 1e-4;  ///< smallest sheet width / height [m]
constexpr int MAX_DOCUMENT_SIDE = 8192;  ///< built-in page raster, per side [pixels]
constexpr double MAX_DPI = 1200.0;       ///< --dpi
constexpr int MAX_PROCESSES = 1024;      ///< --threads and --parallel

}  // namespace papersim::scenegen
