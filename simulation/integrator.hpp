#pragma once
/// Backward Euler as minimisation of the incremental potential (Li et al. 2020; Kane et al.
/// 2000), solved by Newton's method with PSD element Hessians, a sparse Cholesky solve, CCD
/// filtered backtracking line search, and step halving when Newton fails.
#include <chrono>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "simulation/energies/energy_term.hpp"
#include "simulation/linear_solver.hpp"
#include "simulation/sheet_state.hpp"
#include "simulation/trace.hpp"

namespace papersim::simulation {

struct NewtonParams {
  int max_iterations = 60;  ///< per time step
  /// Stopping test (IPC): the Newton step's largest vertex displacement divided by h is below
  /// this speed [m/s]. With h = 5 ms the default stops at 0.5 micrometre per step.
  double tolerance = 1e-4;
  double armijo = 1e-4;   ///< sufficient decrease constant [-]
  int max_halvings = 10;  ///< a failed step is split in two up to this depth
  /// Try the exact Hessian (no PSD projection of indefinite element matrices) first in every
  /// iteration, and project only when it is not positive definite. Projection throws away the
  /// negative curvature of compressed, buckling regions, and Newton then converges linearly
  /// there (measured on the pull scenario: 4x the iterations).
  bool exact_hessian_first = true;
  /// Within a time step, after the exact Hessian was found indefinite, factor the projected one
  /// directly for the next 1, 2, 4, ... iterations, at most this many (doubling while the exact
  /// one stays indefinite, back to 1 once it is definite), instead of assembling and trying the
  /// exact one first in every iteration of a buckled phase. 0: try the exact Hessian first in
  /// every iteration.
  int exact_retry_skip_max = 0;
  /// After a full step taken with a projected Hessian, try 2, 4, ... up to this many times the
  /// step while the energy keeps falling (1: off). Projection replaces the negative curvature
  /// of a sheet escaping a saddle by inertia alone, so the projected step is too short there and
  /// Newton crawls for tens of iterations (see docs/performance.md, "Bending model").
  int max_extrapolation = 1;
  /// Where the exact Hessian is indefinite, take the Newton direction from up to this many
  /// Steihaug-Toint conjugate-gradient iterations on the exact Hessian, preconditioned by the
  /// factored projected one (simulation/steihaug.hpp), instead of the projected Newton step
  /// (0: off). The trust region (in the projected Hessian's norm) starts each time step at the
  /// projected step's length, never falls below it, doubles after a full step whose energy
  /// change the exact model predicted within a quarter, and shrinks after a shortened one. The
  /// projected model is too stiff along the directions a compressed sheet buckles in, so its
  /// steps are too short there and Newton crawls (docs/performance.md, "Trust-region steps on the
  /// exact Hessian").
  int trust_region_cg = 0;
  /// Modified Newton in quiet phases (flight, rest): when the last time step converged within 2
  /// iterations on a factorisation of the exact (not projected) Hessian with the same h, up to
  /// this many consecutive iterations reuse that factorisation (and assemble only the gradient)
  /// instead of assembling and factoring again: the step's first iteration, and each following
  /// one whose predecessor took a full step with the residual falling tenfold or more.
  /// 0: refactor every iteration.
  /// Factoring is most of an iteration's cost (docs/performance.md, "Where a fall's time goes").
  int max_factor_reuse = 0;
  /// Follow moving obstacles within a step where they close in on the sheet
  /// (Integrator::follow_obstacles); false: every step starts against the obstacles at its end.
  bool follow_obstacles = true;
  /// What the solver tells when asked (topics newton, model, line-search, inf, solver); not a
  /// scene key.
  Trace trace;
};

/// What one Newton solve did.
struct NewtonResult {
  bool converged = false;
  int iterations = 0;
  int line_search_evaluations = 0;
  /// iterations whose step was lengthened (NewtonParams::max_extrapolation)
  int extrapolations = 0;
  int trust_region_steps = 0;  ///< directions from NewtonParams::trust_region_cg
  double residual = 0.0;       ///< last max |dx_v| / h [m/s]
  std::string failure;         ///< why it did not converge
};

/// The factorisation a quiet step leaves for the next one (NewtonParams::max_factor_reuse), as
/// a checkpoint saves it: the matrix that was factored and how far it has been reused.
struct ReusableFactor {
  double h = 0;    ///< time step of the factored matrix [s]
  int reused = 0;  ///< consecutive iterations that have reused it so far
  /// The matrix's stored entries (BlockSymmetricMatrix::values) on the Hessian pattern the run
  /// had when it was saved.
  std::vector<double> values;
};

/// Statistics of one accepted time step (accumulated over substeps).
struct StepStats {
  int substeps = 0;
  int failed_solves = 0;       ///< solves that did not converge and were retried with h / 2
  int projected_hessians = 0;  ///< iterations whose exact Hessian was indefinite (projected)
  /// iterations that factored the projected Hessian without trying the exact one
  /// (NewtonParams::exact_retry_skip_max)
  int exact_skipped = 0;
  int newton_iterations = 0;
  int line_search_evaluations = 0;
  int extrapolations = 0;         ///< Newton steps lengthened beyond the full step
  int trust_region_steps = 0;     ///< Newton steps from conjugate gradients on the exact Hessian
  int reused_factorizations = 0;  ///< iterations that reused the previous factorisation
  /// Newton iterations that moved obstacles from the step start to its end with the sheet
  /// (Integrator::follow_obstacles); counted in newton_iterations too.
  int following_iterations = 0;
  double seconds_assembly = 0, seconds_solve = 0, seconds_line_search = 0;
  double residual = 0;  ///< largest final residual [m/s]
  /// Sums the counts and times; keeps the larger residual.
  StepStats& operator+=(const StepStats& o);
};

class Integrator {
 public:
  /// @param terms the incremental potential; the integrator owns them.
  /// @param rigid_blocks unknowns of bodies solved with the sheet (a coupled lifting obstacle's
  ///        displacement, LiftBodyEnergy): blocks num_vertices .. num_vertices + rigid_blocks - 1
  ///        of the Newton system, and the entries after the sheet's 3N of the x every term sees.
  ///        Their positions and velocities are kept here (rigid_positions) and advance with the
  ///        sheet, over split steps too.
  Integrator(int num_vertices, std::vector<std::unique_ptr<EnergyTerm>> terms,
             const NewtonParams& params = {}, int rigid_blocks = 0);

  /// Positions and velocities of the rigid blocks (3 per block) from which the next step starts.
  void set_rigid_state(const Eigen::VectorXd& positions, const Eigen::VectorXd& velocities);
  const Eigen::VectorXd& rigid_positions() const { return m_rigid_x; }
  const Eigen::VectorXd& rigid_velocities() const { return m_rigid_v; }

  /// Advance `state` by h [s], splitting a failed step in two up to `max_halvings` times (< 0:
  /// NewtonParams::max_halvings).
  /// @throw NumericError when the step fails even after those splits, or NaN appears; `state`
  ///        may then have advanced part of the step.
  StepStats step(SheetState& state, double h, int max_halvings = -1);
  /// As above, counting into `stats` (which then holds the work of a step that failed too).
  void step(SheetState& state, double h, int max_halvings, StepStats& stats);

  /// Begins a step of length h from `state` and returns the incremental potential at its start
  /// (+inf when the state is infeasible for some term): the check of a state the integrator has
  /// not produced itself, such as a remeshed sheet. Obstacles that close in on the sheet during
  /// the step are where they are at its start, as the step itself starts with them (a roller
  /// pressing the sheet would otherwise overlap it at its end-of-step pose).
  double start_energy(const SheetState& state, double h);
  /// Total incremental potential at x for the step last begun (for tests and diagnostics).
  double energy(const Eigen::VectorXd& x) const;
  const std::vector<std::unique_ptr<EnergyTerm>>& terms() const { return m_terms; }
  EnergyTerm* find(const std::string& name) const;
  /// Builds the matrix from every term's present dynamic pattern (a pattern restored from a
  /// checkpoint, SelfContactEnergy::restore_pattern), before the first factorisation; not a
  /// pattern change (pattern_id() stays).
  void adopt_dynamic_patterns();
  /// The factorisation the next step may start from (NewtonParams::max_factor_reuse), if any:
  /// the last step converged within 2 iterations on the exact Hessian and the pattern has not
  /// changed since.
  std::optional<ReusableFactor> reusable_factor() const;
  /// Factors `f`'s matrix on the present pattern and lets the next step start from it as the
  /// run that saved it would have, before the first factorisation (after
  /// adopt_dynamic_patterns when the pattern was restored). The same matrix on the same pattern
  /// gives the same factor, so a run continued from a checkpoint takes the same steps.
  /// @throw std::invalid_argument when `f` does not fit the matrix (another number of entries,
  ///        one outside the pattern, NaN or inf, a time step not above 0) or its matrix is not
  ///        positive definite
  void adopt_factor(const ReusableFactor& f);
  /// Names the current Hessian sparsity pattern; it grows by one whenever a term's dynamic
  /// pattern changed (statistics and tests).
  long pattern_id() const { return m_pattern_id; }

 private:
  /// Newton's method on the step's incremental potential from x: newton_matrix, then
  /// newton_direction, the stopping test, line_search, extrapolate, update_trust_radius.
  NewtonResult solve(const StepContext& ctx, Eigen::VectorXd& x, StepStats& stats);
  using Clock = std::chrono::steady_clock::time_point;
  /// NewtonParams::exact_retry_skip_max within one solve: the iterations left that factor the
  /// projected Hessian without trying the exact one, and the length of the next such run.
  struct ExactSkip {
    int left = 0, backoff = 1;
  };
  /// The Newton matrix of an iteration at x, with the gradient into g: the last factorisation
  /// reused (`reuse`: the gradient alone is assembled) or the Hessian assembled and factored
  /// (factor_newton_matrix). `t0`: when the iteration's assembly began, reset at its end.
  /// @return whether the factorisation in use is of the projected Hessian (`factor_projected`
  ///         when reused)
  bool newton_matrix(const StepContext& ctx, const Eigen::VectorXd& x, Eigen::VectorXd& g,
                     StepStats& stats, bool reuse, bool factor_projected, ExactSkip& skip,
                     Clock& t0);
  /// A Newton direction: the factored system's solution (with the auxiliary unknowns) and its
  /// position part; trust_model < 0 when it is a trust-region step on the exact Hessian, the
  /// exact model's change along it.
  struct NewtonDirection {
    Eigen::VectorXd sol, dx;
    double trust_model = 0;
  };
  /// Solves for the direction on the factorisation in use (-g on the right), sets r.residual
  /// (the projected step's largest vertex displacement / h) and, where the projected Hessian was
  /// factored and NewtonParams::trust_region_cg is on, takes the Steihaug step instead.
  NewtonDirection newton_direction(const Eigen::VectorXd& g, double h, bool project,
                                   NewtonResult& r);
  /// The backtracking line search along dx from x (energy e, gradient g): alpha starts at the
  /// largest step every term allows (max_step) and halves until the Armijo condition holds or
  /// alpha <= min_alpha.
  struct LineSearch {
    double alpha = 1.0, alpha_feasible = 1.0, slope = 0.0, min_alpha = 0.0,
           e_new = std::numeric_limits<double>::infinity();
    Eigen::VectorXd x_new;
  };
  LineSearch line_search(const Eigen::VectorXd& x, const Eigen::VectorXd& dx,
                         const Eigen::VectorXd& g, double e, NewtonResult& r) const;
  /// After a full projected step: tries 2, 4, ... times dx up to NewtonParams::max_extrapolation
  /// while the energy keeps falling and every term allows it, updating ls.
  void extrapolate(const Eigen::VectorXd& x, const Eigen::VectorXd& dx, double e, LineSearch& ls,
                   NewtonResult& r) const;
  /// The trust region after a step of length alpha whose energy change was `change` against the
  /// exact model's `model` (< 0).
  void update_trust_radius(double alpha, double change, double model);
  /// Following moving obstacles: with the obstacles evaluated at time tau (the step start),
  /// moves them to the step's end in Newton iterations on the joint motion (see the .cpp).
  /// @return false (r.failure set) when they cannot get there within the iteration budget
  bool follow_obstacles(const StepContext& ctx, Eigen::VectorXd& x, double tau, StepStats& stats,
                        NewtonResult& r);
  /// Terms whose moving obstacles are followed in this step (empty: evaluated at the step's end).
  std::vector<EnergyTerm*> m_following;
  /// Begins a step on every term and chooses the terms whose obstacles are followed
  /// (m_following), those set to the step start.
  void begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0);
  /// Sets x_t0 and v_t0 to the step start of `state` (the sheet's, then the rigid blocks'),
  /// begins a step of length h there, and returns its context (which points into x_t0, v_t0).
  /// h_whole: StepContext::h_whole.
  StepContext begin_step(const SheetState& state, double h, double h_whole, Eigen::VectorXd& x_t0,
                         Eigen::VectorXd& v_t0);
  bool advance(SheetState& state, double h, int depth, int max_depth, StepStats& stats);
  /// The gradient of the incremental potential at x into g (no Hessian).
  void assemble_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const;
  /// Gradient and Hessian at x (element Hessians projected to PSD when `project`).
  void assemble(const Eigen::VectorXd& x, Eigen::VectorXd& g, bool project);
  /// Assembles at x and factors the Newton matrix: the exact Hessian first (when
  /// NewtonParams::exact_hessian_first), the projected one when that is not positive definite.
  /// `skip_exact`: factor the projected Hessian without trying the exact one.
  /// @return true when the factored matrix is the projected Hessian
  /// @throw NumericError when even a shifted projected Hessian cannot be factored
  bool factor_newton_matrix(const StepContext& ctx, const Eigen::VectorXd& x, Eigen::VectorXd& g,
                            StepStats& stats, bool skip_exact = false);
  /// Asks every term whether its dynamic pattern changed at x and rebuilds the matrix if so.
  void update_pattern(const Eigen::VectorXd& x);
  /// The matrix of the static pattern and every term's dynamic pattern.
  void build_matrix();
  /// Traces (topic `model`) each term's change along the Newton step sol from x against its
  /// quadratic model.
  void trace_model(const Eigen::VectorXd& x, const Eigen::VectorXd& sol, bool project);
  /// The sheet's positions (or velocities) followed by the rigid blocks'.
  Eigen::VectorXd with_rigid(const Eigen::VectorXd& sheet, const Eigen::VectorXd& rigid) const;
  std::vector<std::unique_ptr<EnergyTerm>> m_terms;
  NewtonParams m_params;
  Eigen::VectorXd m_rigid_x, m_rigid_v;  // rigid blocks (3 per block)
  BlockPattern m_static_pattern;         // from add_pattern, built once
  BlockSymmetricMatrix m_hessian;
  /// The exact Hessian behind a projected factorisation (NewtonParams::trust_region_cg);
  /// valid while m_have_exact.
  BlockSymmetricMatrix m_hessian_exact;
  bool m_have_exact = false;
  double m_trust_radius = 0;  // of NewtonParams::trust_region_cg, in the projected Hessian's norm
  LinearSolver m_solver;
  long m_pattern_id = 0;
  long m_factor_pattern = -1;  // pattern of the factorisation in m_solver (-1: none yet)
  double m_factor_h = 0;       // time step of the factorisation in m_solver [s]
  int m_reused = 0;            // consecutive iterations that reused it
  bool m_reuse_next = false;   // the last solve converged within 2 iterations, exact Hessian
};

}  // namespace papersim::simulation
