#include "scenegen/sheet_obj.hpp"

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <vector>

#include "scenegen/errors.hpp"
#include "scenegen/limits.hpp"

namespace papersim::scenegen {
namespace {

struct Corner {
  int v = -1;
  int t = -1;
};

[[noreturn]] void fail(const std::string& source, int line, const std::string& what) {
  throw InputError(source + ":" + std::to_string(line) + ": " + what);
}

int resolve_index(long idx, std::size_t count, const std::string& source, int line) {
  const long n = static_cast<long>(count);
  const long resolved = idx > 0 ? idx - 1 : n + idx;
  if (idx == 0 || resolved < 0 || resolved >= n)
    fail(source, line, "index " + std::to_string(idx) + " out of range");
  return static_cast<int>(resolved);
}

Corner parse_corner(const std::string& token, std::size_t nv, std::size_t nt,
                    const std::string& source, int line) {
  Corner c;
  const auto slash = token.find('/');
  try {
    c.v = resolve_index(std::stol(token.substr(0, slash)), nv, source, line);
    if (slash == std::string::npos) return c;
    const auto rest = token.substr(slash + 1);
    const auto slash2 = rest.find('/');
    const auto vt = rest.substr(0, slash2);
    if (!vt.empty()) c.t = resolve_index(std::stol(vt), nt, source, line);
  } catch (const std::logic_error&) {
    fail(source, line, "malformed face corner '" + token + "'");
  }
  return c;
}

/// Least-squares fit of (width^2, height^2) to |dx|^2 = W^2 du^2 + H^2 dv^2 over face edges.
void fit_size(SheetMesh& mesh, const std::string& source) {
  Eigen::Matrix2d ata = Eigen::Matrix2d::Zero();
  Eigen::Vector2d atb = Eigen::Vector2d::Zero();
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.faces(f, k), b = mesh.faces(f, (k + 1) % 3);
      const Eigen::Vector2d row = (mesh.uv.row(b) - mesh.uv.row(a)).array().square();
      const double rhs = (mesh.positions.row(b) - mesh.positions.row(a)).squaredNorm();
      ata += row * row.transpose();
      atb += row * rhs;
    }
  const Eigen::Vector2d sq = ata.ldlt().solve(atb);
  if (!(sq.x() > 0.0) || !(sq.y() > 0.0))
    throw InputError(source +
                     ": cannot fit the sheet size from the mesh (add a '# papersim "
                     "sheet WIDTH HEIGHT' header)");
  mesh.width = std::sqrt(sq.x());
  mesh.height = std::sqrt(sq.y());
  if (!(mesh.width >= MIN_SHEET_SIZE && mesh.height >= MIN_SHEET_SIZE))
    throw InputError(source + ": the fitted sheet size is below the limit of 1e-4 m");
}

void check_and_orient(SheetMesh& mesh, const std::string& source) {
  if (mesh.num_faces() == 0) throw InputError(source + ": mesh has no faces");
  if (!mesh.positions.allFinite()) throw InputError(source + ": non-finite vertex position");
  if (mesh.positions.cwiseAbs().maxCoeff() > MAX_MESH_COORDINATE)
    throw InputError(source + ": a vertex coordinate exceeds the limit of " +
                     std::to_string(static_cast<int>(MAX_MESH_COORDINATE)) + " m");
  for (int i = 0; i < mesh.num_vertices(); ++i)
    for (int k = 0; k < 2; ++k) {
      const double t = mesh.uv(i, k);
      if (!(t >= -1e-9 && t <= 1.0 + 1e-9))
        throw InputError(source + ": vt of vertex " + std::to_string(i + 1) + " outside [0, 1]");
      mesh.uv(i, k) = std::min(1.0, std::max(0.0, t));
    }
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector2d a = mesh.uv.row(mesh.faces(f, 0));
    const Eigen::Vector2d e1 = Eigen::Vector2d(mesh.uv.row(mesh.faces(f, 1))) - a;
    const Eigen::Vector2d e2 = Eigen::Vector2d(mesh.uv.row(mesh.faces(f, 2))) - a;
    const double area2 = e1.x() * e2.y() - e1.y() * e2.x();
    if (std::abs(area2) < 1e-14)
      throw InputError(source + ": face " + std::to_string(f + 1) + " has zero UV area");
    if (area2 < 0.0) std::swap(mesh.faces(f, 1), mesh.faces(f, 2));
  }
}

}  // namespace

SheetMesh parse_sheet_obj(std::istream& in, const std::string& source) {
  SheetMesh mesh;
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector2d> vt;
  std::vector<std::array<Corner, 3>> tris;
  std::string line_text;
  int line = 0;
  while (std::getline(in, line_text)) {
    ++line;
    std::istringstream ls(line_text);
    std::string key;
    if (!(ls >> key)) continue;
    if (key == "#") {
      std::string w1, w2;
      double width = 0, height = 0;
      if (line == 1 && (ls >> w1 >> w2) && w1 == "papersim" && w2 == "sheet") {
        if (!(ls >> width >> height) || !(width > 0) || !(height > 0))
          fail(source, line, "malformed '# papersim sheet WIDTH HEIGHT' header");
        if (width < MIN_SHEET_SIZE || height < MIN_SHEET_SIZE || width > MAX_MESH_COORDINATE ||
            height > MAX_MESH_COORDINATE)
          fail(source, line, "sheet size outside the limits [1e-4, 1000] m");
        mesh.width = width;
        mesh.height = height;
        mesh.size_from_header = true;
      }
    } else if (key == "v") {
      if (static_cast<long>(v.size()) >= MAX_MESH_VERTICES)
        fail(source, line,
             "more than " + std::to_string(MAX_MESH_VERTICES) + " vertices (the limit)");
      Eigen::Vector3d p;
      if (!(ls >> p.x() >> p.y() >> p.z())) fail(source, line, "malformed 'v' line");
      v.push_back(p);
    } else if (key == "vt") {
      if (static_cast<long>(vt.size()) >= MAX_MESH_VERTICES)
        fail(source, line,
             "more than " + std::to_string(MAX_MESH_VERTICES) + " vt lines (the limit)");
      Eigen::Vector2d t;
      if (!(ls >> t.x() >> t.y())) fail(source, line, "malformed 'vt' line");
      vt.push_back(t);
    } else if (key == "f") {
      std::vector<Corner> poly;
      std::string tok;
      while (ls >> tok) poly.push_back(parse_corner(tok, v.size(), vt.size(), source, line));
      if (poly.size() < 3) fail(source, line, "face with fewer than 3 corners");
      if (static_cast<long>(tris.size() + poly.size() - 2) > MAX_MESH_FACES)
        fail(source, line,
             "more than " + std::to_string(MAX_MESH_FACES) + " triangles (the limit)");
      for (std::size_t k = 1; k + 1 < poly.size(); ++k)
        tris.push_back({poly[0], poly[k], poly[k + 1]});
    } else if (key[0] == '#') {
      continue;
    }
  }
  if (in.bad()) throw IoError(source + ": read error");
  if (v.empty()) throw InputError(source + ": no vertices (not an OBJ mesh?)");
  if (vt.empty())
    throw InputError(source +
                     ": mesh has no texture coordinates (vt); scenegen needs the "
                     "sheet's material coordinates as UV");
  mesh.positions.resize(static_cast<long>(v.size()), 3);
  mesh.uv.setConstant(static_cast<long>(v.size()), 2, -1.0);
  mesh.faces.resize(static_cast<long>(tris.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) mesh.positions.row(static_cast<long>(i)) = v[i];
  for (std::size_t f = 0; f < tris.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Corner c = tris[f][k];
      if (c.t < 0) throw InputError(source + ": face " + std::to_string(f + 1) + " has no vt");
      const long row = c.v;
      if (mesh.uv(row, 0) < -0.5) {
        mesh.uv.row(row) = vt[static_cast<std::size_t>(c.t)];
      } else if ((Eigen::Vector2d(mesh.uv.row(row)) - vt[static_cast<std::size_t>(c.t)]).norm() >
                 1e-12) {
        throw InputError(source + ": vertex " + std::to_string(c.v + 1) +
                         " has two different vt (a sheet needs one UV per vertex)");
      }
      mesh.faces(static_cast<long>(f), k) = c.v;
    }
  for (long i = 0; i < mesh.uv.rows(); ++i)
    if (mesh.uv(i, 0) < -0.5)
      throw InputError(source + ": vertex " + std::to_string(i + 1) +
                       " is used by no face (a truncated file?)");
  check_and_orient(mesh, source);
  if (!mesh.size_from_header) fit_size(mesh, source);
  return mesh;
}

SheetMesh read_sheet_obj(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError("cannot open mesh '" + path + "'");
  return parse_sheet_obj(in, path);
}

void write_sheet_obj(std::ostream& out, const SheetMesh& mesh) {
  out << std::setprecision(17) << "# papersim sheet " << mesh.width << ' ' << mesh.height << '\n';
  for (int i = 0; i < mesh.num_vertices(); ++i)
    out << "v " << mesh.positions(i, 0) << ' ' << mesh.positions(i, 1) << ' '
        << mesh.positions(i, 2) << '\n';
  for (int i = 0; i < mesh.num_vertices(); ++i)
    out << "vt " << mesh.uv(i, 0) << ' ' << mesh.uv(i, 1) << '\n';
  for (int f = 0; f < mesh.num_faces(); ++f) {
    out << 'f';
    for (int k = 0; k < 3; ++k) out << ' ' << mesh.faces(f, k) + 1 << '/' << mesh.faces(f, k) + 1;
    out << '\n';
  }
}

}  // namespace papersim::scenegen
