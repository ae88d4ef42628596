#pragma once
/// Self-contact of the sheet: an IPC barrier between every vertex and the triangles not holding
/// it and between every two edges sharing no vertex, lagged IPC friction between the layers,
/// and continuous collision detection so that no step of the line search lets the sheet pass
/// through itself (Li et al. 2020, "Incremental Potential Contact"; Li et al. 2021,
/// "Codimensional IPC" for the CCD).
///
/// Energy: E = sum_pairs kappa w_k m_k b(d_k, dhat) with d the exact distance of the pair, b the
/// IPC log barrier (collision/barrier.hpp), m the edge-edge mollifier (1 for vertex-triangle
/// pairs) and kappa = stiffness / dhat as for obstacles, so that `stiffness` is a pressure [Pa].
/// Pair weights are areas, so the energy scales with the mesh: a vertex-triangle pair weighs half
/// the vertex's area, an edge-edge pair a quarter of the sum of its edges' areas (a third of the
/// adjacent faces each) - half, because both layers see the same contact. As in IPC, a contact
/// near a vertex or an edge is seen by several pairs (no deduplication: that would make the
/// energy discontinuous), so two layers rest at a somewhat larger gap than a sheet on an
/// obstacle of the same stiffness.
///
/// Friction (IPC Sec. 5, lagged per step): at the step start, every pair within dhat gets its
/// normal force lambda, closest-point weights w and tangent basis T (orthonormal, normal to the
/// contact direction); the relative tangential slip u = T^T sum_i w_i (x_i - x_i,t0) pays
/// mu lambda f0(|u|).
///
/// Adaptive stiffness (IPC Sec. 4.3; ipc-toolkit's update_barrier_stiffness): where a load
/// presses two layers together harder than the barrier at `stiffness` can hold (the crumple's
/// end, under an obstacle barrier made stiff by its load and impact rules), Newton's iterates
/// close a pair to picometres, where the floating-point distance can no longer tell the sides
/// apart and the CCD lets the edges cross (docs/crumple.md). So, as in IPC, the stiffness
/// doubles (up to 100 times `stiffness`) at a Newton iteration whose smallest pair distance and
/// the one before it are both below a floor, 1e-9 of the sheet's bounding-box diagonal at the
/// step start, and falling. The stiffness is carried from step to step
/// (SheetState::self_contact_stiffness, checkpointed) and never falls; a run whose layers never
/// come within the floor is unchanged.
///
/// Active set and Hessian pattern: candidate pairs come from a broad phase at base positions
/// with a margin of 2 dhat; the set holds at every configuration within dhat of the base after
/// removing the common translation, so that the line search, the next Newton iterations and,
/// for a sheet moving as a whole, the next time steps reuse it. A Newton step with more
/// relative motion gets a broad phase over the boxes swept along it (less its mean) instead.
/// The set is a cache, not state: value(), add_derivatives() and max_step() find it again when
/// it does not cover their x (or step), and what they return does not depend on it, since every
/// set that covers x holds the same pairs within dhat and visits them in the broad phase's
/// sorted order (test EnergyDerivatives.SelfContactResultsAtXDoNotDependOnWhatWasEvaluatedBefore).
/// The Hessian pattern holds the pairs within 2 dhat (and the friction pairs) when it was
/// last rebuilt; update_pattern() asks for a rebuild only when a pair within dhat (or a friction
/// pair) is not in it, or when it holds far more pairs than are near (a contact ended), so that
/// the symbolic factorisation is redone rarely.
#include <array>
#include <cstdint>
#include <vector>

#include "collision/self_contact.hpp"
#include "simulation/energies/energy_term.hpp"
#include "simulation/trace.hpp"

namespace papersim::simulation {

struct SelfContactParams {
  bool enabled = true;
  /// Barrier activation distance between two parts of the sheet [m]; 0 = the obstacle contact
  /// thickness (ContactParams::dhat).
  double dhat = 0.0;
  /// Barrier pressure scale [Pa]; 0 = the obstacle contact stiffness (automatic: rho_A |g|).
  double stiffness = 0.0;
  double friction = 0.6;           ///< Coulomb coefficient sheet-sheet [-] (SCENARIOS.md)
  double eps_velocity = 1e-3;      ///< slip speed below which friction is static-like [m/s]
  bool static_whole_step = false;  ///< as ContactParams::static_whole_step
  /// The line search never closes more than this fraction of a pair's gap in one step.
  double ccd_min_separation = 0.1;
  /// Topics `contact` (friction pairs and stiffness raises) and `intersect` (report_crossings);
  /// not a scene key.
  Trace trace;
};

/// Counters of self-contact over a run, owned by the run (as ContactStatistics).
struct SelfContactStatistics {
  double seconds = 0.0;         ///< wall time in the term (broad phase, barrier, friction, CCD) [s]
  int max_active_pairs = 0;     ///< most pairs within dhat at one derivative evaluation
  int pattern_changes = 0;      ///< how often update_pattern() reported a change
  int stiffness_doublings = 0;  ///< Newton iterations that doubled the stiffness (adapt)
  double max_stiffness = 0;     ///< largest stiffness of a step [Pa]
};

class SelfContactEnergy : public EnergyTerm {
 public:
  /// @param material_coords #V by 2 flat sheet coordinates [m] (rest edge lengths)
  /// @param faces           #F by 3
  /// @param params          dhat > 0 and stiffness > 0 (resolved by the caller)
  /// @throw std::invalid_argument when dhat or stiffness is not positive or a face index is
  ///        out of range.
  SelfContactEnergy(const Eigen::MatrixX2d& material_coords, const Eigen::MatrixX3i& faces,
                    const SelfContactParams& params);

  std::string name() const override { return "self_contact"; }
  void add_pattern(SparsityBuilder&) const override {}
  bool update_pattern(const Eigen::VectorXd& x) override;
  void add_dynamic_pattern(SparsityBuilder& pattern) const override;
  void begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0) override;
  double value(const Eigen::VectorXd& x) const override;
  void add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                       BlockSymmetricMatrix* hessian, HessianProjection projection) const override;
  double max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const override;
  /// Doubles the stiffness when the smallest pair distance at x and at the last iterate (or the
  /// step start) are both below the floor and it fell (see "Adaptive stiffness").
  bool adapt(const Eigen::VectorXd& x) override;
  /// Writes the stiffness to state.self_contact_stiffness.
  void end_step(SheetState& state) const override { state.self_contact_stiffness = m_stiffness; }
  /// The barrier's stiffness in the current step [Pa] (params().stiffness or more).
  double stiffness() const { return m_stiffness; }
  /// Most the adaptive stiffness may reach, as a multiple of params().stiffness.
  static constexpr double max_stiffness_factor = 100;
  /// The floor of the adaptive stiffness, as a fraction of the bounding-box diagonal.
  static constexpr double floor_fraction = 1e-9;

  /// Smallest distance between two parts of the sheet that are closer than `radius` [m]
  /// (vertex-triangle and edge-edge pairs), +inf when none is.
  double min_distance(const Eigen::VectorXd& x, double radius) const;
  /// Pairs within dhat at the last derivative evaluation, and the most over the run.
  int active_pairs() const { return m_active; }
  /// Pairs with friction in the current step.
  int active_friction() const { return static_cast<int>(m_friction.size()); }
  /// Where the term counts (see SelfContactStatistics); null: a counter of its own.
  void set_statistics(SelfContactStatistics* statistics) {
    m_stats = statistics ? statistics : &m_own_stats;
  }
  const SelfContactStatistics& statistics() const { return *m_stats; }
  const SelfContactParams& params() const { return m_params; }

  /// The pairs of the Hessian's dynamic pattern, as (kind, a, b): kind 0 a vertex a and face b,
  /// kind 1 edges a and b (the mesh's sorted edge list). The pattern is built when a pair closes
  /// in and holds until the pairs change; the positions do not determine it, so a checkpoint
  /// carries it.
  std::vector<std::array<int, 3>> pattern_pairs() const;
  /// Takes the pattern of a checkpoint (pattern_pairs()), before the first step; the integrator
  /// then builds its matrix with it (Integrator::adopt_dynamic_patterns).
  /// @throw std::invalid_argument for a kind or an index out of range
  void restore_pattern(const std::vector<std::array<int, 3>>& pairs);

 private:
  /// A pair: a vertex-triangle (a = vertex, b = face) or an edge-edge (a, b edges) pair.
  struct Pair {
    bool edge_edge;
    int a, b;
  };
  struct FrictionPair {
    std::array<int, 4> vertices;
    Eigen::Vector4d weights;        // closest-point weights
    Eigen::Matrix<double, 3, 2> T;  // tangent basis
    Eigen::Vector3d r_t0;           // sum_i w_i x_i,t0
    double mu_lambda;               // mu x normal force [N]
  };
  /// What the barrier of one pair is at x.
  struct PairEval {
    double d2 = 0;
    collision::DistanceStencil stencil;
  };

  std::array<int, 4> vertices(const Pair& p) const;
  collision::PairPoints points(const Pair& p, const Eigen::VectorXd& x) const;
  double weight(const Pair& p) const;
  double mollifier_eps(const Pair& p) const;
  static std::uint64_t key(const Pair& p);
  static Pair pair_of(std::uint64_t key);  ///< key()'s inverse
  /// The Hessian pattern: these pairs and the pairs of `extra_keys` (m_pattern), and the pairs
  /// whose cliques the matrix gets (m_pattern_pairs).
  void set_pattern(std::vector<Pair> pairs, const std::vector<std::uint64_t>& extra_keys);
  /// Candidate pairs for every configuration on the segment x -> x + dx (the current set when
  /// it covers the segment).
  void build_candidates(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const;
  /// The candidate pairs valid at x (found again, for x alone, when x is not covered).
  void ensure_candidates(const Eigen::VectorXd& x) const;
  /// Finds the pairs at base x: within 1.5 dhat + 2 dhat at x (dx null), or within 1.5 dhat
  /// along the segment x -> x + dx.
  void find_candidates(const Eigen::VectorXd& x, const Eigen::VectorXd* dx) const;
  /// True when the current candidate set holds every pair within dhat at x.
  bool covered(const Eigen::VectorXd& x) const;
  /// Squared distance of candidate k and its stencil s; when a lower bound shows the squared
  /// distance is at least `reject2`, that bound instead (s not set). `moved`: motions(x).
  double stencil_distance2(std::size_t k, const collision::PairPoints& pts,
                           collision::DistanceStencil& s, double reject2,
                           const Eigen::VectorXd& moved) const;
  /// Per vertex, how far it is from m_base after removing the mean displacement [m]: a pair's
  /// distance differs from its distance at m_base by at most the largest of its first
  /// primitive's plus the largest of its second's.
  Eigen::VectorXd motions(const Eigen::VectorXd& x) const;
  double pair_motion(const Pair& p, const Eigen::VectorXd& moved) const;
  /// Adds one pair's barrier derivatives (gradient, Hessian projected to PSD when `project`) at
  /// distance stencil s.
  void add_pair(const Pair& p, const collision::PairPoints& pts,
                const collision::DistanceStencil& s, Eigen::VectorXd& g, BlockSymmetricMatrix* H,
                bool project) const;
  void add_friction(const Eigen::VectorXd& x, Eigen::VectorXd& g, BlockSymmetricMatrix* H) const;
  /// Trace topic `intersect`: when the step x -> x + alpha dx that max_step allows makes
  /// triangles intersect, prints each new pair's IPC pairs (candidate or not, distances, CCD).
  void report_crossings(const Eigen::VectorXd& x, const Eigen::VectorXd& dx, double alpha) const;
  /// Smallest distance of a candidate pair at x when it is below `floor`, else +inf [m].
  double distance_below(const Eigen::VectorXd& x, double floor) const;

  collision::SelfContactMesh m_mesh;
  SelfContactParams m_params;
  Eigen::VectorXd m_vertex_area, m_edge_area, m_edge_rest;
  double m_eps = 1e-6;      // friction smoothing: eps_velocity h (or h_whole) [m]
  double m_stiffness = 0;   // current stiffness [Pa] (Adaptive stiffness)
  double m_floor = 0;       // floor of the step [m]
  double m_t0 = 0;          // start of the step [s] (debug output)
  double m_last_below = 0;  // distance_below at the last iterate [m]

  // Candidates, found at the base positions m_base, either (a) every pair within 1.5 dhat +
  // m_margin there, or (b) every pair that comes within 1.5 dhat along the segment m_base ->
  // m_base + m_segment_dx. Pair distances do not change under a common translation, so (a)
  // holds every pair within dhat at any x whose vertices are within m_margin / 2 of base +
  // (mean displacement), and (b) at any x within dhat / 4 of a point of the segment after the
  // same removal (see covered).
  mutable std::vector<Pair> m_candidates;
  // Per candidate, a lower bound on its distance at m_base [m]: the best over the distances (or
  // bounds) found at earlier x, each less the pair's motion from m_base to that x; 0 until the
  // first. A candidate whose bound less its motion to x reaches the rejection distance needs no
  // closest-feature search at x (most candidates are mesh neighbours millimetres apart).
  mutable std::vector<double> m_base_distance;
  mutable Eigen::VectorXd m_base, m_segment_dx;
  mutable double m_margin = 0;

  std::vector<std::uint64_t> m_pattern;  // sorted pair keys in the Hessian pattern
  std::vector<Pair> m_pattern_pairs;
  std::vector<FrictionPair> m_friction;
  std::vector<std::uint64_t> m_friction_keys;

  mutable int m_active = 0;
  SelfContactStatistics m_own_stats;
  SelfContactStatistics* m_stats = &m_own_stats;
};

}  // namespace papersim::simulation
