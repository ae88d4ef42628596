/// Throughput of collider queries (distance + gradient) and level-set build times.
/// Run: build-collision/collision/collider_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <map>
#include <memory>
#include <random>
#include <vector>

#include "collision/collider_factory.hpp"
#include "collision/level_set_collider.hpp"
#include "collision/shapes.hpp"
#include "collision/triangle_mesh.hpp"

namespace pc = papersim::collision;

namespace {

enum Case { PLANE, ANALYTIC_SPHERE, VDB_SPHERE, ANALYTIC_GABLE, VDB_GABLE, MESH };
const char* const CASE_NAMES[] = {"plane",          "analytic_sphere", "vdb_sphere",
                                  "analytic_gable", "vdb_gable",       "mesh_icosphere"};

pc::Shape sphere_shape() {
  pc::Shape s;
  s.kind = pc::ShapeKind::sphere;
  s.radius = 0.05;
  return s;
}

pc::Shape gable_shape() {
  pc::Shape s;
  s.kind = pc::ShapeKind::gable;
  s.half_width = s.height = 0.05;
  s.length = 0.3;
  return s;
}

/// Icosphere of radius r subdivided `levels` times (20 * 4^levels triangles).
pc::TriangleMesh icosphere(double r, int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  pc::TriangleMesh m;
  for (const auto& v : std::vector<Eigen::Vector3d>{{-1, t, 0},
                                                    {1, t, 0},
                                                    {-1, -t, 0},
                                                    {1, -t, 0},
                                                    {0, -1, t},
                                                    {0, 1, t},
                                                    {0, -1, -t},
                                                    {0, 1, -t},
                                                    {t, 0, -1},
                                                    {t, 0, 1},
                                                    {-t, 0, -1},
                                                    {-t, 0, 1}})
    m.vertices.push_back(v.normalized());
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.vertices.push_back((m.vertices[a] + m.vertices[b]).normalized());
      return mid[key] = static_cast<int>(m.vertices.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    for (const Eigen::Vector3i& f : m.triangles) {
      const int a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.insert(next.end(), {{f[0], a, c}, {f[1], b, a}, {f[2], c, b}, {a, b, c}});
    }
    m.triangles = std::move(next);
  }
  for (Eigen::Vector3d& v : m.vertices) v *= r;
  return m;
}

std::unique_ptr<pc::Collider> make(Case c) {
  switch (c) {
    case PLANE:
      return std::make_unique<pc::PlaneCollider>();
    case ANALYTIC_SPHERE:
      return std::make_unique<pc::AnalyticCollider>(sphere_shape());
    case VDB_SPHERE:
      return pc::LevelSetCollider::from_shape(sphere_shape());
    case ANALYTIC_GABLE:
      return std::make_unique<pc::AnalyticCollider>(gable_shape());
    case VDB_GABLE:
      return pc::LevelSetCollider::from_shape(gable_shape());
    case MESH:
      return pc::LevelSetCollider::from_mesh(icosphere(0.05, 5));
  }
  return nullptr;
}

/// Points within +-3 mm of the surface (the contact regime) plus 20% farther away.
std::vector<Eigen::Vector3d> query_points(const pc::Collider& c, std::size_t n) {
  std::mt19937 rng(1);
  pc::Aabb b = c.bounds(0.0);
  b.lo = b.lo.cwiseMax(Eigen::Vector3d::Constant(-0.2));
  b.hi = b.hi.cwiseMin(Eigen::Vector3d::Constant(0.2));
  b.inflate(0.01);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3d> points;
  while (points.size() < n) {
    const Eigen::Vector3d p =
        b.lo + (b.hi - b.lo).cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng)));
    const double d = c.distance(p, 0.0);
    if (std::abs(d) < 3e-3 || points.size() % 5 == 0) points.push_back(p);
  }
  return points;
}

struct Fixture {
  std::unique_ptr<pc::Collider> collider;
  std::vector<Eigen::Vector3d> points;
};

Fixture& fixture(Case c) {
  static std::map<Case, Fixture> cache;
  Fixture& f = cache[c];
  if (!f.collider) {
    f.collider = make(c);
    f.points = query_points(*f.collider, 1 << 16);
  }
  return f;
}

void query_single(benchmark::State& state) {
  Fixture& f = fixture(static_cast<Case>(state.range(0)));
  state.SetLabel(CASE_NAMES[state.range(0)]);
  const Eigen::Affine3d pose = f.collider->motion.pose(0.0);
  std::size_t i = 0;
  Eigen::Vector3d g;
  for (auto _ : state) {
    const double d = f.collider->distance_at_pose(f.points[i++ & 0xffff], pose, &g);
    benchmark::DoNotOptimize(d);
    benchmark::DoNotOptimize(g);
  }
  state.SetItemsProcessed(state.iterations());
}

/// The public time-based entry point (keyframe search + pose per call).
void query_single_with_time(benchmark::State& state) {
  Fixture& f = fixture(static_cast<Case>(state.range(0)));
  state.SetLabel(CASE_NAMES[state.range(0)]);
  std::size_t i = 0;
  Eigen::Vector3d g;
  for (auto _ : state) {
    const double d = f.collider->distance(f.points[i++ & 0xffff], 0.0, &g);
    benchmark::DoNotOptimize(d);
  }
  state.SetItemsProcessed(state.iterations());
}

/// All points per iteration with tbb::parallel_for over every available core.
void query_parallel(benchmark::State& state) {
  Fixture& f = fixture(static_cast<Case>(state.range(0)));
  state.SetLabel(CASE_NAMES[state.range(0)]);
  const Eigen::Affine3d pose = f.collider->motion.pose(0.0);
  std::vector<double> out(f.points.size());
  for (auto _ : state) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, f.points.size(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        Eigen::Vector3d g;
                        for (std::size_t i = r.begin(); i != r.end(); ++i)
                          out[i] = f.collider->distance_at_pose(f.points[i], pose, &g) + g.x();
                      });
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * f.points.size());
}

void build_shape(benchmark::State& state) {
  const pc::Shape s = state.range(0) == 0 ? sphere_shape() : gable_shape();
  pc::LevelSetParams params;
  params.voxel_size = state.range(1) * 1e-4;
  std::size_t voxels = 0;
  for (auto _ : state) voxels = pc::LevelSetCollider::from_shape(s, params)->active_voxel_count();
  state.SetLabel(std::string(state.range(0) == 0 ? "sphere r=5cm" : "gable 10x5x30cm") +
                 ", h=" + std::to_string(state.range(1) / 10.0) + "mm");
  state.counters["active_voxels"] = static_cast<double>(voxels);
}

void build_mesh(benchmark::State& state) {
  const pc::TriangleMesh mesh = icosphere(0.05, static_cast<int>(state.range(0)));
  pc::LevelSetParams params;
  params.voxel_size = 1e-3;
  std::size_t voxels = 0;
  for (auto _ : state) voxels = pc::LevelSetCollider::from_mesh(mesh, params)->active_voxel_count();
  state.SetLabel("icosphere r=5cm, " + std::to_string(mesh.triangles.size()) + " triangles, h=1mm");
  state.counters["active_voxels"] = static_cast<double>(voxels);
}

}  // namespace

BENCHMARK(query_single)->DenseRange(PLANE, MESH);
BENCHMARK(query_single_with_time)->Arg(PLANE)->Arg(VDB_SPHERE);
BENCHMARK(query_parallel)->DenseRange(PLANE, MESH)->UseRealTime();
BENCHMARK(build_shape)
    ->Args({0, 10})
    ->Args({0, 5})
    ->Args({1, 10})
    ->Args({1, 5})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(build_mesh)->Arg(3)->Arg(5)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
