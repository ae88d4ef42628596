#pragma once
/// Obstacles as OpenVDB narrow-band level sets: the general path for any closed triangle mesh
/// and for the primitives (OpenVDB types stay in the .cpp; this header is cheap to include).
///
/// Query: trilinear interpolation of the voxel samples; the gradient is the derivative of that
/// interpolant, normalised. Inside the narrow band (|phi| < (N - sqrt 3) h, N the half width in
/// voxels, h the voxel size) the value is the interpolated field. Farther away the grid holds no
/// sample and the query returns a bound instead: outside, max((N - sqrt 3) h, distance to the
/// surface's bounding box), a lower bound on the true distance (still conservative for CCD);
/// inside, -(N - sqrt 3) h. There the gradient points away from the bounding-box centre (it
/// only matters where phi < contact thickness, which the band covers).
///
/// Accuracy: the interpolant is a weighted mean of exact samples, so |phi_grid - phi| <=
/// (sqrt 3 / 2) h everywhere in the band (error_bound()); measured maxima are 0.01-0.05 h on
/// spheres and capsules and 0.25-0.4 h next to sharp edges (box, cylinder rim, gable ridge),
/// where the grid overestimates the outside distance by up to 0.25 h. A solver that must never
/// let a vertex inside should keep phi_grid > error_bound() or use the exact analytic field
/// (AnalyticCollider, the factory's default for primitives).
#include <cstddef>
#include <memory>
#include <string>

#include "collision/collider.hpp"
#include "collision/shapes.hpp"
#include "collision/triangle_mesh.hpp"

namespace papersim::collision {

/// How a level set is resolved.
struct LevelSetParams {
  /// Voxel edge [m]; <= 0 selects min(smallest feature / 8, contact_thickness).
  double voxel_size = 0.0;
  /// The sheet's contact distance dhat [m]: distances below it must be accurate.
  double contact_thickness = 1e-3;
  /// Extra distance beyond contact_thickness over which the field must be exact, e.g. the
  /// largest motion of a vertex in one step [m]. Beyond it queries return the band bound.
  double reach = 1e-3;
  /// Smallest narrow-band half width [voxels]; the band used is
  /// N = max(min_band_voxels, ceil((contact_thickness + reach) / h + sqrt 3)).
  int min_band_voxels = 3;
  /// Refuse to build grids with more active voxels than this (about 4 bytes each) [-].
  std::size_t max_active_voxels = 60'000'000;
};

/// A signed distance field sampled on a sparse OpenVDB grid in the collider's local frame.
/// Immutable after construction; queries are thread-safe (each query uses its own unsafe,
/// unregistered value accessor: a few pointers on the stack, no locking).
class LevelSetCollider : public Collider {
 public:
  /// Samples the exact signed distance of `shape` at every voxel of the narrow band (analytic
  /// fill, see the .cpp for why).
  /// @throw ColliderError for an invalid shape or parameter, an inverted sphere (unbounded
  ///        solid), or a grid above max_active_voxels.
  static std::unique_ptr<LevelSetCollider> from_shape(const Shape& shape,
                                                      const LevelSetParams& params = {});
  /// Builds the level set of a closed triangle mesh with openvdb::tools::meshToLevelSet.
  /// `name` is used in error messages. Automatic voxel size: smallest bounding-box extent / 8,
  /// capped by contact_thickness.
  /// @throw ColliderError when the mesh is not closed, a parameter is invalid or the grid
  ///        would exceed max_active_voxels.
  static std::unique_ptr<LevelSetCollider> from_mesh(const TriangleMesh& mesh,
                                                     const LevelSetParams& params = {},
                                                     const std::string& name = "mesh");
  /// read_obj + from_mesh, with the vertices scaled by `scale` [-] first.
  /// @throw ColliderIoError for an unreadable or open mesh; ColliderError as from_mesh.
  static std::unique_ptr<LevelSetCollider> from_obj(const std::string& path,
                                                    const LevelSetParams& params = {},
                                                    double scale = 1.0);

  ~LevelSetCollider() override;
  LevelSetCollider(const LevelSetCollider&) = delete;
  LevelSetCollider& operator=(const LevelSetCollider&) = delete;

  /// Voxel edge h [m].
  double voxel_size() const;
  /// Narrow-band half width N h [m].
  double band_width() const;
  /// Distance up to which queries interpolate the grid, (N - sqrt 3) h [m]; beyond it they
  /// return bounds (see the file comment).
  double exact_range() const;
  /// Bound on |phi_grid - phi_exact| inside the band: (sqrt 3 / 2) h [m].
  double error_bound() const;
  /// Number of active voxels and the grid's memory [bytes].
  std::size_t active_voxel_count() const;
  std::size_t memory_bytes() const;

 protected:
  double local_distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient) const override;
  Aabb local_bounds() const override;

 private:
  struct Grid;  // holds the openvdb::FloatGrid
  explicit LevelSetCollider(std::unique_ptr<Grid> grid, const Aabb& surface_bounds);
  /// The bound returned outside the band (see file comment).
  double far_field(const Eigen::Vector3d& p, bool inside, Eigen::Vector3d* gradient) const;

  std::unique_ptr<Grid> m_grid;
  Aabb m_surface_bounds;
};

}  // namespace papersim::collision
