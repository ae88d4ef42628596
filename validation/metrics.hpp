#pragma once
/// Measurements of a deformed sheet (VALIDATION.md section 7): isometry, developability,
/// creases, mesh quality and self-intersection.
///
/// The core functions take plain arrays:
///   material_coords    #V by 2 material (flat sheet) coordinates [m]
///   positions          #V by 3 world positions [m]
///   faces              #F by 3 vertex indices, consistently oriented (counter-clockwise in
///                      material space for a papersim sheet)
///   plastic_curvature  #F by 3 (k_xx, k_yy, k_xy) [1/m] in material coordinates, or 0 rows
///                      when the mesh carries no plastic data
/// Vertices used by no face are ignored. Angles are in radians unless a name says `_deg`.
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <iosfwd>
#include <nlohmann/json_fwd.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace papersim::remesh {
struct SheetData;
}

namespace papersim::validation {

/// Options of compute_metrics.
struct MetricsOptions {
  double crease_angle_deg = 30.0;  ///< [deg] an interior edge is a crease when |dihedral| > this
  bool self_intersections = true;  ///< run the exact self-intersection count (collision module)
  std::size_t max_samples = 0;     ///< per-element values kept per quantity in MetricsSamples
                                   ///< (evenly strided); 0 keeps none
};

/// Isometric distortion relative to the material coordinates. Edge strain is l / L - 1
/// (l world, L material length); s1 >= s2 are the singular values of the per-triangle 3x2
/// deformation gradient F = Dx Dm^-1. "Stretch" is the part above 1, "compression" below 1.
struct IsometryMetrics {
  double edge_strain_max = 0.0;       ///< max |l / L - 1| [-]
  double edge_strain_mean = 0.0;      ///< mean |l / L - 1| over edges [-]
  double edge_strain_p99 = 0.0;       ///< 99th percentile of |l / L - 1| [-]
  double edge_stretch_max = 0.0;      ///< max(0, max l / L - 1) [-]
  double edge_compression_max = 0.0;  ///< max(0, max 1 - l / L) [-]
  double s1_max = 1.0;                ///< largest principal stretch over triangles [-]
  double s2_min = 1.0;                ///< smallest principal stretch over triangles [-]
  double stretch_max = 0.0;           ///< max(0, s1_max - 1) [-]
  double compression_max = 0.0;       ///< max(0, 1 - s2_min) [-]
  double stretch_p99 = 0.0;           ///< 99th percentile over triangles of max(0, s1 - 1) [-]
  double compression_p99 = 0.0;       ///< 99th percentile over triangles of max(0, 1 - s2) [-]
  double area_change_max = 0.0;       ///< max over triangles of s1 s2 - 1 [-]
  double area_change_min = 0.0;       ///< min over triangles of s1 s2 - 1 [-]
  double area_change_mean = 0.0;      ///< material-area-weighted mean of |s1 s2 - 1| [-]
  double total_area_change = 0.0;     ///< world area / material area - 1 [-]
};

/// Discrete Gaussian curvature. Angle defect K_i = 2 pi - (sum of world corner angles at i) at
/// an interior vertex. Gauss-Bonnet residual = sum_interior (2 pi - angle sum)
/// + sum_boundary (pi - angle sum) - 2 pi chi, chi = V - E + F (1 for a disk); a boundary
/// vertex touched by n boundary edges contributes (2 - n / 2) pi - angle sum, which is pi -
/// angle sum for an ordinary boundary vertex and keeps the identity exact for pinched ones.
struct DevelopabilityMetrics {
  double angle_defect_max = 0.0;       ///< max |K_i| over interior vertices [rad]
  double angle_defect_integral = 0.0;  ///< sum of |K_i| over interior vertices [rad]
  double gauss_bonnet_residual = 0.0;  ///< signed, [rad]; zero to rounding for any mesh
  int euler_characteristic = 0;        ///< V - E + F (used vertices only)
  /// Stein, Grinspun, Crane 2018 "Developability of triangle meshes", combinatorial covariance
  /// energy: sum over interior vertices of the smallest eigenvalue of
  /// sum_faces (corner angle) N N^T (N unit world face normal) [rad]; zero on a developable
  /// vertex (normals of its faces lie on a great circle).
  double covariance_energy = 0.0;
  double covariance_max = 0.0;  ///< largest per-vertex smallest eigenvalue [rad]
};

/// A chain of crease edges walked through vertices of crease valence 2; it ends at a vertex of
/// crease valence 1 or >= 3, or closes on itself.
struct CreaseLine {
  int edges = 0;                ///< number of crease edges
  double length = 0.0;          ///< world length [m]
  double max_angle_deg = 0.0;   ///< largest |dihedral| along the line [deg]
  double plastic_length = 0.0;  ///< length of its plastic edges [m]
  bool closed = false;          ///< a loop without end points
  /// More than half of the length is plastic (see CreaseMetrics).
  bool plastic() const { return plastic_length > 0.5 * length; }
};

/// Creases: interior edges whose |dihedral| (angle between the two world face normals)
/// exceeds crease_angle_deg. Note that a dihedral threshold depends on the mesh size: a smooth
/// bend of radius R meshed at spacing h gives dihedrals of about h / R.
///
/// Plastic versus elastic (when plastic data exists): the rest dihedral of an edge is
///   rest = kappa_n (A1 + A2) / L
/// with kappa_n = m^T Kbar m the plastic normal curvature across the edge (Kbar the mean of the
/// two faces' plastic curvature tensors, m the unit in-plane normal of the edge in material
/// space), A1, A2 the material areas of the two faces and L the material edge length (the
/// hinge curvature theta L / (A1 + A2) of VALIDATION.md section 7, exact on a cylinder meshed
/// with edges along the axis). A crease edge is plastic when |rest| also exceeds the threshold:
/// it would stay a crease if the sheet were released. A line is plastic when more than half
/// of its length is.
struct CreaseMetrics {
  double threshold_deg = 30.0;      ///< the threshold used [deg]
  int edges = 0;                    ///< crease edges
  int lines = 0;                    ///< crease lines
  int junctions = 0;                ///< vertices of crease valence >= 3
  double total_length = 0.0;        ///< sum of crease edge world lengths [m]
  double length_min = 0.0;          ///< shortest line [m] (0 without lines)
  double length_median = 0.0;       ///< [m]
  double length_mean = 0.0;         ///< [m]
  double length_max = 0.0;          ///< [m]
  double log_length_mean = 0.0;     ///< mean of ln(length / 1 m), for a log-normal fit
  double log_length_std = 0.0;      ///< standard deviation of ln(length / 1 m)
  double sharpest_angle_deg = 0.0;  ///< max |dihedral| over all interior edges [deg]
  /// Kolmogorov-Smirnov distance between the line lengths and the log-normal of parameters
  /// (log_length_mean, log_length_std): the largest gap between the two cumulative
  /// distributions [-] (0 with fewer than three lines or a zero spread). Ridge lengths of
  /// crumpled paper are log-normal (Andresen et al., PRE 2007); for n lines a distance above
  /// about 0.89 / sqrt(n) rejects the fit at 5% (Lilliefors, parameters estimated).
  double log_normal_ks = 0.0;
  /// Junctions by crease valence: [0] valence 3, [1] valence 4, [2] valence 5 or more.
  std::array<int, 3> junction_degrees = {0, 0, 0};
  bool has_plastic_data = false;  ///< plastic_curvature was given
  int plastic_lines = 0;          ///< lines with CreaseLine::plastic()
  double plastic_length = 0.0;    ///< world length of plastic crease edges [m]
  double elastic_length = 0.0;    ///< total_length - plastic_length [m]
  /// The plastic crease network, from the plastic state alone (whatever the current shape):
  /// interior edges whose rest dihedral exceeds the threshold, walked into lines between
  /// junctions as above. Lengths in material space [m] (what a flattened sheet would show).
  int plastic_network_edges = 0;
  int plastic_network_lines = 0;
  int plastic_network_junctions = 0;
  double plastic_network_length = 0.0;           ///< [m]
  double plastic_network_log_length_mean = 0.0;  ///< mean of ln(line length / 1 m)
  double plastic_network_log_length_std = 0.0;
  double plastic_network_log_normal_ks = 0.0;        ///< as log_normal_ks [-]
  std::vector<double> plastic_network_line_lengths;  ///< [m], longest first
  std::vector<CreaseLine> crease_lines;              ///< every line, longest first
};

/// Element quality. Aspect is 12 sqrt(3) area / perimeter^2 (1 for an equilateral triangle,
/// -> 0 for a sliver; the measure of ARCSim / Narain et al. 2012).
struct QualityMetrics {
  double min_angle_deg = 0.0;        ///< smallest corner angle in material space [deg]
  double min_angle_world_deg = 0.0;  ///< smallest corner angle in world space [deg]
  double aspect_min = 0.0;           ///< worst aspect in material space [-]
  double aspect_min_world = 0.0;     ///< worst aspect in world space [-]
  double edge_length_min = 0.0;      ///< material edge length range [m]
  double edge_length_max = 0.0;
  double world_edge_length_min = 0.0;  ///< world edge length range [m]
  double world_edge_length_max = 0.0;
};

/// Every figure of one mesh.
struct MeshMetrics {
  int vertices = 0;  ///< used vertices
  int faces = 0;
  int edges = 0;
  int boundary_edges = 0;
  IsometryMetrics isometry;
  DevelopabilityMetrics developability;
  CreaseMetrics creases;
  QualityMetrics quality;
  int self_intersections = -1;  ///< intersecting triangle pairs; -1 when not computed
};

/// Per-element values kept for histograms (at most MetricsOptions::max_samples each).
struct MetricsSamples {
  std::vector<double> edge_strain;    ///< l / L - 1 per edge [-]
  std::vector<double> s1;             ///< largest principal stretch per triangle [-]
  std::vector<double> s2;             ///< smallest principal stretch per triangle [-]
  std::vector<double> angle_defect;   ///< K_i per interior vertex [rad]
  std::vector<double> crease_length;  ///< per crease line [m] (all lines, not subsampled)
  /// Append another mesh's samples.
  void append(const MetricsSamples& other);
};

/// Edges of a triangle mesh with their faces.
struct MeshTopology {
  Eigen::MatrixX2i edges;            ///< #E by 2 (v0, v1), directed as in face edge_faces(e, 0)
  Eigen::MatrixX2i edge_faces;       ///< #E by 2; second is -1 on a boundary edge
  Eigen::MatrixX3i face_edges;       ///< #F by 3, edge opposite corner k of the face
  Eigen::VectorXi boundary_valence;  ///< #V number of boundary edges at each vertex
  Eigen::VectorXi used;              ///< #V 1 when a face uses the vertex
  int num_used_vertices = 0;
  int num_boundary_edges = 0;
};

/// Bad input to the metrics (shapes, indices, NaN, degenerate material triangles,
/// non-manifold or inconsistently oriented edges).
struct MetricsInputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Edge topology of a mesh.
/// @param num_vertices #V, every index in faces must be below it
/// @throw MetricsInputError on an index out of range, an edge with more than two faces, or two
///        faces traversing an edge in the same direction.
MeshTopology build_topology(const Eigen::MatrixX3i& faces, int num_vertices);

/// Per-edge strain l / L - 1 [-], #E (order of topology.edges).
/// @throw MetricsInputError on a zero-length material edge.
Eigen::VectorXd edge_strains(const Eigen::MatrixX2d& material_coords,
                             const Eigen::MatrixX3d& positions, const MeshTopology& topology);

/// Per-triangle principal stretches, #F by 2 (s1 >= s2 >= 0) [-].
/// @throw MetricsInputError on a degenerate material triangle.
Eigen::MatrixX2d principal_stretches(const Eigen::MatrixX2d& material_coords,
                                     const Eigen::MatrixX3d& positions,
                                     const Eigen::MatrixX3i& faces);

/// Per-vertex curvature [rad], #V: 2 pi - angle sum at interior vertices, the boundary term
/// (2 - n / 2) pi - angle sum at boundary vertices (n boundary edges; pi - angle sum for an
/// ordinary boundary vertex), 0 at unused vertices.
Eigen::VectorXd angle_defects(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces,
                              const MeshTopology& topology);

/// Per-edge signed bending angle [rad], #E: the angle between the world normals of the two
/// faces, positive when the surface bends towards its normals; 0 on boundary edges.
Eigen::VectorXd dihedral_angles(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces,
                                const MeshTopology& topology);

/// Isometry figures (see IsometryMetrics).
IsometryMetrics isometry_metrics(const Eigen::MatrixX2d& material_coords,
                                 const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces,
                                 const MeshTopology& topology);

/// Developability figures (see DevelopabilityMetrics).
DevelopabilityMetrics developability_metrics(const Eigen::MatrixX3d& positions,
                                             const Eigen::MatrixX3i& faces,
                                             const MeshTopology& topology);

/// Log-normal fit of positive lengths [m]: mean and standard deviation of ln(length / 1 m),
/// and the Kolmogorov-Smirnov distance of the lengths to that log-normal [-] (0 with fewer
/// than three lengths or a zero spread).
struct LogNormalFit {
  double mean = 0.0, std = 0.0, ks = 0.0;
};
LogNormalFit fit_log_normal(std::vector<double> lengths);

/// Crease figures (see CreaseMetrics).
/// @param plastic_curvature #F by 3 [1/m], or 0 rows when there is no plastic data
CreaseMetrics crease_metrics(const Eigen::MatrixX2d& material_coords,
                             const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces,
                             const MeshTopology& topology,
                             const Eigen::MatrixX3d& plastic_curvature, double crease_angle_deg);

/// Quality figures (see QualityMetrics).
QualityMetrics quality_metrics(const Eigen::MatrixX2d& material_coords,
                               const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces,
                               const MeshTopology& topology);

/// Every figure of a mesh.
/// @param plastic_curvature #F by 3 [1/m], or 0 rows when there is no plastic data
/// @param samples when not null, receives per-element values (MetricsOptions::max_samples)
/// @throw MetricsInputError on bad input (see the functions above).
MeshMetrics compute_metrics(const Eigen::MatrixX2d& material_coords,
                            const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces,
                            const Eigen::MatrixX3d& plastic_curvature,
                            const MetricsOptions& options = {}, MetricsSamples* samples = nullptr);

/// Every figure of a sheet read with remesh::read_sheet.
/// @param use_plastic_data pass the faces' plastic curvature (false for formats without it,
///        such as OBJ, so the report says "no plastic data" rather than "all elastic")
/// @throw MetricsInputError on bad input.
MeshMetrics compute_metrics(const remesh::SheetData& sheet, const MetricsOptions& options = {},
                            bool use_plastic_data = true, MetricsSamples* samples = nullptr);

/// Every scalar figure as ("group.name", value), in a fixed order (the CSV columns).
/// Integers and booleans are given as doubles; crease_lines are left out.
std::vector<std::pair<std::string, double>> metric_fields(const MeshMetrics& metrics);

/// Minimum, mean and maximum of one field over several meshes.
struct FieldSummary {
  std::string name;
  double min = 0.0;
  double mean = 0.0;
  double max = 0.0;
};

/// Per-field summary over meshes (fields in metric_fields order); empty for no meshes.
std::vector<FieldSummary> summarize(const std::vector<MeshMetrics>& metrics);

/// JSON object grouping the fields ({"isometry": {...}, ..., "creases": {..., "line_lengths":
/// [...]}}).
nlohmann::json to_json(const MeshMetrics& metrics);

/// Human-readable table of one mesh: group, figure, value, one row per field.
void write_table(std::ostream& out, const MeshMetrics& metrics);

/// CSV header: "mesh" followed by the metric_fields names.
void write_csv_header(std::ostream& out);

/// One CSV row: mesh name (quoted when needed) and the metric_fields values.
void write_csv_row(std::ostream& out, const std::string& mesh_name, const MeshMetrics& metrics);

}  // namespace papersim::validation
