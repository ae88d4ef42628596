#include "scenegen/contact_shadow.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

#include "scenegen/errors.hpp"

namespace papersim::scenegen {
namespace {

constexpr double PI = 3.14159265358979323846;
constexpr int MAX_FIELD_SIDE = 4096;

struct StagePoint {
  double x, y, h;  ///< stage coordinates [m], h above the table
};

void mark(SheetHeightField& f, int i, int j, double h) {
  if (i < 0 || j < 0 || i >= f.width || j >= f.height) return;
  const std::size_t k = std::size_t(j) * f.width + i;
  f.lo[k] = std::min(f.lo[k], static_cast<float>(h));
  f.hi[k] = std::max(f.hi[k], static_cast<float>(h));
}

/// Cell centres inside the triangle's projection (edges included) take its interpolated height.
void fill_triangle(SheetHeightField& f, const StagePoint (&p)[3]) {
  const double det = (p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[2].x - p[0].x) * (p[1].y - p[0].y);
  if (std::abs(det) < 1e-18) return;  // seen edge-on: its edges mark its cells
  const double lx = std::min({p[0].x, p[1].x, p[2].x}), hx = std::max({p[0].x, p[1].x, p[2].x});
  const double ly = std::min({p[0].y, p[1].y, p[2].y}), hy = std::max({p[0].y, p[1].y, p[2].y});
  const int i0 = std::max(0, static_cast<int>(std::ceil((lx - f.x0) / f.cell - 0.5)));
  const int i1 = std::min(f.width - 1, static_cast<int>(std::floor((hx - f.x0) / f.cell - 0.5)));
  const int j0 = std::max(0, static_cast<int>(std::ceil((ly - f.y0) / f.cell - 0.5)));
  const int j1 = std::min(f.height - 1, static_cast<int>(std::floor((hy - f.y0) / f.cell - 0.5)));
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const double x = f.x0 + (i + 0.5) * f.cell, y = f.y0 + (j + 0.5) * f.cell;
      const double w1 = ((x - p[0].x) * (p[2].y - p[0].y) - (p[2].x - p[0].x) * (y - p[0].y)) / det;
      const double w2 = ((p[1].x - p[0].x) * (y - p[0].y) - (x - p[0].x) * (p[1].y - p[0].y)) / det;
      const double eps = 1e-12;
      if (w1 < -eps || w2 < -eps || w1 + w2 > 1.0 + eps) continue;
      mark(f, i, j, (1.0 - w1 - w2) * p[0].h + w1 * p[1].h + w2 * p[2].h);
    }
}

/// Points along the edge, half a cell apart, mark the cells they fall in.
void mark_edge(SheetHeightField& f, const StagePoint& a, const StagePoint& b) {
  const double len = std::hypot(b.x - a.x, b.y - a.y);
  const int n = 1 + static_cast<int>(std::ceil(2.0 * len / f.cell));
  for (int k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) / n;
    const double x = a.x + t * (b.x - a.x), y = a.y + t * (b.y - a.y);
    mark(f, static_cast<int>(std::floor((x - f.x0) / f.cell)),
         static_cast<int>(std::floor((y - f.y0) / f.cell)), a.h + t * (b.h - a.h));
  }
}

/// Chebyshev distance [cells] from every cell to the nearest covered cell (two chamfer passes;
/// 0 on covered cells, capped at `cap`): no point closer than (d - 1) cells to a cell's centre
/// lies under the sheet, which lets a march skip empty table.
std::vector<int> distance_to_sheet(const SheetHeightField& f, int cap) {
  std::vector<int> d(std::size_t(f.width) * f.height, cap);
  const auto at = [&](int i, int j) -> int& { return d[std::size_t(j) * f.width + i]; };
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) {
      if (f.covered(i, j)) {
        at(i, j) = 0;
        continue;
      }
      int& v = at(i, j);
      if (i > 0) v = std::min(v, at(i - 1, j) + 1);
      if (j > 0) {
        v = std::min(v, at(i, j - 1) + 1);
        if (i > 0) v = std::min(v, at(i - 1, j - 1) + 1);
        if (i + 1 < f.width) v = std::min(v, at(i + 1, j - 1) + 1);
      }
    }
  for (int j = f.height; j-- > 0;)
    for (int i = f.width; i-- > 0;) {
      int& v = at(i, j);
      if (i + 1 < f.width) v = std::min(v, at(i + 1, j) + 1);
      if (j + 1 < f.height) {
        v = std::min(v, at(i, j + 1) + 1);
        if (i + 1 < f.width) v = std::min(v, at(i + 1, j + 1) + 1);
        if (i > 0) v = std::min(v, at(i - 1, j + 1) + 1);
      }
    }
  return d;
}

/// What a march needs besides the field.
struct March {
  std::vector<double> cx, cy;  ///< unit directions
  std::vector<int> dist;       ///< distance_to_sheet
  double top = 0.0;            ///< highest point of the sheet above the table [m]
};

/// Blocked part of one direction's cosine-weighted half-disc at cell (i, j) (see
/// contact_occlusion). Stops early once farther cells cannot change it by more than 1e-3.
double blocked_along(const SheetHeightField& f, const ContactParams& params, const March& m, int i,
                     int j, int k) {
  constexpr double TOL = 1e-3;
  const double inf = std::numeric_limits<double>::infinity();
  const double x = (i + 0.5) * f.cell, y = (j + 0.5) * f.cell;  // relative to (x0, y0)
  const std::size_t own = std::size_t(j) * f.width + i;
  // Under the sheet (the cell itself covered) the sheet is straight above: b = inf; the own
  // cell's sheet leaves the sky free below the elevation of the cell's edge.
  const bool under = f.covered(i, j);
  double a = under ? std::max(0.0, static_cast<double>(f.lo[own])) / (0.5 * f.cell) : inf;
  double b = under ? inf : -inf;
  const double dx = m.cx[static_cast<std::size_t>(k)], dy = m.cy[static_cast<std::size_t>(k)];
  // Half a cell apart near the point (the contact line is a few cells wide), then 10% of the
  // distance (far parts of the sheet subtend small angles).
  for (double r = 0.5 * f.cell; r <= params.reach; r += std::max(0.5 * f.cell, 0.1 * r)) {
    const int ci = static_cast<int>(std::floor((x + r * dx) / f.cell));
    const int cj = static_cast<int>(std::floor((y + r * dy) / f.cell));
    if (ci < 0 || cj < 0 || ci >= f.width || cj >= f.height) break;
    if (ci == i && cj == j) continue;
    const std::size_t c = std::size_t(cj) * f.width + ci;
    if (!(f.lo[c] <= f.hi[c])) {
      // Empty table: no covered cell within (dist - 1) cells of this one's centre.
      r += std::max(0.0, (m.dist[c] - 1.5) * f.cell);
      continue;
    }
    a = std::min(a, std::max(0.0, static_cast<double>(f.lo[c])) / r);
    b = std::max(b, std::max(0.0, static_cast<double>(f.hi[c])) / r);
    // Farther cells can raise b only to top / r and lower a by at most 1 - 1 / (1 + a^2) ~ a^2.
    if (a * a < TOL && (b == inf || m.top / r <= b)) break;
  }
  if (!(a <= b)) return 0.0;
  return 1.0 / (1.0 + a * a) - (b == inf ? 0.0 : 1.0 / (1.0 + b * b));
}

/// A cell under a part of the sheet that rests on the table (at most 2 gaps above it) with its
/// 8 neighbours covered too: its table is hidden from the camera (it would have to look under
/// the sheet at less than 27 degrees from the table) and all but a sliver of its sky is covered
/// (below 2 gaps over 1.5 cells); it is taken as fully occluded without a march.
bool resting_inside(const SheetHeightField& f, const ContactParams& params, int i, int j) {
  if (i == 0 || j == 0 || i + 1 == f.width || j + 1 == f.height) return false;
  if (!(f.lo[std::size_t(j) * f.width + i] <= 2.0 * params.gap)) return false;
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di)
      if (!f.covered(i + di, j + dj)) return false;
  return true;
}

/// Occlusion of the cells of rows [row_begin, row_end).
void occlude_rows(const SheetHeightField& f, const ContactParams& params, const March& m,
                  int row_begin, int row_end, std::vector<float>& out) {
  const int n_az = static_cast<int>(m.cx.size());
  const double reach_cells = params.reach / f.cell;
  for (int j = row_begin; j < row_end; ++j)
    for (int i = 0; i < f.width; ++i) {
      if (m.dist[std::size_t(j) * f.width + i] - 1 > reach_cells)
        continue;  // no sheet within reach
      if (resting_inside(f, params, i, j)) {
        out[std::size_t(j) * f.width + i] = 1.0f;
        continue;
      }
      double blocked = 0.0;
      for (int k = 0; k < n_az; ++k) blocked += blocked_along(f, params, m, i, j, k);
      out[std::size_t(j) * f.width + i] = static_cast<float>(std::clamp(blocked / n_az, 0.0, 1.0));
    }
}

}  // namespace

ContactParams contact_params_for(double extent) {
  ContactParams p;
  p.cell = std::max(p.cell, extent / 1600.0);
  p.reach = std::max(p.reach, 80.0 * p.cell);
  return p;
}

SheetHeightField sheet_height_field(const SheetMesh& surface, const Stage& stage,
                                    const ContactParams& params) {
  if (surface.num_vertices() == 0 || surface.num_faces() == 0)
    throw InputError("contact shadow: empty mesh");
  if (!(params.cell > 0.0) || !(params.reach >= 0.0))
    throw InputError("contact shadow: cell must be > 0 and reach >= 0");
  std::vector<StagePoint> pts(static_cast<std::size_t>(surface.num_vertices()));
  double lx = std::numeric_limits<double>::infinity(), hx = -lx, ly = lx, hy = -lx;
  for (int v = 0; v < surface.num_vertices(); ++v) {
    const Eigen::Vector3d d = surface.positions.row(v).transpose() - stage.origin;
    StagePoint& p = pts[static_cast<std::size_t>(v)];
    p = {d.dot(stage.ex), d.dot(stage.ey), d.dot(stage.up) + params.gap};
    lx = std::min(lx, p.x), hx = std::max(hx, p.x), ly = std::min(ly, p.y), hy = std::max(hy, p.y);
  }
  SheetHeightField f;
  f.cell = params.cell;
  const double w = (hx - lx + 2.0 * params.reach) / f.cell,
               h = (hy - ly + 2.0 * params.reach) / f.cell;
  if (!(w < MAX_FIELD_SIDE - 1) || !(h < MAX_FIELD_SIDE - 1))
    throw InputError("contact shadow: the map would exceed " + std::to_string(MAX_FIELD_SIDE) +
                     " cells per side");
  f.width = static_cast<int>(std::ceil(w)) + 1;
  f.height = static_cast<int>(std::ceil(h)) + 1;
  f.x0 = lx - params.reach;
  f.y0 = ly - params.reach;
  const std::size_t n = std::size_t(f.width) * f.height;
  f.lo.assign(n, std::numeric_limits<float>::infinity());
  f.hi.assign(n, -std::numeric_limits<float>::infinity());
  for (int t = 0; t < surface.num_faces(); ++t) {
    const StagePoint tri[3] = {pts[static_cast<std::size_t>(surface.faces(t, 0))],
                               pts[static_cast<std::size_t>(surface.faces(t, 1))],
                               pts[static_cast<std::size_t>(surface.faces(t, 2))]};
    fill_triangle(f, tri);
    for (int e = 0; e < 3; ++e) mark_edge(f, tri[e], tri[(e + 1) % 3]);
  }
  return f;
}

std::vector<float> contact_occlusion(const SheetHeightField& field, const ContactParams& params,
                                     int threads) {
  std::vector<float> out(std::size_t(field.width) * field.height, 0.0f);
  March m;
  const int n_az = std::max(1, params.azimuths);
  for (int k = 0; k < n_az; ++k) {
    const double theta = 2.0 * PI * (k + 0.5) / n_az;
    m.cx.push_back(std::cos(theta));
    m.cy.push_back(std::sin(theta));
  }
  m.dist = distance_to_sheet(field, field.width + field.height);
  for (std::size_t c = 0; c < field.hi.size(); ++c)
    if (field.lo[c] <= field.hi[c]) m.top = std::max(m.top, static_cast<double>(field.hi[c]));
  int t =
      threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  t = std::clamp(t, 1, std::max(1, field.height));
  // Each cell is computed on its own, so the split over threads does not change any value.
  std::vector<std::thread> pool;
  for (int k = 1; k < t; ++k)
    pool.emplace_back([&, k] {
      occlude_rows(field, params, m, k * field.height / t, (k + 1) * field.height / t, out);
    });
  occlude_rows(field, params, m, 0, field.height / t, out);
  for (auto& th : pool) th.join();
  return out;
}

void write_contact_png(const std::string& path, const SheetHeightField& field,
                       const std::vector<float>& occlusion) {
  ImageF img(field.width, field.height, 1);
  for (int j = 0; j < field.height; ++j)
    for (int i = 0; i < field.width; ++i)
      img.at(i, field.height - 1 - j, 0) = occlusion[std::size_t(j) * field.width + i];
  write_png(path, img, 16);
}

}  // namespace papersim::scenegen
