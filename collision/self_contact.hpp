#pragma once
/// Geometry of self-contact within one triangle mesh (the sheet against itself): broad phase,
/// exact primitive distances with derivatives, and continuous collision detection.
///
/// Pairs (IPC, Li et al. 2020, Sec. 4): a vertex against a triangle that does not hold it, and
/// an edge against an edge sharing no vertex with it. Their distance is the exact distance
/// between the closed primitives; which sub-features are closest (the "distance type") decides
/// the smooth formula used for its derivatives: point-point, point-edge (point to the edge's
/// line), point-triangle (point to the triangle's plane) or edge-edge (line to line). All
/// formulas are squared distances d^2, smooth within their type; d^2 is C1 across types except
/// where edges are parallel, which the edge-edge mollifier covers (IPC Sec. 4.3).
///
/// CCD is Additive CCD (Li et al. 2021, "Codimensional Incremental Potential Contact", Sec. 5):
/// along a linear motion, a pair whose distance is d cannot touch before its points moved
/// relatively by d, so advancing by a fraction of d / (bound on relative speed) is always safe.
#include <Eigen/Core>
#include <array>
#include <vector>

namespace papersim::collision {

using Vector12d = Eigen::Matrix<double, 12, 1>;
using Matrix12d = Eigen::Matrix<double, 12, 12>;

/// Topology for self-contact: faces and their unique edges.
struct SelfContactMesh {
  Eigen::MatrixX3i faces;  ///< #F by 3 vertex indices
  Eigen::MatrixX2i edges;  ///< #E by 2 vertex indices (i < j), each edge once
  int num_vertices = 0;
  /// Builds the edge list from the faces.
  /// @throw std::invalid_argument when a face index is out of [0, num_vertices).
  static SelfContactMesh from_faces(const Eigen::MatrixX3i& faces, int num_vertices);
};

/// Candidate pairs of the broad phase.
struct SelfContactCandidates {
  std::vector<std::array<int, 2>> point_triangle;  ///< (vertex, face), the face not holding it
  std::vector<std::array<int, 2>> edge_edge;       ///< (edge a, edge b), a < b, no shared vertex
  std::size_t size() const { return point_triangle.size() + edge_edge.size(); }
};

/// Every pair whose primitives may come within `radius` of each other while the vertices move
/// linearly from x0 to x1 (bounding boxes of both positions, grown by radius / 2, overlap);
/// a superset of the pairs within `radius`, each list sorted (so sums over the pairs near each
/// other come in one order whatever positions the set was found at). Uniform-grid broad phase,
/// O(#F + #pairs) for boxes of about the cell size, and a sort of the pairs.
/// @param x0, x1 flat positions (3N: vertex v at 3v..3v+2) [m]; pass x0 twice for a static test
/// @param radius [m], >= 0
SelfContactCandidates find_self_contact_candidates(const SelfContactMesh& mesh,
                                                   const Eigen::VectorXd& x0,
                                                   const Eigen::VectorXd& x1, double radius);

/// Smooth formulas for the squared distance of a pair.
enum class DistanceType { point_point, point_edge, point_triangle, edge_edge };

/// Which points of a pair's four (point-triangle: p, t0, t1, t2; edge-edge: a0, a1, b0, b1)
/// enter the closest-feature formula, in its order: point_point (p, q), point_edge (p, e0, e1),
/// point_triangle (p, t0, t1, t2), edge_edge (a0, a1, b0, b1).
struct DistanceStencil {
  DistanceType type = DistanceType::point_point;
  std::array<int, 4> points{{0, 1, 2, 3}};
  int count() const;
};

/// The four points of a pair [m].
using PairPoints = std::array<Eigen::Vector3d, 4>;

/// Closest features of point p = x[0] and triangle x[1..3]. A triangle whose area is zero to
/// round-off is treated through its edges.
DistanceStencil point_triangle_stencil(const PairPoints& x);
/// Closest features of segments x[0]x[1] and x[2]x[3]. Parallel segments (cross product zero to
/// round-off) are measured from their endpoints (the distance is attained there).
DistanceStencil edge_edge_stencil(const PairPoints& x);

/// Squared distance of the stencil's formula [m^2].
double distance_squared(const DistanceStencil& s, const PairPoints& x);
/// Squared distance [m^2], its gradient with respect to the 12 coordinates of the pair [m]
/// (zero for points outside the stencil), and, when `hessian` is not null, its Hessian [-].
/// The Hessian is exact for the stencil's formula (indefinite in general).
double distance_squared_derivatives(const DistanceStencil& s, const PairPoints& x,
                                    Vector12d& gradient, Matrix12d* hessian);
/// The closest points as weights on the pair's four points: the vector from the second
/// primitive's closest point to the first's is r = sum_i w_i x_i (|r|^2 = the squared distance).
Eigen::Vector4d closest_point_weights(const DistanceStencil& s, const PairPoints& x);

/// A cheap lower bound on the distance of a pair [m] from bounding spheres (the triangle's about
/// its centroid, each segment's about its midpoint); may be negative.
double pair_distance_lower_bound(const PairPoints& x, bool edge_edge);

/// Exact squared distance between point x[0] and triangle x[1..3] [m^2].
double point_triangle_distance_squared(const PairPoints& x);
/// Exact squared distance between segments x[0]x[1] and x[2]x[3] [m^2].
double edge_edge_distance_squared(const PairPoints& x);

/// IPC edge-edge mollifier (Li et al. 2020, eq. 10): with c = |(a1 - a0) x (b1 - b0)|^2,
/// m = 2 c / eps - c^2 / eps^2 for c < eps and 1 otherwise [-]; it makes the edge-edge barrier
/// vanish smoothly as the edges turn parallel, where point-triangle pairs hold the contact.
/// Fills the gradient [1/m^4 * m^3 = 1/m] and Hessian with respect to the 12 coordinates.
double edge_edge_mollifier(const PairPoints& x, double eps, Vector12d* gradient,
                           Matrix12d* hessian);
/// eps of the mollifier from rest edge lengths: 1e-3 |a_rest|^2 |b_rest|^2 [m^4].
double edge_edge_mollifier_threshold(double rest_length_a, double rest_length_b);

/// The IPC barrier of one pair, b(d, dhat) (collision/barrier.hpp) with d = |r| - offset, |r| the
/// stencil's distance (offset: the radius of a round primitive, 0 for the sheet against itself),
/// times the edge-edge mollifier when `mollifier_eps` > 0 (0: a point-triangle pair). Fills its
/// gradient with respect to the 12 coordinates and, when `hessian` is not null, its exact
/// Hessian (indefinite in general). Requires 0 < d < dhat.
double pair_barrier_derivatives(const DistanceStencil& s, const PairPoints& x, double dhat,
                                double mollifier_eps, Vector12d& gradient, Matrix12d* hessian,
                                double offset = 0.0);

/// Additive CCD (Li et al. 2021, Alg. 1) for the linear motion x + t dx, t in [0, t_max]:
/// a time of impact t such that every configuration on [0, t] keeps a positive distance and
/// the distance at t is at least min_separation x the distance at 0; t_max when the pair stays
/// apart beyond t_max. Returns 0 when the pair touches at t = 0.
/// @param min_separation in (0, 1), IPC uses 0.1
/// @param offset thickness of the point (a sphere of that radius about it) [m]: the gap is
///        the distance less the offset
double point_triangle_ccd(const PairPoints& x, const PairPoints& dx, double t_max,
                          double min_separation = 0.1, double offset = 0.0);
double edge_edge_ccd(const PairPoints& x, const PairPoints& dx, double t_max,
                     double min_separation = 0.1);

/// Smallest distance between any vertex and a triangle not holding it, and between any two
/// edges sharing no vertex, among pairs closer than `radius` [m]; +inf when none is.
double min_self_distance(const SelfContactMesh& mesh, const Eigen::VectorXd& x, double radius);

}  // namespace papersim::collision
