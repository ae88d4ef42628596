#pragma once
/// Turning POV-Ray's raw 16-bit renders into the float passes, and the backward map.
#include <Eigen/Core>
#include <string>

#include "scenegen/camera.hpp"
#include "scenegen/image_io.hpp"
#include "scenegen/sheet_obj.hpp"

namespace papersim::scenegen {

/// Encoding factor of u, v in the UV render (keeps values below 1: pattern values wrap at 1).
constexpr double UV_ENCODING = 1.0 - 1.0 / 65536.0;
/// Fine renders hold frac(FINE_FACTOR * value).
constexpr double FINE_FACTOR = 256.0;

/// Combine a coarse 16-bit value c (of e) and a fine one f (of frac(256 e)) into e.
double combine_fine(double coarse, double fine);

/// UV pass from raw_uv.png (and raw_uv_fine.png when `fine_path` is not empty):
/// 3 channels u, v, mask; u = v = 0 where mask = 0. @throw IoError
ImageF decode_uv(const std::string& coarse_path, const std::string& fine_path);
/// World coordinates [m] from raw_coords(.png, _fine.png), zero outside `mask` (1 channel).
ImageF decode_coords(const std::string& coarse_path, const std::string& fine_path,
                     const Eigen::Vector3d& coords_min, double coords_span, const ImageF& mask);
/// Unit world normals turned towards the camera (slope pattern: v = 0.5 + asin(n.d) / pi).
ImageF decode_normal(const std::string& path, const ImageF& mask);
/// A linear 16-bit render as an image of linear values (3 channels).
ImageF decode_linear(const std::string& path);

/// Natural vignetting of the camera (an ideal lens): linear radiance falls off as cos^4 of the
/// angle between a pixel's ray and the optical axis (0.70 in the corners of a 50 mm lens on a
/// 36 mm sensor). Multiplies the linear channels of `linear` in place.
void apply_vignetting(ImageF& linear, const Camera& camera);

/// Backward-map parameters.
struct BackwardParams {
  int grid_width = 121;           ///< points across the page (u), 0: the render width
  int grid_height = 177;          ///< points down the page (v), 0: the render height
  double tolerance_pixels = 1.5;  ///< occlusion test: material distance in pixel footprints
};

/// Backward map: for grid point (c, r) of the flat page (u = c / (W - 1), v = 1 - r / (H - 1),
/// row 0 = top of the page) the pixel coordinates (x, y) where it appears (pixel centres at
/// i + 0.5) and a visibility flag: the point is in the frame and it is what the UV render sees
/// at that pixel (material distance below tolerance), so occlusion comes from the render.
/// Channels x, y, visible. Grid points outside the sheet's UV domain: (0, 0, 0).
ImageF backward_map(const SheetMesh& mesh, const Camera& camera, const ImageF& uv_pass,
                    const BackwardParams& params);

/// Sample channel-interleaved `image` bilinearly at pixel coordinates (x, y) (centres at
/// i + 0.5), using only pixels with mask > 0.5 (weights renormalised). False when none.
bool sample_masked(const ImageF& image, const ImageF& mask, double x, double y, float* out);

/// Apply a backward map to an image: the flat page (grid size), invisible points zero.
ImageF unwarp(const ImageF& image, const ImageF& mask, const ImageF& backward);

}  // namespace papersim::scenegen
