#include "remesh/sheet_io.hpp"

#include <Eigen/Cholesky>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include "remesh/errors.hpp"

namespace papersim::remesh {

namespace {

void check_sizes(const SheetMesh& mesh, const Eigen::MatrixX3d& positions) {
  if (positions.rows() != mesh.num_vertices())
    throw MeshError("sheet writer: positions need one row per vertex");
}

bool ends_with(const std::string& s, const std::string& suffix) {
  if (s.size() < suffix.size()) return false;
  std::string tail = s.substr(s.size() - suffix.size());
  for (auto& c : tail) c = static_cast<char>(std::tolower(c));
  return tail == suffix;
}

}  // namespace

void write_obj(std::ostream& out, const SheetMesh& mesh, const Eigen::MatrixX3d& positions,
               double width, double height) {
  check_sizes(mesh, positions);
  out << "# papersim sheet " << std::setprecision(17) << width << ' ' << height << '\n';
  out << std::setprecision(9);
  for (int v = 0; v < positions.rows(); ++v)
    out << "v " << positions(v, 0) << ' ' << positions(v, 1) << ' ' << positions(v, 2) << '\n';
  out << std::setprecision(12);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector2d m = mesh.material_coord(v);
    out << "vt " << m.x() / width << ' ' << m.y() / height << '\n';
  }
  const Eigen::MatrixX3i faces = mesh.faces();
  for (int f = 0; f < faces.rows(); ++f) {
    out << 'f';
    for (int k = 0; k < 3; ++k) out << ' ' << faces(f, k) + 1 << '/' << faces(f, k) + 1;
    out << '\n';
  }
}

namespace {

template <class T>
void put(std::ostream& out, T value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));  // little-endian host (x86-64)
}

}  // namespace

void write_ply(std::ostream& out, const SheetMesh& mesh, const Eigen::MatrixX3d& positions,
               const Eigen::MatrixX3d& velocities, double width, double height) {
  check_sizes(mesh, positions);
  const bool has_vel = velocities.rows() == positions.rows();
  out << "ply\nformat binary_little_endian 1.0\n"
      << "comment papersim sheet " << std::setprecision(17) << width << ' ' << height << '\n'
      << "element vertex " << mesh.num_vertices() << '\n'
      << "property double x\nproperty double y\nproperty double z\n"
      << "property double mx\nproperty double my\n"
      << "property double vx\nproperty double vy\nproperty double vz\n"
      << "element face " << mesh.num_faces() << '\n'
      << "property list uchar int vertex_indices\n"
      << "property double kxx\nproperty double kyy\nproperty double kxy\nproperty double damage\n"
      << "end_header\n";
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector2d m = mesh.material_coord(v);
    for (int k = 0; k < 3; ++k) put<double>(out, positions(v, k));
    put<double>(out, m.x());
    put<double>(out, m.y());
    for (int k = 0; k < 3; ++k) put<double>(out, has_vel ? velocities(v, k) : 0.0);
  }
  const Eigen::MatrixX3i faces = mesh.faces();
  const Eigen::MatrixX3d plastic = mesh.plastic_curvature();
  const Eigen::VectorXd damage = mesh.damage();
  for (int f = 0; f < faces.rows(); ++f) {
    put<std::uint8_t>(out, 3);
    for (int k = 0; k < 3; ++k) put<std::int32_t>(out, faces(f, k));
    for (int k = 0; k < 3; ++k) put<double>(out, plastic(f, k));
    put<double>(out, damage(f));
  }
}

namespace {

[[noreturn]] void parse_error(const std::string& path, const std::string& what) {
  throw IoError(path + ": " + what);
}

/// Fit material scales (sx, sy) so that |x_j - x_i|^2 ~ sx^2 du^2 + sy^2 dv^2 over all edges.
Eigen::Vector2d fit_uv_scale(const Eigen::MatrixX3d& x, const Eigen::MatrixX2d& uv,
                             const Eigen::MatrixX3i& faces) {
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (int f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int i = faces(f, k), j = faces(f, (k + 1) % 3);
      const Eigen::Vector2d d2 = (uv.row(j) - uv.row(i)).array().square();
      A += d2 * d2.transpose();
      b += d2 * (x.row(j) - x.row(i)).squaredNorm();
    }
  const Eigen::Vector2d s2 = A.ldlt().solve(b);
  if (!(s2.x() > 0 && s2.y() > 0)) return {1.0, 1.0};
  return s2.cwiseSqrt();
}

int parse_obj_index(const std::string& token, int count, const std::string& path) {
  const int i = std::stoi(token);
  const int idx = i > 0 ? i - 1 : count + i;
  if (idx < 0 || idx >= count) parse_error(path, "face index " + token + " out of range");
  return idx;
}

SheetData read_obj(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError(path + ": cannot open");
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector2d> vt;
  std::vector<Eigen::Vector3i> fv, ft;
  double width = 0, height = 0;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "#") {
      std::string a, b;
      ls >> a >> b;
      if (a == "papersim" && b == "sheet") ls >> width >> height;
    } else if (tag == "v") {
      // strtod, unlike operator>>, reads "nan" and "inf", which are then rejected as such.
      Eigen::Vector3d p;
      std::string tok[3];
      if (!(ls >> tok[0] >> tok[1] >> tok[2])) parse_error(path, "bad vertex line: " + line);
      for (int k = 0; k < 3; ++k) {
        char* end = nullptr;
        p[k] = std::strtod(tok[k].c_str(), &end);
        if (end == tok[k].c_str()) parse_error(path, "bad vertex line: " + line);
      }
      v.push_back(p);
    } else if (tag == "vt") {
      Eigen::Vector2d t;
      if (!(ls >> t.x() >> t.y())) parse_error(path, "bad vt line: " + line);
      vt.push_back(t);
    } else if (tag == "f") {
      std::string tok;
      std::vector<int> iv, it;
      while (ls >> tok) {
        const auto slash = tok.find('/');
        iv.push_back(parse_obj_index(tok.substr(0, slash), static_cast<int>(v.size()), path));
        if (slash == std::string::npos) parse_error(path, "face without vt index: " + line);
        const auto slash2 = tok.find('/', slash + 1);
        it.push_back(parse_obj_index(tok.substr(slash + 1, slash2 - slash - 1),
                                     static_cast<int>(vt.size()), path));
      }
      if (iv.size() != 3) parse_error(path, "only triangles are supported: " + line);
      fv.emplace_back(iv[0], iv[1], iv[2]);
      ft.emplace_back(it[0], it[1], it[2]);
    }
  }
  if (v.empty() || fv.empty()) parse_error(path, "no vertices or faces");
  if (vt.empty()) throw MeshError(path + ": mesh has no texture coordinates (vt)");
  // One material coordinate per vertex: the vt index used with each v must agree.
  Eigen::MatrixX2d uv = Eigen::MatrixX2d::Constant(v.size(), 2, std::nan(""));
  for (size_t f = 0; f < fv.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d t = vt[ft[f][k]];
      auto row = uv.row(fv[f][k]);
      if (std::isnan(row(0))) row = t.transpose();
      else if ((row.transpose() - t).norm() > 1e-9)
        throw MeshError(path + ": vertex " + std::to_string(fv[f][k] + 1) +
                        " has two different vt (a seam); a sheet needs one vt per vertex");
    }
  if (!uv.allFinite()) throw MeshError(path + ": a vertex is used by no face or has NaN vt");
  SheetData data;
  data.positions.resize(v.size(), 3);
  for (size_t i = 0; i < v.size(); ++i) data.positions.row(i) = v[i].transpose();
  if (!data.positions.allFinite()) throw MeshError(path + ": vertex positions contain NaN or inf");
  Eigen::MatrixX3i faces(fv.size(), 3);
  for (size_t f = 0; f < fv.size(); ++f) faces.row(f) = fv[f].transpose();
  if (!(width > 0 && height > 0)) {
    const Eigen::Vector2d s = fit_uv_scale(data.positions, uv, faces);
    width = s.x();
    height = s.y();
  }
  Eigen::MatrixX2d material(uv.rows(), 2);
  material.col(0) = uv.col(0) * width;
  material.col(1) = uv.col(1) * height;
  try {
    data.mesh = SheetMesh(material, faces);
  } catch (const MeshError& e) {
    throw MeshError(path + ": " + e.what());
  }
  // SheetMesh orients faces; positions follow vertex indices, so nothing else changes.
  data.velocities = Eigen::MatrixX3d::Zero(v.size(), 3);
  data.width = width;
  data.height = height;
  return data;
}

struct PlyProperty {
  std::string name, type, count_type;  // count_type non-empty for lists
};
struct PlyElement {
  std::string name;
  long count = 0;
  std::vector<PlyProperty> props;
};

double read_value(std::istream& in, const std::string& type, bool binary) {
  if (!binary) {
    double d;
    in >> d;
    return d;
  }
  auto get = [&](auto tag) {
    decltype(tag) x;
    in.read(reinterpret_cast<char*>(&x), sizeof(x));
    return static_cast<double>(x);
  };
  if (type == "double" || type == "float64") return get(double{});
  if (type == "float" || type == "float32") return get(float{});
  if (type == "int" || type == "int32") return get(std::int32_t{});
  if (type == "uint" || type == "uint32") return get(std::uint32_t{});
  if (type == "uchar" || type == "uint8") return get(std::uint8_t{});
  if (type == "char" || type == "int8") return get(std::int8_t{});
  if (type == "short" || type == "int16") return get(std::int16_t{});
  if (type == "ushort" || type == "uint16") return get(std::uint16_t{});
  throw IoError("ply: unsupported property type " + type);
}

SheetData read_ply(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open");
  std::string line, format;
  std::getline(in, line);
  if (line.rfind("ply", 0) != 0) parse_error(path, "not a PLY file");
  std::vector<PlyElement> elements;
  double width = 0, height = 0;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "format") ls >> format;
    else if (tag == "comment") {
      std::string a, b;
      ls >> a >> b;
      if (a == "papersim" && b == "sheet") ls >> width >> height;
    } else if (tag == "element") {
      PlyElement e;
      ls >> e.name >> e.count;
      elements.push_back(e);
    } else if (tag == "property") {
      if (elements.empty()) parse_error(path, "property before element");
      PlyProperty p;
      ls >> p.type;
      if (p.type == "list") ls >> p.count_type >> p.type;
      ls >> p.name;
      elements.back().props.push_back(p);
    } else if (tag == "end_header") break;
  }
  const bool binary = format == "binary_little_endian";
  if (!binary && format != "ascii") parse_error(path, "unsupported PLY format '" + format + "'");
  SheetData data;
  Eigen::MatrixX2d material;
  Eigen::MatrixX3i faces;
  Eigen::MatrixX3d plastic;
  Eigen::VectorXd damage;
  bool has_material = false;
  for (const auto& e : elements) {
    std::vector<std::vector<double>> cols(e.props.size(), std::vector<double>(e.count));
    std::vector<Eigen::Vector3i> lists;
    for (long i = 0; i < e.count; ++i)
      for (size_t p = 0; p < e.props.size(); ++p) {
        const auto& pr = e.props[p];
        if (!pr.count_type.empty()) {
          const int n = static_cast<int>(read_value(in, pr.count_type, binary));
          if (n != 3) parse_error(path, "only triangles are supported");
          Eigen::Vector3i t;
          for (int k = 0; k < 3; ++k) t[k] = static_cast<int>(read_value(in, pr.type, binary));
          lists.push_back(t);
        } else {
          cols[p][i] = read_value(in, pr.type, binary);
        }
      }
    if (!in) parse_error(path, "truncated data in element " + e.name);
    auto col = [&](const std::string& name) -> const std::vector<double>* {
      for (size_t p = 0; p < e.props.size(); ++p)
        if (e.props[p].name == name) return &cols[p];
      return nullptr;
    };
    if (e.name == "vertex") {
      data.positions.resize(e.count, 3);
      data.velocities = Eigen::MatrixX3d::Zero(e.count, 3);
      material.resize(e.count, 2);
      const char* xyz[3] = {"x", "y", "z"};
      const char* vel[3] = {"vx", "vy", "vz"};
      for (int k = 0; k < 3; ++k) {
        const auto* c = col(xyz[k]);
        if (!c) parse_error(path, std::string("vertex property ") + xyz[k] + " missing");
        for (long i = 0; i < e.count; ++i) data.positions(i, k) = (*c)[i];
        if (const auto* cv = col(vel[k]))
          for (long i = 0; i < e.count; ++i) data.velocities(i, k) = (*cv)[i];
      }
      const auto* mx = col("mx");
      const auto* my = col("my");
      if (mx && my) {
        has_material = true;
        for (long i = 0; i < e.count; ++i) material.row(i) << (*mx)[i], (*my)[i];
      }
    } else if (e.name == "face") {
      faces.resize(lists.size(), 3);
      for (size_t f = 0; f < lists.size(); ++f) faces.row(f) = lists[f].transpose();
      plastic = Eigen::MatrixX3d::Zero(e.count, 3);
      damage = Eigen::VectorXd::Zero(e.count);
      const char* kn[3] = {"kxx", "kyy", "kxy"};
      for (int k = 0; k < 3; ++k)
        if (const auto* c = col(kn[k]))
          for (long i = 0; i < e.count; ++i) plastic(i, k) = (*c)[i];
      if (const auto* c = col("damage"))
        for (long i = 0; i < e.count; ++i) damage(i) = (*c)[i];
    }
  }
  if (!has_material) throw MeshError(path + ": PLY has no material coordinates (mx, my)");
  if (!data.positions.allFinite()) throw MeshError(path + ": vertex positions contain NaN or inf");
  try {
    data.mesh = SheetMesh(material, faces);
  } catch (const MeshError& e) {
    throw MeshError(path + ": " + e.what());
  }
  data.mesh.set_plastic_curvature(plastic);
  data.mesh.set_damage(damage);
  const Eigen::Vector4d b = data.mesh.material_bounds();
  data.width = width > 0 ? width : b[2];
  data.height = height > 0 ? height : b[3];
  return data;
}

}  // namespace

SheetData read_sheet(const std::string& path) {
  if (!std::filesystem::exists(path)) throw IoError(path + ": no such file");
  if (ends_with(path, ".obj")) return read_obj(path);
  if (ends_with(path, ".ply")) return read_ply(path);
  throw IoError(path + ": unknown mesh format (expected .obj or .ply)");
}

void write_sheet_file(const std::string& path, const SheetMesh& mesh,
                      const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities,
                      double width, double height) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw IoError(path + ": cannot write");
    if (ends_with(path, ".obj")) write_obj(out, mesh, positions, width, height);
    else if (ends_with(path, ".ply")) write_ply(out, mesh, positions, velocities, width, height);
    else throw IoError(path + ": unknown mesh format (expected .obj or .ply)");
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw IoError(path + ": write failed");
    }
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace papersim::remesh
