// Writers of MeshMetrics: the flat field list (one source for CSV, JSON and tables).
#include <algorithm>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <ostream>
#include <sstream>

#include "validation/metrics.hpp"

namespace papersim::validation {
namespace {

using Fields = std::vector<std::pair<std::string, double>>;

void add_isometry(Fields& f, const IsometryMetrics& m) {
  f.insert(f.end(), {{"isometry.edge_strain_max", m.edge_strain_max},
                     {"isometry.edge_strain_mean", m.edge_strain_mean},
                     {"isometry.edge_strain_p99", m.edge_strain_p99},
                     {"isometry.edge_stretch_max", m.edge_stretch_max},
                     {"isometry.edge_compression_max", m.edge_compression_max},
                     {"isometry.s1_max", m.s1_max},
                     {"isometry.s2_min", m.s2_min},
                     {"isometry.stretch_max", m.stretch_max},
                     {"isometry.compression_max", m.compression_max},
                     {"isometry.stretch_p99", m.stretch_p99},
                     {"isometry.compression_p99", m.compression_p99},
                     {"isometry.area_change_max", m.area_change_max},
                     {"isometry.area_change_min", m.area_change_min},
                     {"isometry.area_change_mean", m.area_change_mean},
                     {"isometry.total_area_change", m.total_area_change}});
}

void add_developability(Fields& f, const DevelopabilityMetrics& m) {
  f.insert(f.end(), {{"developability.angle_defect_max", m.angle_defect_max},
                     {"developability.angle_defect_integral", m.angle_defect_integral},
                     {"developability.gauss_bonnet_residual", m.gauss_bonnet_residual},
                     {"developability.euler_characteristic", m.euler_characteristic},
                     {"developability.covariance_energy", m.covariance_energy},
                     {"developability.covariance_max", m.covariance_max}});
}

void add_creases(Fields& f, const CreaseMetrics& m) {
  f.insert(f.end(), {{"creases.threshold_deg", m.threshold_deg},
                     {"creases.edges", m.edges},
                     {"creases.lines", m.lines},
                     {"creases.junctions", m.junctions},
                     {"creases.total_length", m.total_length},
                     {"creases.length_min", m.length_min},
                     {"creases.length_median", m.length_median},
                     {"creases.length_mean", m.length_mean},
                     {"creases.length_max", m.length_max},
                     {"creases.log_length_mean", m.log_length_mean},
                     {"creases.log_length_std", m.log_length_std},
                     {"creases.sharpest_angle_deg", m.sharpest_angle_deg},
                     {"creases.has_plastic_data", m.has_plastic_data ? 1.0 : 0.0},
                     {"creases.plastic_lines", m.plastic_lines},
                     {"creases.plastic_length", m.plastic_length},
                     {"creases.elastic_length", m.elastic_length},
                     {"creases.log_normal_ks", m.log_normal_ks},
                     {"creases.junctions_valence_3", m.junction_degrees[0]},
                     {"creases.junctions_valence_4", m.junction_degrees[1]},
                     {"creases.junctions_valence_5_or_more", m.junction_degrees[2]},
                     {"creases.plastic_network_edges", m.plastic_network_edges},
                     {"creases.plastic_network_lines", m.plastic_network_lines},
                     {"creases.plastic_network_junctions", m.plastic_network_junctions},
                     {"creases.plastic_network_length", m.plastic_network_length},
                     {"creases.plastic_network_log_length_mean", m.plastic_network_log_length_mean},
                     {"creases.plastic_network_log_length_std", m.plastic_network_log_length_std},
                     {"creases.plastic_network_log_normal_ks", m.plastic_network_log_normal_ks}});
}

void add_quality(Fields& f, const QualityMetrics& m) {
  f.insert(f.end(), {{"quality.min_angle_deg", m.min_angle_deg},
                     {"quality.min_angle_world_deg", m.min_angle_world_deg},
                     {"quality.aspect_min", m.aspect_min},
                     {"quality.aspect_min_world", m.aspect_min_world},
                     {"quality.edge_length_min", m.edge_length_min},
                     {"quality.edge_length_max", m.edge_length_max},
                     {"quality.world_edge_length_min", m.world_edge_length_min},
                     {"quality.world_edge_length_max", m.world_edge_length_max}});
}

/// Fields that are counts print as integers.
bool is_count(const std::string& name) {
  static const char* const COUNTS[] = {
      "mesh.",         "euler_characteristic", "creases.edges", "creases.lines",
      "network_edges", "network_lines",        "junctions",     "plastic_lines",
      "has_plastic",   "self_intersection"};
  return std::any_of(std::begin(COUNTS), std::end(COUNTS),
                     [&](const char* c) { return name.find(c) != std::string::npos; });
}

std::string format_value(const std::string& name, double value) {
  std::ostringstream s;
  if (is_count(name))
    s << static_cast<long long>(value);
  else
    s << std::setprecision(6) << value;
  return s.str();
}

std::string csv_quote(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

}  // namespace

std::vector<std::pair<std::string, double>> metric_fields(const MeshMetrics& metrics) {
  Fields f{{"mesh.vertices", metrics.vertices},
           {"mesh.faces", metrics.faces},
           {"mesh.edges", metrics.edges},
           {"mesh.boundary_edges", metrics.boundary_edges}};
  add_isometry(f, metrics.isometry);
  add_developability(f, metrics.developability);
  add_creases(f, metrics.creases);
  add_quality(f, metrics.quality);
  f.emplace_back("self_intersection.pairs", metrics.self_intersections);
  return f;
}

std::vector<FieldSummary> summarize(const std::vector<MeshMetrics>& metrics) {
  std::vector<FieldSummary> summary;
  for (std::size_t i = 0; i < metrics.size(); ++i) {
    const Fields fields = metric_fields(metrics[i]);
    if (i == 0)
      for (const auto& [name, value] : fields) summary.push_back({name, value, 0.0, value});
    for (std::size_t k = 0; k < fields.size(); ++k) {
      summary[k].min = std::min(summary[k].min, fields[k].second);
      summary[k].max = std::max(summary[k].max, fields[k].second);
      summary[k].mean += fields[k].second / static_cast<double>(metrics.size());
    }
  }
  return summary;
}

nlohmann::json to_json(const MeshMetrics& metrics) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [name, value] : metric_fields(metrics)) {
    const std::size_t dot = name.find('.');
    const std::string group = name.substr(0, dot), key = name.substr(dot + 1);
    if (is_count(name))
      out[group][key] = static_cast<long long>(value);
    else
      out[group][key] = value;
  }
  out["creases"]["has_plastic_data"] = metrics.creases.has_plastic_data;
  nlohmann::json lengths = nlohmann::json::array();
  for (const CreaseLine& line : metrics.creases.crease_lines) lengths.push_back(line.length);
  out["creases"]["line_lengths"] = lengths;
  out["creases"]["plastic_network_line_lengths"] = metrics.creases.plastic_network_line_lengths;
  return out;
}

void write_table(std::ostream& out, const MeshMetrics& metrics) {
  const Fields fields = metric_fields(metrics);
  std::size_t width = 0;
  for (const auto& field : fields) width = std::max(width, field.first.size());
  for (const auto& [name, value] : fields)
    out << std::left << std::setw(static_cast<int>(width) + 2) << name << std::right
        << format_value(name, value) << '\n';
}

void write_csv_header(std::ostream& out) {
  out << "mesh";
  for (const auto& field : metric_fields(MeshMetrics{})) out << ',' << field.first;
  out << '\n';
}

void write_csv_row(std::ostream& out, const std::string& mesh_name, const MeshMetrics& metrics) {
  out << csv_quote(mesh_name);
  for (const auto& [name, value] : metric_fields(metrics)) {
    if (is_count(name)) {
      out << ',' << format_value(name, value);
    } else {
      std::ostringstream s;
      s << std::setprecision(std::numeric_limits<double>::max_digits10) << value;
      out << ',' << s.str();
    }
  }
  out << '\n';
}

}  // namespace papersim::validation
