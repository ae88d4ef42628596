#include "remesh/sheet_io.hpp"

#include <Eigen/Cholesky>
#include <cerrno>
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

#include "common/atomic_file.hpp"
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

/// A 1-based (or negative, relative) OBJ index into `count` elements, as a 0-based index.
int parse_obj_index(const std::string& token, int count, const std::string& where) {
  errno = 0;
  char* end = nullptr;
  const long i = std::strtol(token.c_str(), &end, 10);
  if (token.empty() || *end != '\0' || errno == ERANGE)
    parse_error(where, "bad face index '" + token + "'");
  const long idx = i > 0 ? i - 1 : count + i;
  if (i == 0 || idx < 0 || idx >= count)
    parse_error(where, "face index " + token + " out of range");
  return static_cast<int>(idx);
}

/// A sheet size from a file header: positive, finite and within MAX_SHEET_COORDINATE.
void check_size(double width, double height, const std::string& where) {
  if (width == 0 && height == 0) return;  // none given
  if (!(width > 0 && width <= MAX_SHEET_COORDINATE && height > 0 && height <= MAX_SHEET_COORDINATE))
    parse_error(where,
                "sheet size must be in (0, " + std::to_string(int(MAX_SHEET_COORDINATE)) + "] m");
}

void check_positions(const Eigen::MatrixX3d& x, const std::string& path) {
  if (!x.allFinite()) throw MeshError(path + ": vertex positions contain NaN or inf");
  if (x.size() > 0 && x.cwiseAbs().maxCoeff() > MAX_SHEET_COORDINATE)
    throw MeshError(path + ": a vertex coordinate exceeds the limit of 1e6 m");
}

SheetData read_obj(std::istream& in, const std::string& path) {
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector2d> vt;
  std::vector<Eigen::Vector3i> fv, ft;
  double width = 0, height = 0;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string where = path + ":" + std::to_string(line_no);
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "#") {
      std::string a, b;
      ls >> a >> b;
      if (a == "papersim" && b == "sheet") {
        if (!(ls >> width >> height))
          parse_error(where, "malformed '# papersim sheet WIDTH HEIGHT'");
        check_size(width, height, where);
      }
    } else if (tag == "v") {
      if (static_cast<long>(v.size()) >= MAX_SHEET_VERTICES)
        throw MeshError(path + ": more than " + std::to_string(MAX_SHEET_VERTICES) +
                        " vertices (the limit of a sheet file)");
      // strtod, unlike operator>>, reads "nan" and "inf", which are then rejected as such.
      Eigen::Vector3d p;
      std::string tok[3];
      if (!(ls >> tok[0] >> tok[1] >> tok[2])) parse_error(where, "bad vertex line: " + line);
      for (int k = 0; k < 3; ++k) {
        char* end = nullptr;
        p[k] = std::strtod(tok[k].c_str(), &end);
        if (end == tok[k].c_str()) parse_error(where, "bad vertex line: " + line);
      }
      v.push_back(p);
    } else if (tag == "vt") {
      if (static_cast<long>(vt.size()) >= MAX_SHEET_VERTICES)
        throw MeshError(path + ": more than " + std::to_string(MAX_SHEET_VERTICES) + " vt lines");
      Eigen::Vector2d t;
      if (!(ls >> t.x() >> t.y()) || !t.allFinite()) parse_error(where, "bad vt line: " + line);
      vt.push_back(t);
    } else if (tag == "f") {
      if (static_cast<long>(fv.size()) >= MAX_SHEET_FACES)
        throw MeshError(path + ": more than " + std::to_string(MAX_SHEET_FACES) +
                        " faces (the limit of a sheet file)");
      std::string tok;
      std::vector<int> iv, it;
      while (ls >> tok) {
        const auto slash = tok.find('/');
        iv.push_back(parse_obj_index(tok.substr(0, slash), static_cast<int>(v.size()), where));
        if (slash == std::string::npos) parse_error(where, "face without vt index: " + line);
        const auto slash2 = tok.find('/', slash + 1);
        it.push_back(parse_obj_index(tok.substr(slash + 1, slash2 - slash - 1),
                                     static_cast<int>(vt.size()), where));
      }
      if (iv.size() != 3) parse_error(where, "only triangles are supported: " + line);
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
      if (std::isnan(row(0)))
        row = t.transpose();
      else if ((row.transpose() - t).norm() > 1e-9)
        throw MeshError(path + ": vertex " + std::to_string(fv[f][k] + 1) +
                        " has two different vt (a seam); a sheet needs one vt per vertex");
    }
  for (int i = 0; i < uv.rows(); ++i)
    if (std::isnan(uv(i, 0)))
      throw MeshError(path + ": vertex " + std::to_string(i + 1) +
                      " is used by no face (a truncated file?)");
  SheetData data;
  data.positions.resize(v.size(), 3);
  for (size_t i = 0; i < v.size(); ++i) data.positions.row(i) = v[i].transpose();
  check_positions(data.positions, path);
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
    double d = 0;
    in >> d;
    return d;
  }
  auto get = [&](auto tag) {
    decltype(tag) x{};
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

SheetData read_ply(std::istream& in, const std::string& path) {
  std::string line, format;
  std::getline(in, line);
  if (line.rfind("ply", 0) != 0) parse_error(path, "not a PLY file");
  std::vector<PlyElement> elements;
  double width = 0, height = 0;
  bool header_done = false;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "format")
      ls >> format;
    else if (tag == "comment") {
      std::string a, b;
      ls >> a >> b;
      if (a == "papersim" && b == "sheet") {
        if (!(ls >> width >> height))
          parse_error(path, "malformed 'comment papersim sheet WIDTH HEIGHT'");
        check_size(width, height, path);
      }
    } else if (tag == "element") {
      PlyElement e;
      if (!(ls >> e.name >> e.count) || e.count < 0)
        parse_error(path, "malformed element line: " + line);
      const long limit = e.name == "vertex" ? MAX_SHEET_VERTICES : MAX_SHEET_FACES;
      if (e.count > limit)
        throw MeshError(path + ": element " + e.name + " has " + std::to_string(e.count) +
                        " entries, more than the limit of " + std::to_string(limit));
      elements.push_back(e);
    } else if (tag == "property") {
      if (elements.empty()) parse_error(path, "property before element");
      PlyProperty p;
      ls >> p.type;
      if (p.type == "list") ls >> p.count_type >> p.type;
      if (!(ls >> p.name)) parse_error(path, "malformed property line: " + line);
      if (elements.back().props.size() >= 32)
        parse_error(path, "more than 32 properties in an element");
      elements.back().props.push_back(p);
    } else if (tag == "end_header") {
      header_done = true;
      break;
    }
  }
  if (!header_done) parse_error(path, "no end_header (not a PLY file or truncated)");
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
          const double n = read_value(in, pr.count_type, binary);
          if (!in) parse_error(path, "truncated data in element " + e.name);
          if (n != 3) parse_error(path, "only triangles are supported");
          Eigen::Vector3i t;
          for (int k = 0; k < 3; ++k) {
            const double index = read_value(in, pr.type, binary);
            if (!(index >= 0 && index < MAX_SHEET_VERTICES) || index != std::floor(index))
              parse_error(path, "bad vertex index in element " + e.name);
            t[k] = static_cast<int>(index);
          }
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
  check_positions(data.positions, path);
  if (!data.velocities.allFinite()) throw MeshError(path + ": velocities contain NaN or inf");
  if (material.size() > 0 && material.cwiseAbs().maxCoeff() > MAX_SHEET_COORDINATE)
    throw MeshError(path + ": a material coordinate exceeds the limit of 1e6 m");
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

SheetData parse_sheet(std::istream& in, const std::string& source, SheetFormat format) {
  return format == SheetFormat::obj ? read_obj(in, source) : read_ply(in, source);
}

SheetData read_sheet(const std::string& path) {
  if (!std::filesystem::exists(path)) throw IoError(path + ": no such file");
  const bool obj = ends_with(path, ".obj");
  if (!obj && !ends_with(path, ".ply"))
    throw IoError(path + ": unknown mesh format (expected .obj or .ply)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open");
  return parse_sheet(in, path, obj ? SheetFormat::obj : SheetFormat::ply);
}

void write_sheet_file(const std::string& path, const SheetMesh& mesh,
                      const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities,
                      double width, double height) {
  const bool obj = ends_with(path, ".obj");
  if (!obj && !ends_with(path, ".ply"))
    throw IoError(path + ": unknown mesh format (expected .obj or .ply)");
  common::write_file_atomically(path, [&](std::ostream& out) {
    if (obj)
      write_obj(out, mesh, positions, width, height);
    else
      write_ply(out, mesh, positions, velocities, width, height);
  });
}

}  // namespace papersim::remesh
