#include "collision/level_set_collider.hpp"

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <sstream>

#include "collision/errors.hpp"
#include "common/format.hpp"

namespace papersim::collision {

namespace {

using FloatTree = openvdb::FloatTree;
using LeafT = FloatTree::LeafNodeType;
/// Not registered with the tree (IsSafe = false): constructing one per query costs a few
/// stores, and concurrent readers never touch shared state.
using ConstAccessor = openvdb::tree::ValueAccessor<const FloatTree, false>;

const double SQRT3 = std::sqrt(3.0);

/// Voxel size h [m] and narrow-band half width n [voxels].
struct Resolution {
  double h = 0.0;
  int n = 0;
};

void require(bool ok, const std::string& what) {
  if (!ok) throw ColliderError("level set: " + what);
}

Resolution resolve(const LevelSetParams& p, double smallest_feature) {
  require(std::isfinite(p.voxel_size), "voxel_size must be finite");
  require(std::isfinite(p.contact_thickness) && p.contact_thickness > 0.0,
          "contact_thickness must be > 0, got " + common::format_number(p.contact_thickness));
  require(std::isfinite(p.reach) && p.reach >= 0.0,
          "reach must be >= 0, got " + common::format_number(p.reach));
  require(p.min_band_voxels >= 2,
          "min_band_voxels must be >= 2, got " + std::to_string(p.min_band_voxels));
  Resolution r;
  r.h = p.voxel_size > 0.0 ? p.voxel_size : std::min(smallest_feature / 8.0, p.contact_thickness);
  require(r.h > 0.0, "voxel size must be > 0, got " + common::format_number(r.h));
  const double needed = std::ceil((p.contact_thickness + p.reach) / r.h + SQRT3);
  r.n = std::max(p.min_band_voxels, static_cast<int>(needed));
  return r;
}

/// A narrow band holds about area / h^2 * 2 n active voxels: refuse before allocating.
void check_budget(double area, const Resolution& r, std::size_t max_active) {
  const double estimate = area / (r.h * r.h) * 2.0 * r.n;
  if (estimate > static_cast<double>(max_active)) {
    std::ostringstream os;
    os << "level set: voxel size " << r.h << " m with a band of " << r.n << " voxels gives about "
       << estimate << " active voxels, more than max_active_voxels = " << max_active
       << "; raise voxel_size";
    throw ColliderError(os.str());
  }
}

openvdb::FloatGrid::Ptr empty_level_set(const Resolution& r) {
  static std::once_flag init;
  std::call_once(init, [] { openvdb::initialize(); });
  auto grid = openvdb::FloatGrid::create(static_cast<float>(r.n * r.h));
  grid->setTransform(openvdb::math::Transform::createLinearTransform(r.h));
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  return grid;
}

/// One 8^3 leaf of exact samples, or null when the leaf holds no band voxel. Leaves whose
/// centre is farther than band + half diagonal from the surface are skipped without sampling
/// (the SDF is 1-Lipschitz).
LeafT* sample_leaf(const Shape& s, const openvdb::Coord& origin, const Resolution& r) {
  const double band = r.n * r.h;
  const double half = 0.5 * (LeafT::DIM - 1);
  const Eigen::Vector3d centre =
      r.h * Eigen::Vector3d(origin.x() + half, origin.y() + half, origin.z() + half);
  if (std::abs(shape_distance(s, centre, nullptr)) >= band + half * SQRT3 * r.h) return nullptr;
  const float bg = static_cast<float>(band);
  auto leaf = std::make_unique<LeafT>(origin, bg, false);
  bool any_active = false;
  for (openvdb::Index i = 0; i < LeafT::SIZE; ++i) {
    const openvdb::Coord ijk = leaf->offsetToGlobalCoord(i);
    const double d = shape_distance(s, r.h * Eigen::Vector3d(ijk.x(), ijk.y(), ijk.z()), nullptr);
    if (std::abs(d) < band) {
      leaf->setValueOn(i, static_cast<float>(d));
      any_active = true;
    } else {
      leaf->setValueOff(i, d > 0.0 ? bg : -bg);
    }
  }
  return any_active ? leaf.release() : nullptr;
}

/// Why analytic fill rather than meshToLevelSet of a fine triangulation: every sample is the
/// exact distance (no tessellation error on curved surfaces, sharp ridges stay sharp at the
/// samples), it needs no triangulation code per primitive, and it is embarrassingly parallel
/// over leaves. The band test per leaf keeps the cost proportional to the surface area.
openvdb::FloatGrid::Ptr fill_band(const Shape& s, const Resolution& r) {
  Aabb box = shape_bounds(s);
  box.inflate((r.n + 1) * r.h);
  const int dim = LeafT::DIM;
  auto leaf_floor = [&](double x) {
    return static_cast<int>(std::floor(std::floor(x / r.h) / dim)) * dim;
  };
  const openvdb::Coord lo(leaf_floor(box.lo.x()), leaf_floor(box.lo.y()), leaf_floor(box.lo.z()));
  const openvdb::Coord hi(leaf_floor(box.hi.x()), leaf_floor(box.hi.y()), leaf_floor(box.hi.z()));
  const std::size_t nx = (hi.x() - lo.x()) / dim + 1, ny = (hi.y() - lo.y()) / dim + 1,
                    nz = (hi.z() - lo.z()) / dim + 1;
  std::vector<LeafT*> leaves(nx * ny * nz, nullptr);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t k = range.begin(); k != range.end(); ++k) {
                        const openvdb::Coord origin(lo.x() + dim * int(k % nx),
                                                    lo.y() + dim * int((k / nx) % ny),
                                                    lo.z() + dim * int(k / (nx * ny)));
                        leaves[k] = sample_leaf(s, origin, r);
                      }
                    });
  openvdb::FloatGrid::Ptr grid = empty_level_set(r);
  // the tree takes ownership
  for (LeafT* leaf : leaves)
    if (leaf) grid->tree().addLeaf(leaf);
  openvdb::tools::signedFloodFill(grid->tree());
  return grid;
}

double mesh_smallest_feature(const TriangleMesh& mesh) {
  const Aabb b = mesh_bounds(mesh);
  return (b.hi - b.lo).minCoeff();
}

}  // namespace

struct LevelSetCollider::Grid {
  openvdb::FloatGrid::Ptr grid;
  double h = 0.0;      ///< voxel size [m]
  double band = 0.0;   ///< n h [m]
  double exact = 0.0;  ///< (n - sqrt 3) h [m]
};

LevelSetCollider::LevelSetCollider(std::unique_ptr<Grid> grid, const Aabb& surface_bounds)
    : m_grid(std::move(grid)), m_surface_bounds(surface_bounds) {}

LevelSetCollider::~LevelSetCollider() = default;

std::unique_ptr<LevelSetCollider> LevelSetCollider::from_shape(const Shape& shape,
                                                               const LevelSetParams& params) {
  validate(shape);
  if (shape.kind == ShapeKind::inverted_sphere)
    throw ColliderError(
        "level set: an inverted sphere has an unbounded solid; use its analytic field");
  const Resolution r = resolve(params, shape_smallest_feature(shape));
  check_budget(shape_surface_area(shape), r, params.max_active_voxels);
  auto grid = std::make_unique<Grid>();
  grid->grid = fill_band(shape, r);
  grid->h = r.h;
  grid->band = r.n * r.h;
  grid->exact = (r.n - SQRT3) * r.h;
  return std::unique_ptr<LevelSetCollider>(
      new LevelSetCollider(std::move(grid), shape_bounds(shape)));
}

std::unique_ptr<LevelSetCollider> LevelSetCollider::from_mesh(const TriangleMesh& mesh,
                                                              const LevelSetParams& params,
                                                              const std::string& name) {
  check_closed(mesh, name);
  const Resolution r = resolve(params, mesh_smallest_feature(mesh));
  check_budget(mesh_area(mesh), r, params.max_active_voxels);
  std::vector<openvdb::Vec3s> points;
  points.reserve(mesh.vertices.size());
  for (const Eigen::Vector3d& v : mesh.vertices) points.emplace_back(v.x(), v.y(), v.z());
  std::vector<openvdb::Vec3I> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  openvdb::FloatGrid::Ptr vdb = empty_level_set(r);
  vdb = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(vdb->transform(), points, triangles,
                                                           static_cast<float>(r.n));
  auto grid = std::make_unique<Grid>();
  grid->grid = vdb;
  grid->h = r.h;
  grid->band = r.n * r.h;
  grid->exact = (r.n - SQRT3) * r.h;
  return std::unique_ptr<LevelSetCollider>(
      new LevelSetCollider(std::move(grid), mesh_bounds(mesh)));
}

std::unique_ptr<LevelSetCollider> LevelSetCollider::from_obj(const std::string& path,
                                                             const LevelSetParams& params,
                                                             double scale) {
  if (!(std::isfinite(scale) && scale > 0.0))
    throw ColliderError("mesh '" + path + "': scale must be > 0, got " +
                        common::format_number(scale));
  TriangleMesh mesh = read_obj(path);
  for (Eigen::Vector3d& v : mesh.vertices) v *= scale;
  try {
    check_closed(mesh, path);
  } catch (const ColliderError& e) {
    throw ColliderIoError(e.what());
  }
  return from_mesh(mesh, params, path);
}

double LevelSetCollider::voxel_size() const { return m_grid->h; }
double LevelSetCollider::band_width() const { return m_grid->band; }
double LevelSetCollider::exact_range() const { return m_grid->exact; }
double LevelSetCollider::error_bound() const { return 0.5 * SQRT3 * m_grid->h; }
std::size_t LevelSetCollider::active_voxel_count() const {
  return static_cast<std::size_t>(m_grid->grid->activeVoxelCount());
}
std::size_t LevelSetCollider::memory_bytes() const {
  return static_cast<std::size_t>(m_grid->grid->memUsage());
}

Aabb LevelSetCollider::local_bounds() const { return m_surface_bounds; }

double LevelSetCollider::far_field(const Eigen::Vector3d& p, bool inside,
                                   Eigen::Vector3d* gradient) const {
  const Eigen::Vector3d centre = 0.5 * (m_surface_bounds.lo + m_surface_bounds.hi);
  const Eigen::Vector3d nearest = p.cwiseMax(m_surface_bounds.lo).cwiseMin(m_surface_bounds.hi);
  if (gradient) {
    Eigen::Vector3d dir =
        (!inside && nearest != p) ? Eigen::Vector3d(p - nearest) : Eigen::Vector3d(p - centre);
    const double n = dir.norm();
    *gradient = n > 0.0 ? Eigen::Vector3d(dir / n) : Eigen::Vector3d::UnitZ();
  }
  if (inside) return -m_grid->exact;
  return std::max(m_grid->exact, (p - nearest).norm());
}

// Trilinear interpolation of the 8 samples around p and its exact derivative; a corner outside
// the band means |phi(p)| >= (n - sqrt 3) h, so the far-field bound is returned instead.
double LevelSetCollider::local_distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient) const {
  const double h = m_grid->h;
  const Eigen::Vector3d x = p / h;
  const Eigen::Vector3d base = x.array().floor();
  const Eigen::Vector3d f = x - base;
  if (!base.allFinite() || base.cwiseAbs().maxCoeff() > 1e9) return far_field(p, false, gradient);
  const openvdb::Coord c0(static_cast<int>(base.x()), static_cast<int>(base.y()),
                          static_cast<int>(base.z()));
  ConstAccessor acc(m_grid->grid->constTree());
  double value = 0.0;
  Eigen::Vector3d grad = Eigen::Vector3d::Zero();
  for (int corner = 0; corner < 8; ++corner) {
    const int i = corner & 1, j = (corner >> 1) & 1, k = (corner >> 2) & 1;
    float v;
    if (!acc.probeValue(c0.offsetBy(i, j, k), v)) return far_field(p, v < 0.0f, gradient);
    const double wx = i ? f.x() : 1.0 - f.x(), wy = j ? f.y() : 1.0 - f.y(),
                 wz = k ? f.z() : 1.0 - f.z();
    value += wx * wy * wz * v;
    grad.x() += (i ? 1.0 : -1.0) * wy * wz * v;
    grad.y() += (j ? 1.0 : -1.0) * wx * wz * v;
    grad.z() += (k ? 1.0 : -1.0) * wx * wy * v;
  }
  if (gradient) {
    const double n = grad.norm();
    if (n > 0.0) {
      *gradient = grad / n;
    } else {
      far_field(p, value < 0.0, gradient);
    }
  }
  return value;
}

}  // namespace papersim::collision
