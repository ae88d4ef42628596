#pragma once
/// The common interface of every term of the incremental potential
/// (inertia, gravity, damping, stretching, strain limit, bending, handles, contact, friction).
///
/// Positions are a flat vector x of size 3N (vertex v at x[3v..3v+2]) [m]. Each term evaluates
/// its elements on fixed-size Eigen types and adds element Hessians to the assembler, projected
/// to PSD or exact as the caller asks.
#include <Eigen/Core>
#include <limits>
#include <string>

#include "simulation/sheet_state.hpp"
#include "simulation/sparse_matrix.hpp"

namespace papersim::simulation {

/// What a term may need to know about the step being solved.
struct StepContext {
  double time_t0 = 0.0;  ///< start of the step [s]
  double h = 1e-3;       ///< step length [s]
  /// The step the run asked for, of which this one is a part when the solver split it
  /// (Integrator::step) [s]; 0: h (not split).
  double h_whole = 0.0;
  const Eigen::VectorXd* x_t0 = nullptr;  ///< positions at the step start (3N) [m]
  const Eigen::VectorXd* v_t0 = nullptr;  ///< velocities at the step start (3N) [m/s]
  double contact_stiffness = 0.0;         ///< SheetState::contact_stiffness at the step start [Pa]
  /// SheetState::self_contact_stiffness at the step start [Pa]
  double self_contact_stiffness = 0.0;
  double time_t1() const { return time_t0 + h; }
  double whole_step() const { return h_whole > 0 ? h_whole : h; }
};

/// How add_derivatives adds element Hessians that can be indefinite (as ipc-toolkit's
/// PSDProjectionMethod): projected to the nearest PSD matrix (negative eigenvalues clamped to 0)
/// or exact.
enum class HessianProjection { psd, none };

class EnergyTerm {
 public:
  virtual ~EnergyTerm() = default;
  /// Short name for statistics ("stretch", "bend", ...).
  virtual std::string name() const = 0;
  /// Declares every element's vertices so the Hessian pattern can be built (once, for the
  /// static part of the pattern: elements whose vertices never change).
  virtual void add_pattern(SparsityBuilder& pattern) const = 0;
  /// Terms whose elements change with the configuration (self-contact couples vertices far
  /// apart in the mesh) keep a dynamic part of the pattern. Called before every assembly at x;
  /// returns true when the term's coupled vertex cliques changed, so that the integrator
  /// rebuilds the matrix from add_pattern and every term's add_dynamic_pattern (and CHOLMOD
  /// redoes its symbolic analysis). After it returns, add_derivatives(x, ...) adds Hessian
  /// elements only within the pattern. Default: no dynamic part.
  virtual bool update_pattern(const Eigen::VectorXd& /*x*/) { return false; }
  /// Declares the cliques of the dynamic pattern (as chosen by the last update_pattern).
  virtual void add_dynamic_pattern(SparsityBuilder& /*pattern*/) const {}
  /// Called once at the start of each time step (lagged quantities, active sets).
  virtual void begin_step(const StepContext& /*ctx*/, const Eigen::VectorXd& /*x_t0*/) {}
  /// Called at the start of every Newton iteration but the first, at the iterate the last line
  /// search accepted: a term whose stiffness adapts to the iterates (the self-contact barrier,
  /// as in IPC) returns true when it changed, and the integrator evaluates the energy again.
  virtual bool adapt(const Eigen::VectorXd& /*x*/) { return false; }
  /// Called on the state a step (or part step) was accepted with: a term that carries a
  /// quantity from step to step writes it there (the barriers' stiffnesses).
  virtual void end_step(SheetState& /*state*/) const {}
  /// Value [J]; +infinity when x is infeasible for this term.
  virtual double value(const Eigen::VectorXd& x) const = 0;
  /// Adds the gradient [J/m] to `gradient` and, when `hessian` is not null, the element
  /// Hessians [J/m^2]. Terms whose exact element Hessians can be indefinite (the membrane under
  /// compression, the contact barriers) project them to PSD with `HessianProjection::psd` and
  /// add them exactly with `none`; the other terms' element Hessians are PSD either way. The
  /// integrator tries the exact Hessian first and projects when the assembled matrix is not
  /// positive definite (Integrator::newton_matrix). The gradient does not depend on
  /// `projection`.
  virtual void add_derivatives(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                               BlockSymmetricMatrix* hessian,
                               HessianProjection projection) const = 0;
  /// Adds the gradient alone.
  void add_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) const {
    add_derivatives(x, gradient, nullptr, HessianProjection::psd);
  }

  /// Unknowns of the linear system that are not positions: a term whose energy is minimised
  /// over internal variables y (the bending energy's edge slopes) keeps y out of the state
  /// (y = y*(x), recomputed by value and add_derivatives) but adds the (x, y) Hessian to the
  /// Newton system, whose position part is then the exact Newton direction of the condensed
  /// energy. Auxiliary unknowns are packed three per 3x3 block after the vertex blocks.
  virtual int auxiliary_blocks() const { return 0; }
  /// Block index of this term's first auxiliary block (called by the integrator).
  virtual void set_auxiliary_offset(int /*first_block*/) {}

  /// Largest alpha in (0, 1] such that x + a dx stays feasible for all a in [0, alpha]
  /// (continuous collision detection). Default: no constraint.
  virtual double max_step(const Eigen::VectorXd& /*x*/, const Eigen::VectorXd& /*dx*/) const {
    return 1.0;
  }

  /// Obstacles that move during the step (Integrator: "Following moving obstacles"). A term
  /// evaluates them at the step's end unless set_obstacle_time says otherwise.
  enum class ObstacleMotion {
    none,        ///< the term does not depend on obstacles that move during the current step
    follow,      ///< it does, and supports every call below
    unsupported  ///< it does, but cannot be evaluated with them part-way
  };
  virtual ObstacleMotion obstacle_motion() const { return ObstacleMotion::none; }
  /// True when, from x at the step start, an obstacle closes in on the sheet during the step by
  /// more than the sheet can be trusted to get out of its way in one solve.
  virtual bool obstacles_close_in(const Eigen::VectorXd& /*x*/) const { return false; }
  /// Evaluates the moving obstacles at time t [s] (within the current step) from now on.
  virtual void set_obstacle_time(double /*t*/) {}
  /// Adds (d gradient / d t) dt at x to `gradient`: how the gradient changes when the
  /// obstacles move on by dt [s].
  virtual void add_obstacle_motion_gradient(const Eigen::VectorXd& /*x*/, double /*dt*/,
                                            Eigen::VectorXd& /*gradient*/) const {}
  /// max_step for the joint motion x -> x + a dx, obstacle time t -> t + a dt.
  virtual double max_step_with_obstacles(const Eigen::VectorXd& x, const Eigen::VectorXd& dx,
                                         double /*dt*/) const {
    return max_step(x, dx);
  }
};

constexpr double INF = std::numeric_limits<double>::infinity();

}  // namespace papersim::simulation
