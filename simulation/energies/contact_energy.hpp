#pragma once
/// Contact of sheet vertices with obstacles (signed distance fields) and Coulomb friction.
///
/// Contact: E = sum_v sum_o kappa A_v b(phi_o(x_v), dhat) with the IPC log barrier b
/// (Li et al. 2020, eq. 6); kappa = stiffness / dhat, so that the contact pressure at gap d is
/// stiffness |b'(d)| / dhat: `stiffness` is the pressure at about half the thickness [Pa]. A
/// sheet resting under its weight rho_A g with stiffness = rho_A g sits at about 0.55 dhat. The
/// Hessian keeps b'' grad phi grad phi^T and drops b' Hess phi (exact for planes; for curved
/// obstacles the dropped term is the obstacle curvature times the contact force), except where the
/// collider provides Hess phi (Collider::distance_hessian: the inverted sphere). Inside a spherical
/// cavity that term is positive semi-definite and must be kept: without it Newton's model lets a
/// vertex slide tangentially for free, which on a concave wall drives it into the wall, and
/// continuous collision detection then cuts every step short. Friction (lagged per time step, IPC
/// eqs. 14-16): normal force magnitudes and tangent bases are frozen at the step start; the
/// tangential slip u = T^T (x - x_t0 - h v_obstacle) pays mu lambda f0(|u|), with f0 the C1
/// smoothing of |u| below eps_v h. CCD: along the segment x_v -> x_v + a dx_v, a point cannot reach
/// an obstacle before it moved by its distance phi (phi is 1-Lipschitz); sphere tracing gives a
/// conservative largest a.
///
/// Faces (set_faces): obstacles other than planes touch the sheet's triangles and edges, not only
/// its vertices, so that a ridge, an edge or a small sphere cannot slip between vertices. How
/// depends on the obstacle:
/// - Sphere: each face f pays kappa_f b(d_f) with d_f = dist(centre, triangle) - radius, the
///   exact minimum of the field over the triangle, and kappa_f = stiffness / dhat x A_f / 3
///   (which equals the vertex term when the closest point is a vertex shared by the faces
///   around it). The point-triangle distance is C1 and has exact derivatives
///   (collision::pair_barrier_derivatives), so the energy is smooth to round-off.
/// - Box and gable prism (polyhedra): as IPC between two meshes. The vertex terms above, plus a
///   barrier between every obstacle corner and sheet triangle (weight A_f / 3) and between every
///   obstacle edge and sheet edge (mollified as IPC's edge-edge pairs, weight a third of the
///   areas of the faces at the sheet edge). Every term is an exact distance with exact
///   derivatives; CCD is additive CCD on the corner-triangle and edge-edge pairs.
/// - Other obstacles (cylinder, capsule, mesh level sets): d_f is the minimum of the field over
///   the triangle found by a search (collision::triangle_min_distance, polished by projected
///   gradient steps). That minimum is accurate only to the search's tolerance, so the energy
///   carries a little noise; derivatives hold the minimiser's barycentric weights w fixed (the
///   envelope theorem: d d_f / d x_i = w_i n).
/// Friction acts at each term's closest point on the sheet with the same weights. Over a plane
/// the minimum over a triangle is at a vertex, so planes keep the cheaper vertex terms. Against
/// convex obstacles (the ground and every primitive) vertex and face CCD use the tangent plane
/// at the closest point, which the convex solid lies behind: a face or vertex sliding along a
/// curved surface close to it is not held back, as sphere tracing (whose steps shrink with the
/// gap) would hold it. A sphere face whose tangent-plane bound is shorter than the step also gets
/// additive CCD on the centre-triangle distance with the radius as thickness (a face turning on
/// a sphere smaller than itself closes its tangent plane at once but keeps its distance), and
/// the larger of the two safe bounds is taken. Other fields are sphere-traced on a certified
/// lower bound.
///
/// Impacts (set_impact_density): a barrier scaled to the sheet's weight is far too soft to stop
/// a sheet arriving at metres per second; it would be stopped only nanometres from the surface,
/// where Newton stalls. At each step start the stiffness is raised, if needed, so that the
/// barrier can absorb the kinetic energy of the fastest approach within the layer, stopping it
/// at about dhat / 100: stiffness >= rho_A v_n^2 / (2 dhat ln 100), v_n the largest normal
/// speed towards an obstacle of a vertex that can reach it within the step.
///
/// Load rule (ContactParams::hold_load): once an impact has raised the stiffness, the sheet's
/// load may rest on a few vertices or faces at about dhat / 100. Falling back at once to the
/// weight's stiffness would let that load push them to nanometres from the surface, where the
/// continuous collision detection cuts every step short and Newton crawls. So the stiffness the
/// last step ended with (SheetState::contact_stiffness, carried in StepContext) moves at a step
/// start towards the one that holds the largest contact pressure at the step start at dhat / 100:
/// stiffness >= carried x min(load_raise, b'(d_min) / b'(dhat / 100)), d_min the smallest gap
/// of any contact term. Above dhat / 100 it falls that far at once; it falls to the scene's
/// stiffness once the load eases or the sheet leaves the obstacles. A load that grows after the
/// impact presses the sheet below dhat / 100; then the stiffness rises, by at most load_raise
/// per step (2: IPC's adaptive stiffness doubles it while the gap shrinks, Li et al. 2020), so
/// that no step starts with a barrier much stiffer than the one the sheet rests on, which would
/// push the sheet off in one step. A raise stops at raise_limit times the scene's stiffness (IPC
/// bounds its adaptive stiffness too); the impact rule is not bound by it.
#include <array>
#include <memory>
#include <vector>

#include "collision/collider.hpp"
#include "collision/self_contact.hpp"
#include "collision/triangle_sdf.hpp"
#include "simulation/energies/energy_term.hpp"
#include "simulation/trace.hpp"

namespace papersim::simulation {

struct ContactParams {
  double dhat = 3e-4;          ///< barrier activation distance (contact thickness) [m]
  double stiffness = 1.0;      ///< pressure scale of the barrier [Pa] (see above)
  double eps_velocity = 1e-3;  ///< slip speed below which friction is static-like [m/s]
  /// Friction's static zone is the slip eps_velocity times the step: false, the step being
  /// solved (IPC); true, the whole step the run asked for (StepContext::whole_step), so that a step
  /// the solver splits keeps the zone of the whole step instead of narrowing it with every
  /// halving (docs/crumple.md, "Friction's static zone in split steps"). Obstacle and
  /// self-contact friction alike.
  bool static_whole_step = false;
  bool hold_load = true;  ///< the load rule (above)
  /// Largest factor by which the load rule raises the stiffness at one step start, when the
  /// load has pressed the sheet closer than dhat / 100 (1: it never raises it).
  double load_raise = 2.0;
  /// The load rule never raises the stiffness above this many times `stiffness`: a load that
  /// needs more is a jam (a rigid obstacle pressing on a held point), which fails the step rather
  /// than growing the barrier without bound.
  double raise_limit = 10.0;
  /// Contact on sheet faces against obstacles other than planes (set_faces), for features
  /// smaller than the sheet's edges; off: vertices only.
  bool faces = false;
  Trace trace;  ///< topic `contact`: the stiffness and contacts at each step start; not a scene key
};

/// Counters of obstacle contact over a run. The run owns them and hands them to every term it
/// builds, so rebuilding the terms (after remeshing) loses nothing.
struct ContactStatistics {
  double seconds = 0.0;  ///< wall time in the term (field queries, barrier, friction, CCD) [s]
  int max_friction_points = 0;    ///< most friction contacts (vertices, faces, pairs) in one step
  double max_normal_force = 0.0;  ///< largest total normal force at a step start [N]
};

class ObstacleContactEnergy : public EnergyTerm {
 public:
  /// @param vertex_areas material area per vertex [m^2] (a third of the incident faces)
  ObstacleContactEnergy(Eigen::VectorXd vertex_areas,
                        std::vector<std::shared_ptr<const collision::Collider>> obstacles,
                        const ContactParams& params);

  std::string name() const override { return "contact"; }
  /// Couples the vertices of each face when face contact is on (set_faces); vertex terms need
  /// no coupling.
  void add_pattern(SparsityBuilder& pattern) const override;
  void begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0) override;
  double value(const Eigen::VectorXd& x) const override;
  void add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                       BlockSymmetricMatrix* hessian, HessianProjection projection) const override;
  double max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const override;

  /// Moving obstacles (EnergyTerm, Integrator "Following moving obstacles"): supported when
  /// every obstacle that moves during the step touches the sheet by its vertices and moves
  /// affinely (collision::Collider::moves_affinely: the fold's rolling cylinder, the crumple's
  /// shrinking cavity).
  ObstacleMotion obstacle_motion() const override;
  /// Some vertex within the contact thickness of a moving obstacle at the step start, or
  /// reached by one, ends the step closer to it than half its gap and half the thickness, with
  /// the sheet held where it is.
  bool obstacles_close_in(const Eigen::VectorXd& x) const override;
  void set_obstacle_time(double t) override;
  /// Vertex barriers: d/dt (kappa b'(phi) n) ~ kappa b''(phi) (d phi / dt) n with
  /// d phi / dt = -n . (velocity of the obstacle at the vertex), the change of n dropped as the
  /// Hessian drops b' Hess phi.
  void add_obstacle_motion_gradient(const Eigen::VectorXd& x, double dt,
                                    Eigen::VectorXd& gradient) const override;
  /// max_step, with each moving obstacle's vertex CCD done on the joint motion
  /// (collision::Collider::moving_segment_step, exact for the affine motions supported).
  double max_step_with_obstacles(const Eigen::VectorXd& x, const Eigen::VectorXd& dx,
                                 double dt) const override;

  /// Makes obstacle o a body of the step (collision::LiftSpec::coupled, LiftBodyEnergy): its
  /// vertical displacement q_z is entry 3 block + 2 of x (when x is that long; otherwise 0), the
  /// obstacle is evaluated raised by q_z, and each vertex barrier couples the vertex with the
  /// block: with r = p - q_z e_z the point relative to the raised obstacle, E = kappa b(phi(r)),
  /// whose gradient and Hessian in (p, q) are those in r through dr/dp = I, dr/dq = -e_z e_z^T.
  /// Friction keeps the obstacle's keyframed velocity (the lift's vertical motion is along the
  /// normal where the sheet presses it from below). Vertex contact only.
  /// @throw SceneError when o touches the sheet by faces (ContactParams::faces)
  void set_rigid_block(int o, int block);

  /// Switches obstacles other than planes to face contact (see above).
  /// @param faces #F by 3 vertex indices; @param material_coords #V by 2 flat sheet
  /// coordinates [m] (face areas and rest edge lengths)
  void set_faces(const Eigen::MatrixX3i& faces, const Eigen::MatrixX2d& material_coords);

  /// Enables the impact rule (see above) for a sheet of areal density rho_A [kg/m^2].
  void set_impact_density(double areal_density) { m_impact_density = areal_density; }
  /// Barrier stiffness in force for the current step [Pa] (>= ContactParams::stiffness).
  double step_stiffness() const { return m_stiffness; }
  /// Writes the step's stiffness to state.contact_stiffness (the load rule carries it on).
  void end_step(SheetState& state) const override;

  /// Number of vertices with friction active in the current step.
  int active_friction() const { return static_cast<int>(m_friction.size()); }
  /// Sum of normal contact force magnitudes at the step start [N].
  double normal_force() const { return m_normal_force; }
  int num_obstacles() const { return static_cast<int>(m_obstacles.size()); }
  /// The force the sheet at x presses obstacle o with through the contact barriers (vertex,
  /// face and feature-pair contacts), the obstacles where they are at the current step's end
  /// [N]. Friction is not included.
  Eigen::Vector3d obstacle_load(int o, const Eigen::VectorXd& x) const;
  /// Smallest signed distance from the sheet's surface to obstacle o at time t [m]: over the
  /// vertices, and with face contact over the faces (spheres, searched fields) or the corner-
  /// triangle and edge-edge pairs (polyhedra) too, so a ridge between vertices counts.
  double surface_distance(int o, const Eigen::VectorXd& x, double t) const;
  /// Where the term counts (see ContactStatistics); null: a counter of its own.
  void set_statistics(ContactStatistics* statistics) {
    m_stats = statistics ? statistics : &m_own_stats;
  }
  const ContactStatistics& statistics() const { return *m_stats; }

 private:
  struct FrictionPoint {
    std::array<int, 3> vertices{{-1, -1, -1}};  // one (a vertex), two (an edge) or three (a face)
    Eigen::Vector3d weights = Eigen::Vector3d(1, 0, 0);
    int count = 1;
    int obstacle = -1;
    double mu_lambda = 0.0;                                               // mu x normal force [N]
    Eigen::Matrix<double, 3, 2> T = Eigen::Matrix<double, 3, 2>::Zero();  // tangent basis
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();                     // x_t0 + h v_obstacle [m]
  };
  /// How an obstacle touches the sheet (see the header comment).
  enum class Mode { vertices, sphere, polytope, search };
  /// A corner-triangle (a = corner, b = sheet face) or edge-edge (a = sheet edge, b = obstacle
  /// edge) pair of a polyhedral obstacle.
  struct FeaturePair {
    int obstacle;
    bool edge_edge;
    int a, b;
  };
  /// An obstacle's corners and edges in the world at one time.
  struct WorldFeatures {
    std::vector<Eigen::Vector3d> corners;
    std::vector<std::array<int, 2>> edges;
    std::vector<double> edge_length;
  };

  bool near_bounds(int o, const Eigen::Vector3d& p) const;
  /// The boxes of the sheet's faces at one configuration, and which of them come near an
  /// obstacle's bounds (face_near_bounds for every face at once; see the .cpp).
  class FaceBoxes;
  FaceBoxes face_boxes(const Eigen::VectorXd& x) const;
  /// The largest vertex displacement of each face along dx [m] (the faces' part of max_step;
  /// empty when no obstacle touches the sheet by faces through sphere or search mode).
  std::vector<double> face_speeds(const Eigen::VectorXd& dx) const;
  /// Obstacles that touch the sheet's faces by sphere or search mode (those face_boxes serves).
  int face_obstacles() const;
  /// The rigid displacement of obstacle o held in v (x or dx; set_rigid_block): (0, 0, v_z of
  /// its block), zero when o has none or v holds only the sheet.
  Eigen::Vector3d lift_of(int o, const Eigen::VectorXd& v) const {
    const int b = m_rigid[o];
    return b >= 0 && v.size() >= 3 * b + 3 ? Eigen::Vector3d(0, 0, v[3 * b + 2])
                                           : Eigen::Vector3d::Zero();
  }
  /// Calls visit(FrictionPoint fp, double lambda, Vector3d p, Vector3d n) for every barrier
  /// contact of the sheet at x with the obstacles (only obstacle `only` when >= 0) at time t
  /// (see the .cpp).
  template <class F>
  void for_each_contact(const Eigen::VectorXd& x, double t, F&& visit, int only = -1) const;
  /// Bounds of the field at m_time, inflated by the thickness (m_bounds).
  void update_bounds();
  /// Largest step along dx for obstacle o held at m_time (vertices and faces; not the pairs),
  /// with the faces' boxes at x and their speeds along dx (face_boxes, face_speeds).
  double obstacle_max_step(int o, const Eigen::VectorXd& x, const Eigen::VectorXd& dx, double alpha,
                           const FaceBoxes& boxes, const std::vector<double>& speeds) const;
  /// Largest step along dx for the pairs of polyhedral obstacles held at m_time.
  double pairs_max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx, double alpha) const;
  bool face_near_bounds(int o, const Eigen::VectorXd& x, int f, double margin) const;
  bool uses_faces(int o) const { return m_mode[o] != Mode::vertices; }
  bool uses_vertices(int o) const {
    return m_mode[o] == Mode::vertices || m_mode[o] == Mode::polytope;
  }
  /// Minimum of obstacle o's field (at `pose`) over face f at x: exact for a sphere, searched
  /// otherwise; +inf distance when the face's box is outside the obstacle's bounds.
  collision::TriangleSdfResult face_contact(int o, const Eigen::VectorXd& x, int f,
                                            const Eigen::Affine3d& pose) const;
  /// Sphere obstacle o (at `pose`) against face f: the four points (centre, face corners).
  collision::PairPoints sphere_points(const Eigen::VectorXd& x, int f,
                                      const Eigen::Affine3d& pose) const;
  /// Sphere obstacle o against face f: its surface distance |centre - triangle| - radius [m],
  /// with the points and the closest-feature stencil it was measured on.
  double sphere_face_distance(int o, const Eigen::VectorXd& x, int f, const Eigen::Affine3d& pose,
                              collision::PairPoints& pts, collision::DistanceStencil& s) const;
  /// Radius of sphere obstacle o at placement `pose` (its radius times the pose's scale) [m].
  double sphere_radius(int o, const Eigen::Affine3d& pose) const {
    return m_sphere_radius[o] * pose.linear().col(0).norm();
  }
  double face_kappa(int f) const { return m_stiffness / m_params.dhat * m_face_area[f] / 3; }
  /// Corners and edges of polyhedral obstacle o at time t.
  WorldFeatures world_features(int o, double t) const;
  /// Pairs of the polyhedral obstacles whose boxes come within `radius` of each other while the
  /// sheet moves from x to x + dx (dx null: at x only), with the features `features`.
  std::vector<FeaturePair> feature_pairs(const Eigen::VectorXd& x, const Eigen::VectorXd* dx,
                                         double radius,
                                         const std::vector<WorldFeatures>& features) const;
  collision::PairPoints pair_points(const FeaturePair& p, const Eigen::VectorXd& x,
                                    const std::vector<WorldFeatures>& features) const;
  /// Weight (area) of a pair [m^2] and its mollifier threshold (0 for corner-triangle pairs).
  double pair_weight(const FeaturePair& p) const;
  double pair_mollifier_eps(const FeaturePair& p, const std::vector<WorldFeatures>& features) const;
  /// Point of a friction contact: sum of weight x vertex position.
  Eigen::Vector3d contact_point(const FrictionPoint& fp, const Eigen::VectorXd& x) const;
  double kappa(int v) const { return m_stiffness / m_params.dhat * m_area[v]; }

  Eigen::VectorXd m_area;
  std::vector<std::shared_ptr<const collision::Collider>> m_obstacles;
  ContactParams m_params;
  std::vector<collision::Aabb> m_bounds;  // at the step end, inflated by dhat
  std::vector<FrictionPoint> m_friction;
  std::vector<Mode> m_mode;               // per obstacle
  std::vector<int> m_rigid;               // per obstacle: its rigid block, or -1 (set_rigid_block)
  std::vector<double> m_sphere_radius;    // per obstacle (sphere mode), at scale 1 [m]
  std::vector<WorldFeatures> m_features;  // per obstacle at the step end (polytope mode)
  Eigen::MatrixX3i m_faces;
  Eigen::MatrixX2i m_edges;  // sheet edges (polytope mode)
  Eigen::VectorXd m_face_area, m_edge_area, m_edge_rest;
  collision::TriangleSdfParams m_triangle;
  double m_time = 0.0;  // time the obstacles are evaluated at: the step's end unless followed
  double m_t0 = 0.0, m_t1 = 0.0;  // the current step [s]
  std::vector<bool> m_moving;     // per obstacle: moves during the current step
  double m_eps = 1e-6, m_normal_force = 0.0;
  double m_impact_density = 0.0;  // rho_A for the impact rule; 0: off
  double m_stiffness = 0.0;       // this step's stiffness [Pa]
  ContactStatistics m_own_stats;
  ContactStatistics* m_stats = &m_own_stats;
};

}  // namespace papersim::simulation
