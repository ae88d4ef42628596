#pragma once
/// Exact detection of intersecting triangle pairs within one triangle mesh (the sheet against
/// itself), for measurements and validation. Not used inside the time step (which relies on
/// continuous collision detection); this is the after-the-fact check "did the sheet pass
/// through itself".
///
/// Which pairs count. Two triangles that share vertices always touch there, so a pair counts
/// only when the triangles meet somewhere else:
/// - no shared vertex: the closed triangles intersect (touching counts);
/// - exactly one shared vertex s, triangles (s, a, b) and (s, c, d): they meet beyond s if and
///   only if segment ab meets triangle (s, c, d) or segment cd meets triangle (s, a, b). (The
///   intersection of two convex sets containing s is convex; if it holds a point other than s,
///   its boundary reaches an edge not through s. Covers the coplanar case too.)
/// - a shared edge pq, triangles (p, q, a) and (q, p, b): they overlap beyond the edge if and
///   only if a and b are coplanar with pq and on the same side of it (folded flat onto itself).
/// A world-degenerate (collinear) triangle is tested through its edges when it shares no
/// vertex with the other triangle, and skipped when it does (the rules above need a proper
/// triangle); such pairs are counted in SelfIntersections::skipped_degenerate.
/// All predicates are exact (CGAL Exact_predicates_inexact_constructions_kernel). The broad
/// phase is a uniform grid over the triangles' closed bounding boxes (cell = twice the mean box
/// size); it never misses a pair whose boxes overlap. The whole count takes about 10 ms for a
/// folded sheet of 10k triangles, where CGAL::box_self_intersection_d alone took about 19 ms.
#include <Eigen/Core>
#include <vector>

namespace papersim::collision {

/// Result of find_self_intersections.
struct SelfIntersections {
  /// Intersecting pairs (i, j), i < j face indices, sorted by (i, j). #P by 2.
  Eigen::MatrixX2i pairs;
  int disjoint_pairs = 0;      ///< pairs sharing no vertex that intersect
  int vertex_pairs = 0;        ///< pairs sharing one vertex that meet beyond it
  int edge_pairs = 0;          ///< pairs sharing an edge that are folded flat onto each other
  int skipped_degenerate = 0;  ///< adjacent pairs not tested because a triangle is degenerate
  /// Total number of intersecting pairs (rows of `pairs`).
  int count() const { return static_cast<int>(pairs.rows()); }
};

/// All intersecting triangle pairs of a mesh (see the file comment for which pairs count).
/// @param positions  #V by 3 vertex positions [m]
/// @param faces      #F by 3 vertex indices
/// @throw std::invalid_argument when a face index is out of range or a position is not finite.
SelfIntersections find_self_intersections(const Eigen::MatrixX3d& positions,
                                          const Eigen::MatrixX3i& faces);

/// Number of intersecting triangle pairs: find_self_intersections(...).count().
/// @throw std::invalid_argument as find_self_intersections.
int count_self_intersections(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3i& faces);

}  // namespace papersim::collision
