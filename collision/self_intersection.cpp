#include "collision/self_intersection.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace papersim::collision {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Segment = Kernel::Segment_3;
using Triangle = Kernel::Triangle_3;

enum class PairKind { disjoint, vertex, edge };

void check_input(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces) {
  if (!positions.allFinite())
    throw std::invalid_argument("self-intersection: positions contain NaN or infinity");
  const int n = static_cast<int>(positions.rows());
  if (faces.size() > 0 && (faces.minCoeff() < 0 || faces.maxCoeff() >= n))
    throw std::invalid_argument("self-intersection: face index out of range [0, " +
                                std::to_string(n) + ")");
}

std::vector<Point> to_points(const Eigen::MatrixX3d& positions) {
  std::vector<Point> points;
  points.reserve(positions.rows());
  for (Eigen::Index v = 0; v < positions.rows(); ++v)
    points.emplace_back(positions(v, 0), positions(v, 1), positions(v, 2));
  return points;
}

/// Closed axis-aligned box of a face.
struct Box {
  Eigen::Array3d lo, hi;
  bool overlaps(const Box& o) const { return (lo <= o.hi).all() && (o.lo <= hi).all(); }
};

std::vector<Box> face_boxes(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces) {
  std::vector<Box> boxes(static_cast<std::size_t>(faces.rows()));
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::Array3d a = positions.row(faces(f, 0)).transpose().array();
    const Eigen::Array3d b = positions.row(faces(f, 1)).transpose().array();
    const Eigen::Array3d c = positions.row(faces(f, 2)).transpose().array();
    boxes[f] = {a.min(b).min(c), a.max(b).max(c)};
  }
  return boxes;
}

/// A uniform grid over the boxes, cells twice the mean box size. A box is listed in every
/// cell it touches; a pair is reported only in the first cell both touch (the cell of the
/// larger lower corner), so each overlapping pair comes out once. cell(x) = floor((x - origin)
/// / size) is monotone, so two overlapping boxes always share that cell. Boxes touching more
/// than MAX_CELLS cells (long slivers) are tested against all boxes instead.
class Grid {
 public:
  static constexpr long MAX_CELLS = 512;
  static constexpr int BITS = 21;  // cells per axis < 2^21

  explicit Grid(const std::vector<Box>& boxes) {
    Eigen::Array3d lo = Eigen::Array3d::Constant(HUGE_VAL), hi = -lo;
    double size = 0.0;
    for (const Box& b : boxes) {
      lo = lo.min(b.lo);
      hi = hi.max(b.hi);
      size += (b.hi - b.lo).maxCoeff();
    }
    m_origin = lo;
    const double span = boxes.empty() ? 1.0 : (hi - lo).maxCoeff();
    m_size = std::max(
        {2.0 * size / std::max<std::size_t>(1, boxes.size()), span / ((1 << BITS) - 2), 1e-300});
  }
  Eigen::Array3i cell(const Eigen::Array3d& x) const {
    return ((x - m_origin) / m_size).floor().cast<int>();
  }
  static std::uint64_t key(const Eigen::Array3i& c) {
    return (std::uint64_t(c(0)) << (2 * BITS)) | (std::uint64_t(c(1)) << BITS) |
           std::uint64_t(c(2));
  }

 private:
  Eigen::Array3d m_origin;
  double m_size = 1.0;
};

/// Candidate pairs (i < j) whose closed bounding boxes overlap.
std::vector<std::pair<int, int>> broad_phase(const std::vector<Box>& boxes) {
  const Grid grid(boxes);
  std::vector<std::pair<std::uint64_t, int>> entries;
  std::vector<int> large;
  std::vector<Eigen::Array3i> first(boxes.size());
  entries.reserve(4 * boxes.size());
  for (std::size_t f = 0; f < boxes.size(); ++f) {
    const Eigen::Array3i a = grid.cell(boxes[f].lo), b = grid.cell(boxes[f].hi);
    first[f] = a;
    if ((b - a + 1).cast<long>().prod() > Grid::MAX_CELLS) {
      large.push_back(static_cast<int>(f));
      continue;
    }
    for (int x = a(0); x <= b(0); ++x)
      for (int y = a(1); y <= b(1); ++y)
        for (int z = a(2); z <= b(2); ++z)
          entries.emplace_back(Grid::key({x, y, z}), static_cast<int>(f));
  }
  std::sort(entries.begin(), entries.end());
  std::vector<std::pair<int, int>> candidates;
  for (std::size_t i = 0; i < entries.size();) {
    std::size_t j = i;
    while (j < entries.size() && entries[j].first == entries[i].first) ++j;
    for (std::size_t p = i; p < j; ++p)
      for (std::size_t q = p + 1; q < j; ++q) {
        const int f = entries[p].second, g = entries[q].second;
        if (!boxes[f].overlaps(boxes[g])) continue;
        if (Grid::key(first[f].max(first[g])) != entries[i].first) continue;  // reported elsewhere
        candidates.emplace_back(std::min(f, g), std::max(f, g));
      }
    i = j;
  }
  std::vector<char> is_large(boxes.size(), 0);
  for (int f : large) is_large[f] = 1;
  for (int f : large)
    for (std::size_t g = 0; g < boxes.size(); ++g)
      if (static_cast<int>(g) != f && !(is_large[g] && static_cast<int>(g) < f) &&
          boxes[f].overlaps(boxes[g]))
        candidates.emplace_back(std::min<int>(f, static_cast<int>(g)),
                                std::max<int>(f, static_cast<int>(g)));
  return candidates;
}

/// Intersection of a possibly degenerate triangle with another, through its edges when it is
/// collinear (a collinear triangle is the union of its edges).
bool degenerate_meets(const Point& a, const Point& b, const Point& c, const Triangle& other) {
  const Point corners[3] = {a, b, c};
  for (int k = 0; k < 3; ++k) {
    const Point& p = corners[k];
    const Point& q = corners[(k + 1) % 3];
    if (p == q ? CGAL::do_intersect(p, other) : CGAL::do_intersect(Segment(p, q), other))
      return true;
  }
  return false;
}

bool disjoint_pair_meets(const Point (&t1)[3], const Point (&t2)[3]) {
  const Triangle a(t1[0], t1[1], t1[2]), b(t2[0], t2[1], t2[2]);
  const bool a_flat = a.is_degenerate(), b_flat = b.is_degenerate();
  if (!a_flat && !b_flat) return CGAL::do_intersect(a, b);
  if (a_flat && !b_flat) return degenerate_meets(t1[0], t1[1], t1[2], b);
  if (!a_flat && b_flat) return degenerate_meets(t2[0], t2[1], t2[2], a);
  // Both collinear: test every edge pair.
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l) {
      const Point &p = t1[k], &q = t1[(k + 1) % 3], &r = t2[l], &s = t2[(l + 1) % 3];
      if (p == q || r == s) continue;  // a collapsed edge is an end point of another edge
      if (CGAL::do_intersect(Segment(p, q), Segment(r, s))) return true;
    }
  return false;
}

/// Triangles (s, a, b) and (s, c, d) sharing only s meet beyond s iff ab meets the second or
/// cd meets the first (see the header).
bool vertex_pair_meets(const Point& s, const Point& a, const Point& b, const Point& c,
                       const Point& d) {
  // Exact early exit: when c and d lie strictly on one side of the first triangle's plane,
  // the second triangle meets that plane only at s (and the same the other way round).
  const CGAL::Orientation oc = CGAL::orientation(s, a, b, c);
  if (oc != CGAL::COPLANAR && oc == CGAL::orientation(s, a, b, d)) return false;
  const CGAL::Orientation oa = CGAL::orientation(s, c, d, a);
  if (oa != CGAL::COPLANAR && oa == CGAL::orientation(s, c, d, b)) return false;
  const Triangle first(s, a, b), second(s, c, d);
  return CGAL::do_intersect(Segment(a, b), second) || CGAL::do_intersect(Segment(c, d), first);
}

/// Triangles (p, q, a) and (q, p, b) sharing edge pq overlap beyond it iff a, b are coplanar
/// with pq and on the same side of the line pq.
bool edge_pair_meets(const Point& p, const Point& q, const Point& a, const Point& b) {
  if (!CGAL::coplanar(p, q, a, b)) return false;
  return CGAL::coplanar_orientation(p, q, a, b) == CGAL::POSITIVE;
}

/// Positions k in face f of the vertices shared with face g, and of those not shared.
struct Sharing {
  int shared_in_f[3], shared_in_g[3], n_shared = 0;
  int own_f[3], own_g[3], n_own_f = 0, n_own_g = 0;
};

Sharing sharing(const Eigen::MatrixX3i& faces, int f, int g) {
  Sharing s;
  bool used_g[3] = {false, false, false};
  for (int k = 0; k < 3; ++k) {
    bool found = false;
    for (int l = 0; l < 3 && !found; ++l)
      if (faces(f, k) == faces(g, l)) {
        s.shared_in_f[s.n_shared] = k;
        s.shared_in_g[s.n_shared++] = l;
        used_g[l] = found = true;
      }
    if (!found) s.own_f[s.n_own_f++] = k;
  }
  for (int l = 0; l < 3; ++l)
    if (!used_g[l]) s.own_g[s.n_own_g++] = l;
  return s;
}

/// Exact test of one candidate pair. Returns true when the pair intersects; sets kind, and
/// `skipped` when an adjacent pair holds a degenerate triangle.
bool pair_meets(const std::vector<Point>& pts, const Eigen::MatrixX3i& faces, int f, int g,
                PairKind& kind, bool& skipped) {
  const Point tf[3] = {pts[faces(f, 0)], pts[faces(f, 1)], pts[faces(f, 2)]};
  const Point tg[3] = {pts[faces(g, 0)], pts[faces(g, 1)], pts[faces(g, 2)]};
  const Sharing s = sharing(faces, f, g);
  skipped = false;
  if (s.n_shared == 0) {
    kind = PairKind::disjoint;
    return disjoint_pair_meets(tf, tg);
  }
  if (s.n_shared == 3) return false;  // a duplicated face: not a crossing of the sheet
  if (CGAL::collinear(tf[0], tf[1], tf[2]) || CGAL::collinear(tg[0], tg[1], tg[2])) {
    skipped = true;
    return false;
  }
  if (s.n_shared == 1) {
    kind = PairKind::vertex;
    return vertex_pair_meets(tf[s.shared_in_f[0]], tf[s.own_f[0]], tf[s.own_f[1]], tg[s.own_g[0]],
                             tg[s.own_g[1]]);
  }
  kind = PairKind::edge;
  return edge_pair_meets(tf[s.shared_in_f[0]], tf[s.shared_in_f[1]], tf[s.own_f[0]],
                         tg[s.own_g[0]]);
}

}  // namespace

SelfIntersections find_self_intersections(const Eigen::MatrixX3d& positions,
                                          const Eigen::MatrixX3i& faces) {
  check_input(positions, faces);
  const std::vector<Point> points = to_points(positions);
  const std::vector<std::pair<int, int>> candidates = broad_phase(face_boxes(positions, faces));

  SelfIntersections result;
  std::vector<std::pair<int, int>> hits;
  for (const auto& [f, g] : candidates) {
    PairKind kind = PairKind::disjoint;
    bool skipped = false;
    const bool meets = pair_meets(points, faces, f, g, kind, skipped);
    result.skipped_degenerate += skipped ? 1 : 0;
    if (!meets) continue;
    hits.emplace_back(f, g);
    result.disjoint_pairs += kind == PairKind::disjoint ? 1 : 0;
    result.vertex_pairs += kind == PairKind::vertex ? 1 : 0;
    result.edge_pairs += kind == PairKind::edge ? 1 : 0;
  }
  std::sort(hits.begin(), hits.end());
  result.pairs.resize(static_cast<Eigen::Index>(hits.size()), 2);
  for (std::size_t k = 0; k < hits.size(); ++k)
    result.pairs.row(static_cast<Eigen::Index>(k)) << hits[k].first, hits[k].second;
  return result;
}

int count_self_intersections(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces) {
  return find_self_intersections(positions, faces).count();
}

}  // namespace papersim::collision
