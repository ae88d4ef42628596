#include "validation/metrics.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "collision/self_intersection.hpp"
#include "remesh/sheet_io.hpp"

namespace papersim::validation {
namespace {

constexpr double PI = 3.14159265358979323846;
constexpr double DEG = PI / 180.0;

Eigen::Vector3d world(const Eigen::MatrixX3d& positions, int v) {
  return positions.row(v).transpose();
}

Eigen::Vector2d material(const Eigen::MatrixX2d& material_coords, int v) {
  return material_coords.row(v).transpose();
}

/// Angle between two vectors [rad], accurate near 0 and pi.
double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

/// The q-quantile (0..1) of values, by partial sort of a copy; 0 for no values.
double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size())));
  const std::size_t index = std::min(values.size() - 1, k == 0 ? 0 : k - 1);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(index),
                   values.end());
  return values[index];
}

/// At most max_count values of `values`, evenly strided.
template <class Get>
std::vector<double> strided(Eigen::Index count, std::size_t max_count, Get get) {
  std::vector<double> out;
  if (max_count == 0 || count == 0) return out;
  const auto n = static_cast<std::size_t>(count);
  const std::size_t stride = (n + max_count - 1) / max_count;
  out.reserve(n / stride + 1);
  for (std::size_t i = 0; i < n; i += stride) out.push_back(get(static_cast<Eigen::Index>(i)));
  return out;
}

/// Half-edge h = 3 f + k runs from corner k + 1 to corner k + 2 of face f (opposite corner k).
struct HalfEdge {
  int from, to, face, corner;
};

HalfEdge half_edge(const Eigen::MatrixX3i& faces, int h) {
  const int f = h / 3, k = h % 3;
  return {faces(f, (k + 1) % 3), faces(f, (k + 2) % 3), f, k};
}

void check_indices(const Eigen::MatrixX3i& faces, int num_vertices) {
  if (faces.size() > 0 && (faces.minCoeff() < 0 || faces.maxCoeff() >= num_vertices))
    throw MetricsInputError("metrics: a face index is out of range [0, " +
                            std::to_string(num_vertices) + ")");
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    if (faces(f, 0) == faces(f, 1) || faces(f, 1) == faces(f, 2) || faces(f, 0) == faces(f, 2))
      throw MetricsInputError("metrics: face " + std::to_string(f) + " repeats a vertex");
}

/// Half-edges ordered so that the two sides of an edge are neighbours: bucketed by their
/// smaller end vertex (counting sort), then by the larger one within a bucket.
std::vector<int> sorted_half_edges(const Eigen::MatrixX3i& faces, int num_vertices) {
  const int n = static_cast<int>(3 * faces.rows());
  std::vector<int> start(static_cast<std::size_t>(num_vertices) + 1, 0), low(n), high(n);
  for (int h = 0; h < n; ++h) {
    const HalfEdge e = half_edge(faces, h);
    low[h] = std::min(e.from, e.to);
    high[h] = std::max(e.from, e.to);
    ++start[low[h] + 1];
  }
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<int> order(n), fill(start.begin(), start.end() - 1);
  for (int h = 0; h < n; ++h) order[fill[low[h]]++] = h;
  for (int v = 0; v < num_vertices; ++v)  // buckets hold a vertex's few edges: insertion sort
    std::sort(order.begin() + start[v], order.begin() + start[v + 1],
              [&high](int a, int b) { return high[a] < high[b]; });
  return order;
}

bool same_edge(const HalfEdge& a, const HalfEdge& b) {
  return std::min(a.from, a.to) == std::min(b.from, b.to) &&
         std::max(a.from, a.to) == std::max(b.from, b.to);
}

void check_input(const Eigen::MatrixX2d& material_coords, const Eigen::MatrixX3d& positions,
                 const Eigen::MatrixX3i& faces, const Eigen::MatrixX3d& plastic_curvature) {
  if (material_coords.rows() != positions.rows())
    throw MetricsInputError("metrics: material_coords and positions differ in rows");
  if (plastic_curvature.rows() != 0 && plastic_curvature.rows() != faces.rows())
    throw MetricsInputError("metrics: plastic_curvature needs one row per face or none");
  if (!material_coords.allFinite() || !positions.allFinite())
    throw MetricsInputError("metrics: coordinates contain NaN or infinity");
}

double triangle_area(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

Eigen::Vector3d lift(const Eigen::Vector2d& p) { return {p.x(), p.y(), 0.0}; }

/// The three corner angles of a triangle [rad].
Eigen::Vector3d corner_angles(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                              const Eigen::Vector3d& c) {
  return {angle_between(b - a, c - a), angle_between(c - b, a - b), angle_between(a - c, b - c)};
}

/// 12 sqrt(3) area / perimeter^2.
double aspect(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const double perimeter = (b - a).norm() + (c - b).norm() + (a - c).norm();
  if (perimeter <= 0.0) return 0.0;
  return 12.0 * std::sqrt(3.0) * triangle_area(a, b, c) / (perimeter * perimeter);
}

Eigen::Vector3d unit_normal(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces,
                            int f) {
  const Eigen::Vector3d a = world(positions, faces(f, 0));
  const Eigen::Vector3d n =
      (world(positions, faces(f, 1)) - a).cross(world(positions, faces(f, 2)) - a);
  const double length = n.norm();
  return length > 0.0 ? Eigen::Vector3d(n / length) : Eigen::Vector3d::Zero();
}

/// World corner angles, #F by 3 [rad].
Eigen::MatrixX3d world_corner_angles(const Eigen::MatrixX3d& positions,
                                     const Eigen::MatrixX3i& faces) {
  Eigen::MatrixX3d angles(faces.rows(), 3);
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    angles.row(f) = corner_angles(world(positions, faces(f, 0)), world(positions, faces(f, 1)),
                                  world(positions, faces(f, 2)))
                        .transpose();
  return angles;
}

/// Unit world normals, #F by 3 (zero for a degenerate face).
Eigen::MatrixX3d face_normals(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces) {
  Eigen::MatrixX3d normals(faces.rows(), 3);
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    normals.row(f) = unit_normal(positions, faces, static_cast<int>(f)).transpose();
  return normals;
}

/// Per-vertex curvature (see angle_defects) from the corner angles.
Eigen::VectorXd defects_from_angles(const Eigen::MatrixX3d& angles, const Eigen::MatrixX3i& faces,
                                    const MeshTopology& topology) {
  Eigen::VectorXd sums = Eigen::VectorXd::Zero(topology.used.size());
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) sums(faces(f, k)) += angles(f, k);
  Eigen::VectorXd defect = Eigen::VectorXd::Zero(sums.size());
  for (Eigen::Index v = 0; v < sums.size(); ++v)
    if (topology.used(v)) defect(v) = (2.0 - 0.5 * topology.boundary_valence(v)) * PI - sums(v);
  return defect;
}

/// Smallest corner angle of a triangle [rad]: the one facing the shortest edge.
double smallest_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                      const Eigen::Vector3d& c) {
  const double ab = (b - a).squaredNorm(), bc = (c - b).squaredNorm(), ca = (a - c).squaredNorm();
  if (bc <= ab && bc <= ca) return angle_between(b - a, c - a);
  if (ca <= ab) return angle_between(c - b, a - b);
  return angle_between(a - c, b - c);
}

/// Smallest eigenvalue of sum_faces angle N N^T at every interior vertex (Stein et al. 2018).
Eigen::VectorXd covariance_lambda_min(const Eigen::MatrixX3d& positions,
                                      const Eigen::MatrixX3i& faces, const MeshTopology& topology,
                                      const Eigen::MatrixX3d& angles) {
  std::vector<Eigen::Matrix3d> covariance(static_cast<std::size_t>(positions.rows()),
                                          Eigen::Matrix3d::Zero());
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::Vector3d n = unit_normal(positions, faces, static_cast<int>(f));
    const Eigen::Matrix3d nn = n * n.transpose();
    for (int k = 0; k < 3; ++k) covariance[faces(f, k)] += angles(f, k) * nn;
  }
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(positions.rows());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  for (Eigen::Index v = 0; v < positions.rows(); ++v) {
    if (!topology.used(v) || topology.boundary_valence(v) > 0) continue;
    solver.computeDirect(covariance[v], Eigen::EigenvaluesOnly);
    lambda(v) = std::max(0.0, solver.eigenvalues()(0));
  }
  return lambda;
}

/// Rest dihedral implied by the plastic curvature of the two faces of interior edge e [rad].
double rest_dihedral(const Eigen::MatrixX2d& material_coords, const Eigen::MatrixX3i& faces,
                     const MeshTopology& topology, const Eigen::MatrixX3d& plastic_curvature,
                     int e) {
  const int f1 = topology.edge_faces(e, 0), f2 = topology.edge_faces(e, 1);
  const Eigen::Vector2d x0 = material(material_coords, topology.edges(e, 0));
  const Eigen::Vector2d x1 = material(material_coords, topology.edges(e, 1));
  const double length = (x1 - x0).norm();
  const Eigen::Vector2d m = Eigen::Vector2d(-(x1 - x0).y(), (x1 - x0).x()) / length;
  const Eigen::RowVector3d k = 0.5 * (plastic_curvature.row(f1) + plastic_curvature.row(f2));
  const double kappa_n = k(0) * m.x() * m.x() + k(1) * m.y() * m.y() + 2.0 * k(2) * m.x() * m.y();
  auto area = [&](int f) {
    return triangle_area(lift(material(material_coords, faces(f, 0))),
                         lift(material(material_coords, faces(f, 1))),
                         lift(material(material_coords, faces(f, 2))));
  };
  return kappa_n * (area(f1) + area(f2)) / length;
}

/// Crease edges incident to each vertex (compressed rows).
struct CreaseAdjacency {
  std::vector<int> start;  ///< #V + 1
  std::vector<int> edges;  ///< crease edge indices
  int valence(int v) const { return start[v + 1] - start[v]; }
};

CreaseAdjacency crease_adjacency(const MeshTopology& topology, const std::vector<int>& creases,
                                 Eigen::Index num_vertices) {
  CreaseAdjacency adjacency;
  adjacency.start.assign(static_cast<std::size_t>(num_vertices) + 1, 0);
  for (int e : creases)
    for (int s = 0; s < 2; ++s) ++adjacency.start[topology.edges(e, s) + 1];
  std::partial_sum(adjacency.start.begin(), adjacency.start.end(), adjacency.start.begin());
  adjacency.edges.resize(2 * creases.size());
  std::vector<int> fill(adjacency.start.begin(), adjacency.start.end() - 1);
  for (int e : creases)
    for (int s = 0; s < 2; ++s) adjacency.edges[fill[topology.edges(e, s)]++] = e;
  return adjacency;
}

/// Crease edges of one line, walked from `seed` through vertices of crease valence 2.
std::vector<int> walk_line(const MeshTopology& topology, const CreaseAdjacency& adjacency, int seed,
                           std::vector<char>& visited, bool& closed) {
  std::vector<int> line{seed};
  visited[seed] = 1;
  closed = false;
  for (int side = 0; side < 2 && !closed; ++side) {
    int v = topology.edges(seed, side), previous = seed;
    while (adjacency.valence(v) == 2) {
      const int* at = &adjacency.edges[adjacency.start[v]];
      const int next = at[0] == previous ? at[1] : at[0];
      if (next == seed) {
        closed = true;
        break;
      }
      if (visited[next]) break;
      visited[next] = 1;
      line.push_back(next);
      v = topology.edges(next, 0) == v ? topology.edges(next, 1) : topology.edges(next, 0);
      previous = next;
    }
  }
  return line;
}

void fill_length_distribution(CreaseMetrics& c) {
  if (c.crease_lines.empty()) return;
  std::vector<double> lengths, logs;
  for (const CreaseLine& line : c.crease_lines) {
    lengths.push_back(line.length);
    logs.push_back(std::log(std::max(line.length, 1e-300)));
  }
  const double n = static_cast<double>(lengths.size());
  c.length_min = *std::min_element(lengths.begin(), lengths.end());
  c.length_max = *std::max_element(lengths.begin(), lengths.end());
  c.length_mean = std::accumulate(lengths.begin(), lengths.end(), 0.0) / n;
  c.length_median = quantile(lengths, 0.5);
  const LogNormalFit fit = fit_log_normal(lengths);
  c.log_length_mean = fit.mean;
  c.log_length_std = fit.std;
  c.log_normal_ks = fit.ks;
}

/// The plastic crease network (CreaseMetrics::plastic_network_*): edges whose rest dihedral
/// exceeds the threshold [rad], walked into lines; lengths in material space.
void fill_plastic_network(const Eigen::MatrixX2d& material_coords, const Eigen::MatrixX3i& faces,
                          const MeshTopology& topology, const Eigen::MatrixX3d& plastic_curvature,
                          double threshold, CreaseMetrics& c) {
  std::vector<int> edges;
  for (Eigen::Index e = 0; e < topology.edges.rows(); ++e)
    if (topology.edge_faces(e, 1) >= 0 &&
        std::abs(rest_dihedral(material_coords, faces, topology, plastic_curvature,
                               static_cast<int>(e))) > threshold)
      edges.push_back(static_cast<int>(e));
  c.plastic_network_edges = static_cast<int>(edges.size());
  const CreaseAdjacency adjacency = crease_adjacency(topology, edges, material_coords.rows());
  for (Eigen::Index v = 0; v < material_coords.rows(); ++v)
    c.plastic_network_junctions += adjacency.valence(static_cast<int>(v)) >= 3 ? 1 : 0;
  std::vector<char> visited(topology.edges.rows(), 0);
  for (int seed : edges) {
    if (visited[seed]) continue;
    bool closed = false;
    double length = 0.0;
    for (int e : walk_line(topology, adjacency, seed, visited, closed))
      length += (material(material_coords, topology.edges(e, 1)) -
                 material(material_coords, topology.edges(e, 0)))
                    .norm();
    c.plastic_network_line_lengths.push_back(length);
    c.plastic_network_length += length;
  }
  std::sort(c.plastic_network_line_lengths.rbegin(), c.plastic_network_line_lengths.rend());
  c.plastic_network_lines = static_cast<int>(c.plastic_network_line_lengths.size());
  const LogNormalFit fit = fit_log_normal(c.plastic_network_line_lengths);
  c.plastic_network_log_length_mean = fit.mean;
  c.plastic_network_log_length_std = fit.std;
  c.plastic_network_log_normal_ks = fit.ks;
}

}  // namespace

void MetricsSamples::append(const MetricsSamples& other) {
  auto add = [](std::vector<double>& to, const std::vector<double>& from) {
    to.insert(to.end(), from.begin(), from.end());
  };
  add(edge_strain, other.edge_strain);
  add(s1, other.s1);
  add(s2, other.s2);
  add(angle_defect, other.angle_defect);
  add(crease_length, other.crease_length);
}

MeshTopology build_topology(const Eigen::MatrixX3i& faces, int num_vertices) {
  check_indices(faces, num_vertices);
  const std::vector<int> order = sorted_half_edges(faces, num_vertices);
  MeshTopology t;
  t.face_edges.resize(faces.rows(), 3);
  t.boundary_valence = Eigen::VectorXi::Zero(num_vertices);
  t.used = Eigen::VectorXi::Zero(num_vertices);
  std::vector<Eigen::Vector4i> edges;  // v0, v1, f0, f1
  edges.reserve(order.size() / 2 + 1);
  for (std::size_t i = 0; i < order.size();) {
    const HalfEdge first = half_edge(faces, order[i]);
    std::size_t j = i + 1;
    while (j < order.size() && same_edge(first, half_edge(faces, order[j]))) ++j;
    if (j - i > 2)
      throw MetricsInputError("metrics: non-manifold edge (" + std::to_string(first.from) + ", " +
                              std::to_string(first.to) + ")");
    const int e = static_cast<int>(edges.size());
    t.face_edges(first.face, first.corner) = e;
    int other_face = -1;
    if (j - i == 2) {
      const HalfEdge second = half_edge(faces, order[i + 1]);
      if (second.from != first.to)
        throw MetricsInputError("metrics: faces " + std::to_string(first.face) + " and " +
                                std::to_string(second.face) + " are oriented inconsistently");
      other_face = second.face;
      t.face_edges(second.face, second.corner) = e;
    } else {
      ++t.boundary_valence(first.from);
      ++t.boundary_valence(first.to);
    }
    edges.emplace_back(first.from, first.to, first.face, other_face);
    i = j;
  }
  t.edges.resize(static_cast<Eigen::Index>(edges.size()), 2);
  t.edge_faces.resize(static_cast<Eigen::Index>(edges.size()), 2);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    t.edges.row(static_cast<Eigen::Index>(e)) << edges[e](0), edges[e](1);
    t.edge_faces.row(static_cast<Eigen::Index>(e)) << edges[e](2), edges[e](3);
  }
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) t.used(faces(f, k)) = 1;
  t.num_used_vertices = t.used.sum();
  t.num_boundary_edges = static_cast<int>((t.edge_faces.col(1).array() < 0).count());
  return t;
}

Eigen::VectorXd edge_strains(const Eigen::MatrixX2d& material_coords,
                             const Eigen::MatrixX3d& positions, const MeshTopology& topology) {
  Eigen::VectorXd strain(topology.edges.rows());
  for (Eigen::Index e = 0; e < topology.edges.rows(); ++e) {
    const int a = topology.edges(e, 0), b = topology.edges(e, 1);
    const double rest = (material(material_coords, b) - material(material_coords, a)).norm();
    if (!(rest > 0.0))
      throw MetricsInputError("metrics: zero-length material edge (" + std::to_string(a) + ", " +
                              std::to_string(b) + ")");
    strain(e) = (world(positions, b) - world(positions, a)).norm() / rest - 1.0;
  }
  return strain;
}

Eigen::MatrixX2d principal_stretches(const Eigen::MatrixX2d& material_coords,
                                     const Eigen::MatrixX3d& positions,
                                     const Eigen::MatrixX3i& faces) {
  Eigen::MatrixX2d s(faces.rows(), 2);
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const int i = faces(f, 0), j = faces(f, 1), k = faces(f, 2);
    Eigen::Matrix2d dm;
    dm << material(material_coords, j) - material(material_coords, i),
        material(material_coords, k) - material(material_coords, i);
    const double det = dm.determinant();
    if (!(std::abs(det) > 0.0))
      throw MetricsInputError("metrics: face " + std::to_string(f) +
                              " is degenerate in material space");
    Eigen::Matrix<double, 3, 2> dx;
    dx << world(positions, j) - world(positions, i), world(positions, k) - world(positions, i);
    const Eigen::Matrix<double, 3, 2> F = dx * dm.inverse();
    // s1 from the larger eigenvalue of F^T F; s2 from s1 s2 = |f1 x f2| (accurate for thin F).
    const Eigen::Matrix2d c = F.transpose() * F;
    const double half_trace = 0.5 * c.trace();
    const double root = std::hypot(0.5 * (c(0, 0) - c(1, 1)), c(0, 1));
    const double s1 = std::sqrt(half_trace + root);
    const double area_ratio = F.col(0).cross(F.col(1)).norm();
    s(f, 0) = s1;
    s(f, 1) = s1 > 0.0 ? area_ratio / s1 : 0.0;
  }
  return s;
}

Eigen::VectorXd angle_defects(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces,
                              const MeshTopology& topology) {
  return defects_from_angles(world_corner_angles(positions, faces), faces, topology);
}

Eigen::VectorXd dihedral_angles(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces,
                                const MeshTopology& topology) {
  Eigen::VectorXd angle = Eigen::VectorXd::Zero(topology.edges.rows());
  const Eigen::MatrixX3d normals = face_normals(positions, faces);
  for (Eigen::Index e = 0; e < topology.edges.rows(); ++e) {
    const int f1 = topology.edge_faces(e, 0), f2 = topology.edge_faces(e, 1);
    if (f2 < 0) continue;
    const Eigen::Vector3d n1 = normals.row(f1).transpose(), n2 = normals.row(f2).transpose();
    const Eigen::Vector3d axis =
        (world(positions, topology.edges(e, 1)) - world(positions, topology.edges(e, 0)))
            .normalized();
    angle(e) = std::atan2(axis.dot(n2.cross(n1)), n1.dot(n2));
  }
  return angle;
}

IsometryMetrics isometry_metrics(const Eigen::MatrixX2d& material_coords,
                                 const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces,
                                 const MeshTopology& topology) {
  IsometryMetrics m;
  const Eigen::VectorXd strain = edge_strains(material_coords, positions, topology);
  if (strain.size() > 0) {
    const Eigen::ArrayXd magnitude = strain.array().abs();
    m.edge_strain_max = magnitude.maxCoeff();
    m.edge_strain_mean = magnitude.mean();
    m.edge_strain_p99 = quantile(std::vector<double>(magnitude.begin(), magnitude.end()), 0.99);
    m.edge_stretch_max = std::max(0.0, strain.maxCoeff());
    m.edge_compression_max = std::max(0.0, -strain.minCoeff());
  }
  if (faces.rows() == 0) return m;
  const Eigen::MatrixX2d s = principal_stretches(material_coords, positions, faces);
  m.s1_max = s.col(0).maxCoeff();
  m.s2_min = s.col(1).minCoeff();
  m.stretch_max = std::max(0.0, m.s1_max - 1.0);
  m.compression_max = std::max(0.0, 1.0 - m.s2_min);
  const Eigen::ArrayXd stretch = (s.col(0).array() - 1.0).max(0.0);
  const Eigen::ArrayXd compression = (1.0 - s.col(1).array()).max(0.0);
  m.stretch_p99 = quantile(std::vector<double>(stretch.begin(), stretch.end()), 0.99);
  m.compression_p99 = quantile(std::vector<double>(compression.begin(), compression.end()), 0.99);
  const Eigen::ArrayXd area_change = s.col(0).array() * s.col(1).array() - 1.0;
  m.area_change_max = area_change.maxCoeff();
  m.area_change_min = area_change.minCoeff();
  double material_area = 0.0, weighted = 0.0, world_area = 0.0;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const double a = triangle_area(lift(material(material_coords, faces(f, 0))),
                                   lift(material(material_coords, faces(f, 1))),
                                   lift(material(material_coords, faces(f, 2))));
    material_area += a;
    weighted += a * std::abs(area_change(f));
    world_area += triangle_area(world(positions, faces(f, 0)), world(positions, faces(f, 1)),
                                world(positions, faces(f, 2)));
  }
  m.area_change_mean = weighted / material_area;
  m.total_area_change = world_area / material_area - 1.0;
  return m;
}

DevelopabilityMetrics developability_metrics(const Eigen::MatrixX3d& positions,
                                             const Eigen::MatrixX3i& faces,
                                             const MeshTopology& topology) {
  DevelopabilityMetrics m;
  m.euler_characteristic = topology.num_used_vertices - static_cast<int>(topology.edges.rows()) +
                           static_cast<int>(faces.rows());
  const Eigen::MatrixX3d angles = world_corner_angles(positions, faces);
  const Eigen::VectorXd defect = defects_from_angles(angles, faces, topology);
  double total = 0.0;
  for (Eigen::Index v = 0; v < defect.size(); ++v) {
    total += defect(v);
    if (!topology.used(v) || topology.boundary_valence(v) > 0) continue;
    m.angle_defect_max = std::max(m.angle_defect_max, std::abs(defect(v)));
    m.angle_defect_integral += std::abs(defect(v));
  }
  m.gauss_bonnet_residual = total - 2.0 * PI * m.euler_characteristic;
  const Eigen::VectorXd lambda = covariance_lambda_min(positions, faces, topology, angles);
  m.covariance_energy = lambda.sum();
  m.covariance_max = lambda.size() > 0 ? lambda.maxCoeff() : 0.0;
  return m;
}

LogNormalFit fit_log_normal(std::vector<double> lengths) {
  LogNormalFit fit;
  if (lengths.empty()) return fit;
  const double n = static_cast<double>(lengths.size());
  for (double l : lengths) fit.mean += std::log(std::max(l, 1e-300)) / n;
  for (double l : lengths) fit.std += std::pow(std::log(std::max(l, 1e-300)) - fit.mean, 2) / n;
  fit.std = std::sqrt(fit.std);
  if (lengths.size() < 3 || !(fit.std > 0)) return fit;
  std::sort(lengths.begin(), lengths.end());
  for (std::size_t i = 0; i < lengths.size(); ++i) {
    const double z =
        (std::log(std::max(lengths[i], 1e-300)) - fit.mean) / (fit.std * std::sqrt(2.0));
    const double cdf = 0.5 * std::erfc(-z);
    fit.ks = std::max({fit.ks, std::abs(cdf - static_cast<double>(i) / n),
                       std::abs(static_cast<double>(i + 1) / n - cdf)});
  }
  return fit;
}

CreaseMetrics crease_metrics(const Eigen::MatrixX2d& material_coords,
                             const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces,
                             const MeshTopology& topology,
                             const Eigen::MatrixX3d& plastic_curvature, double crease_angle_deg) {
  CreaseMetrics c;
  c.threshold_deg = crease_angle_deg;
  c.has_plastic_data = plastic_curvature.rows() == faces.rows() && faces.rows() > 0;
  const double threshold = crease_angle_deg * DEG;
  const Eigen::VectorXd dihedral = dihedral_angles(positions, faces, topology);
  std::vector<int> creases;
  for (Eigen::Index e = 0; e < dihedral.size(); ++e)
    if (std::abs(dihedral(e)) > threshold) creases.push_back(static_cast<int>(e));
  c.sharpest_angle_deg = dihedral.size() > 0 ? dihedral.cwiseAbs().maxCoeff() / DEG : 0.0;
  c.edges = static_cast<int>(creases.size());
  const CreaseAdjacency adjacency = crease_adjacency(topology, creases, positions.rows());
  for (Eigen::Index v = 0; v < positions.rows(); ++v) {
    const int valence = adjacency.valence(static_cast<int>(v));
    if (valence < 3) continue;
    ++c.junctions;
    ++c.junction_degrees[std::min(valence, 5) - 3];
  }

  std::vector<char> visited(dihedral.size(), 0);
  for (int seed : creases) {
    if (visited[seed]) continue;
    CreaseLine line;
    const std::vector<int> edges = walk_line(topology, adjacency, seed, visited, line.closed);
    for (int e : edges) {
      const double length =
          (world(positions, topology.edges(e, 1)) - world(positions, topology.edges(e, 0))).norm();
      line.length += length;
      line.max_angle_deg = std::max(line.max_angle_deg, std::abs(dihedral(e)) / DEG);
      if (c.has_plastic_data && std::abs(rest_dihedral(material_coords, faces, topology,
                                                       plastic_curvature, e)) > threshold)
        line.plastic_length += length;
    }
    line.edges = static_cast<int>(edges.size());
    c.total_length += line.length;
    c.plastic_length += line.plastic_length;
    c.plastic_lines += line.plastic() ? 1 : 0;
    c.crease_lines.push_back(line);
  }
  std::sort(c.crease_lines.begin(), c.crease_lines.end(),
            [](const CreaseLine& a, const CreaseLine& b) { return a.length > b.length; });
  c.lines = static_cast<int>(c.crease_lines.size());
  c.elastic_length = c.total_length - c.plastic_length;
  fill_length_distribution(c);
  if (c.has_plastic_data)
    fill_plastic_network(material_coords, faces, topology, plastic_curvature, threshold, c);
  return c;
}

QualityMetrics quality_metrics(const Eigen::MatrixX2d& material_coords,
                               const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces,
                               const MeshTopology& topology) {
  QualityMetrics q;
  if (faces.rows() == 0) return q;
  double min_angle = PI, min_angle_world = PI, aspect_min = 1.0, aspect_world = 1.0;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::Vector3d a = lift(material(material_coords, faces(f, 0)));
    const Eigen::Vector3d b = lift(material(material_coords, faces(f, 1)));
    const Eigen::Vector3d c = lift(material(material_coords, faces(f, 2)));
    const Eigen::Vector3d x = world(positions, faces(f, 0)), y = world(positions, faces(f, 1)),
                          z = world(positions, faces(f, 2));
    min_angle = std::min(min_angle, smallest_angle(a, b, c));
    min_angle_world = std::min(min_angle_world, smallest_angle(x, y, z));
    aspect_min = std::min(aspect_min, aspect(a, b, c));
    aspect_world = std::min(aspect_world, aspect(x, y, z));
  }
  q.min_angle_deg = min_angle / DEG;
  q.min_angle_world_deg = min_angle_world / DEG;
  q.aspect_min = aspect_min;
  q.aspect_min_world = aspect_world;
  Eigen::VectorXd rest(topology.edges.rows()), length(topology.edges.rows());
  for (Eigen::Index e = 0; e < topology.edges.rows(); ++e) {
    const int i = topology.edges(e, 0), j = topology.edges(e, 1);
    rest(e) = (material(material_coords, j) - material(material_coords, i)).norm();
    length(e) = (world(positions, j) - world(positions, i)).norm();
  }
  q.edge_length_min = rest.minCoeff();
  q.edge_length_max = rest.maxCoeff();
  q.world_edge_length_min = length.minCoeff();
  q.world_edge_length_max = length.maxCoeff();
  return q;
}

namespace {

void collect_samples(const Eigen::MatrixX2d& material_coords, const Eigen::MatrixX3d& positions,
                     const Eigen::MatrixX3i& faces, const MeshTopology& topology,
                     const MeshMetrics& metrics, std::size_t max_samples, MetricsSamples& samples) {
  const Eigen::VectorXd strain = edge_strains(material_coords, positions, topology);
  samples.edge_strain =
      strided(strain.size(), max_samples, [&](Eigen::Index i) { return strain(i); });
  const Eigen::MatrixX2d s = principal_stretches(material_coords, positions, faces);
  samples.s1 = strided(s.rows(), max_samples, [&](Eigen::Index i) { return s(i, 0); });
  samples.s2 = strided(s.rows(), max_samples, [&](Eigen::Index i) { return s(i, 1); });
  const Eigen::VectorXd defect = angle_defects(positions, faces, topology);
  std::vector<double> interior;
  for (Eigen::Index v = 0; v < defect.size(); ++v)
    if (topology.used(v) && topology.boundary_valence(v) == 0) interior.push_back(defect(v));
  samples.angle_defect = strided(static_cast<Eigen::Index>(interior.size()), max_samples,
                                 [&](Eigen::Index i) { return interior[i]; });
  samples.crease_length.clear();
  for (const CreaseLine& line : metrics.creases.crease_lines)
    samples.crease_length.push_back(line.length);
}

}  // namespace

MeshMetrics compute_metrics(const Eigen::MatrixX2d& material_coords,
                            const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces,
                            const Eigen::MatrixX3d& plastic_curvature,
                            const MetricsOptions& options, MetricsSamples* samples) {
  check_input(material_coords, positions, faces, plastic_curvature);
  const MeshTopology topology = build_topology(faces, static_cast<int>(positions.rows()));
  MeshMetrics m;
  m.vertices = topology.num_used_vertices;
  m.faces = static_cast<int>(faces.rows());
  m.edges = static_cast<int>(topology.edges.rows());
  m.boundary_edges = topology.num_boundary_edges;
  m.isometry = isometry_metrics(material_coords, positions, faces, topology);
  m.developability = developability_metrics(positions, faces, topology);
  m.creases = crease_metrics(material_coords, positions, faces, topology, plastic_curvature,
                             options.crease_angle_deg);
  m.quality = quality_metrics(material_coords, positions, faces, topology);
  if (options.self_intersections)
    m.self_intersections = collision::count_self_intersections(positions, faces);
  if (samples != nullptr)
    collect_samples(material_coords, positions, faces, topology, m, options.max_samples, *samples);
  return m;
}

MeshMetrics compute_metrics(const remesh::SheetData& sheet, const MetricsOptions& options,
                            bool use_plastic_data, MetricsSamples* samples) {
  const Eigen::MatrixX3d plastic =
      use_plastic_data ? sheet.mesh.plastic_curvature() : Eigen::MatrixX3d(0, 3);
  return compute_metrics(sheet.mesh.material_coords(), sheet.positions, sheet.mesh.faces(), plastic,
                         options, samples);
}

}  // namespace papersim::validation
