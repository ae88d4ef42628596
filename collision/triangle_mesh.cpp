#include "collision/triangle_mesh.hpp"

#include <Eigen/Geometry>
#include <fstream>
#include <map>
#include <sstream>
#include <utility>

#include "collision/errors.hpp"

namespace papersim::collision {

namespace {

[[noreturn]] void parse_error(const std::string& path, int line, const std::string& what) {
  throw ColliderIoError("OBJ file '" + path + "', line " + std::to_string(line) + ": " + what);
}

/// Parses the vertex index of an `f` token ("7", "7/1", "7//3", "-1") to 0-based.
int face_index(const std::string& token, int vertex_count, const std::string& path, int line) {
  int index = 0;
  try {
    index = std::stoi(token.substr(0, token.find('/')));
  } catch (const std::exception&) {
    parse_error(path, line, "bad face index '" + token + "'");
  }
  const int resolved = index < 0 ? vertex_count + index : index - 1;
  if (index == 0 || resolved < 0 || resolved >= vertex_count)
    parse_error(path, line,
                "face index " + token + " out of range (" + std::to_string(vertex_count) +
                    " vertices so far)");
  return resolved;
}

}  // namespace

TriangleMesh read_obj(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ColliderIoError("cannot open OBJ file '" + path + "'");
  TriangleMesh mesh;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    std::istringstream is(text);
    std::string tag;
    if (!(is >> tag)) continue;
    if (tag == "v") {
      Eigen::Vector3d p;
      if (!(is >> p.x() >> p.y() >> p.z())) parse_error(path, line, "bad vertex record");
      mesh.vertices.push_back(p);
    } else if (tag == "f") {
      std::vector<int> poly;
      for (std::string token; is >> token;)
        poly.push_back(face_index(token, static_cast<int>(mesh.vertices.size()), path, line));
      if (poly.size() < 3) parse_error(path, line, "face with fewer than 3 vertices");
      for (size_t k = 1; k + 1 < poly.size(); ++k)
        mesh.triangles.emplace_back(poly[0], poly[k], poly[k + 1]);
    }
  }
  if (mesh.triangles.empty()) throw ColliderIoError("OBJ file '" + path + "' holds no face");
  return mesh;
}

void check_closed(const TriangleMesh& mesh, const std::string& name) {
  for (size_t v = 0; v < mesh.vertices.size(); ++v)
    if (!mesh.vertices[v].allFinite())
      throw ColliderError("mesh '" + name + "': vertex " + std::to_string(v) + " is not finite");
  std::map<std::pair<int, int>, int> edge_count;
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Eigen::Vector3i& t = mesh.triangles[f];
    if (t.minCoeff() < 0 || t.maxCoeff() >= static_cast<int>(mesh.vertices.size()))
      throw ColliderError("mesh '" + name + "': triangle " + std::to_string(f) +
                          " has a vertex index out of range");
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
      throw ColliderError("mesh '" + name + "': triangle " + std::to_string(f) +
                          " repeats a vertex");
    for (int e = 0; e < 3; ++e) ++edge_count[std::minmax(t[e], t[(e + 1) % 3])];
  }
  for (const auto& [edge, count] : edge_count)
    if (count != 2)
      throw ColliderError("mesh '" + name + "' is not closed: edge (" +
                          std::to_string(edge.first + 1) + ", " + std::to_string(edge.second + 1) +
                          ") (1-based) is shared by " + std::to_string(count) +
                          " triangles instead of 2");
}

Aabb mesh_bounds(const TriangleMesh& mesh) {
  Aabb b;
  for (const Eigen::Vector3d& p : mesh.vertices) b.extend(p);
  return b;
}

double mesh_area(const TriangleMesh& mesh) {
  double area = 0.0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.vertices[t[0]];
    area += 0.5 * (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a).norm();
  }
  return area;
}

}  // namespace papersim::collision
