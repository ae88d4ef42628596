#pragma once
/// Ground truth by ray casting: scenegen casts the camera's pixel-centre rays itself on the
/// triangles POV-Ray renders for the photo, instead of exact emissive POV-Ray renders (each of
/// which parses the whole mesh2 again). UV, world coordinates, normals and the mask of the
/// surface actually rendered come from one nearest hit per pixel.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "scenegen/camera.hpp"
#include "scenegen/image_io.hpp"
#include "scenegen/sheet_obj.hpp"

namespace papersim::scenegen {

/// The nearest hit of each pixel-centre ray with a mesh (row-major, row 0 at the top).
struct PixelHits {
  int width = 0, height = 0;            ///< [pixels]
  std::vector<int> face;                ///< face index per pixel, -1 where the ray misses
  std::vector<Eigen::Vector2d> weight;  ///< barycentric weights of the face's corners 1 and 2
                                        ///< (corner 0 has 1 - their sum)
};

/// The sheet as POV-Ray holds a mesh2: vertex positions rounded to single precision (POV-Ray
/// stores mesh2 vertices and normals as floats), UV unchanged. `normals` (#V by 3) are rounded
/// the same way in place.
SheetMesh povray_precision(const SheetMesh& mesh, Eigen::MatrixX3d& normals);

/// Cast the ray through every pixel centre (i + 0.5, j + 0.5) of `camera` (the pinhole of the
/// POV-Ray camera scenegen writes, Camera::ray) and keep the nearest hit with a face of `mesh`
/// (Moller-Trumbore in double precision, edges included; equal distances keep the lower face
/// index). A z-buffer over each face's projected bounding box (1 pixel of slack); the rows are
/// split over `threads` threads (0: one per core) and the result does not depend on how many.
PixelHits cast_pixel_rays(const SheetMesh& mesh, const Camera& camera, int threads = 0);

/// UV pass: R = u, G = v (interpolated from the hit face's corners), B = mask (1 on the sheet);
/// 0 off the sheet. @throw InputError when the hits are not of this mesh
ImageF uv_from_hits(const PixelHits& hits, const SheetMesh& mesh);

/// World coordinates [m] of each hit point, 0 off the sheet.
ImageF coords_from_hits(const PixelHits& hits, const SheetMesh& mesh);

/// Shading normals: the corners' `normals` (#V by 3) interpolated with the hit's weights,
/// normalised and turned towards the camera (as POV-Ray turns them for a ray that meets the
/// back side); 0 off the sheet.
ImageF normals_from_hits(const PixelHits& hits, const SheetMesh& mesh,
                         const Eigen::MatrixX3d& normals, const Camera& camera);

/// Write #V unit vertex normals as text (one "x y z" line per vertex, 17 digits).
/// @throw common::OutputError
void write_vertex_normals(const std::string& path, const Eigen::MatrixX3d& normals);

/// Read what write_vertex_normals wrote. @throw IoError when the file cannot be read, is cut
/// short or does not hold `count` finite normals
Eigen::MatrixX3d read_vertex_normals(const std::string& path, int count);

}  // namespace papersim::scenegen
