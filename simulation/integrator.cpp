#include "simulation/integrator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>

#include "common/assert.hpp"
#include "common/clock.hpp"
#include "simulation/errors.hpp"
#include "simulation/steihaug.hpp"

namespace papersim::simulation {

namespace {

double max_vertex_norm(const Eigen::VectorXd& d) {
  double m = 0;
  for (int v = 0; v < d.size() / 3; ++v) m = std::max(m, d.segment<3>(3 * v).squaredNorm());
  return std::sqrt(m);
}

}  // namespace

Eigen::MatrixX3d SheetState::positions_matrix() const {
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
      positions.data(), num_vertices(), 3);
}

Eigen::MatrixX3d SheetState::velocities_matrix() const {
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
      velocities.data(), num_vertices(), 3);
}

Eigen::VectorXd flatten(const Eigen::MatrixX3d& m) {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> r = m;
  return Eigen::Map<const Eigen::VectorXd>(r.data(), r.size());
}

StepStats& StepStats::operator+=(const StepStats& o) {
  substeps += o.substeps;
  failed_solves += o.failed_solves;
  projected_hessians += o.projected_hessians;
  exact_skipped += o.exact_skipped;
  newton_iterations += o.newton_iterations;
  line_search_evaluations += o.line_search_evaluations;
  extrapolations += o.extrapolations;
  trust_region_steps += o.trust_region_steps;
  reused_factorizations += o.reused_factorizations;
  following_iterations += o.following_iterations;
  seconds_assembly += o.seconds_assembly;
  seconds_solve += o.seconds_solve;
  seconds_line_search += o.seconds_line_search;
  residual = std::max(residual, o.residual);
  return *this;
}

Integrator::Integrator(int num_vertices, std::vector<std::unique_ptr<EnergyTerm>> terms,
                       const NewtonParams& params, int rigid_blocks)
    : m_terms(std::move(terms)),
      m_params(params),
      m_rigid_x(Eigen::VectorXd::Zero(3 * rigid_blocks)),
      m_rigid_v(Eigen::VectorXd::Zero(3 * rigid_blocks)),
      m_solver(params.trace) {
  const int first_auxiliary = num_vertices + rigid_blocks;
  int blocks = first_auxiliary;
  for (const auto& t : m_terms) {
    t->set_auxiliary_offset(blocks);
    blocks += t->auxiliary_blocks();
  }
  SparsityBuilder pattern(blocks, first_auxiliary);
  for (const auto& t : m_terms) t->add_pattern(pattern);
  m_static_pattern = pattern.finish();
  m_hessian = BlockSymmetricMatrix(m_static_pattern);
}

void Integrator::set_rigid_state(const Eigen::VectorXd& positions,
                                 const Eigen::VectorXd& velocities) {
  PAPERSIM_ASSERT(positions.size() == m_rigid_x.size() && velocities.size() == m_rigid_v.size(),
                  "Integrator::set_rigid_state: wrong number of rigid unknowns");
  m_rigid_x = positions;
  m_rigid_v = velocities;
}

Eigen::VectorXd Integrator::with_rigid(const Eigen::VectorXd& sheet,
                                       const Eigen::VectorXd& rigid) const {
  if (rigid.size() == 0) return sheet;
  Eigen::VectorXd x(sheet.size() + rigid.size());
  x << sheet, rigid;
  return x;
}

void Integrator::update_pattern(const Eigen::VectorXd& x) {
  bool changed = false;
  for (const auto& t : m_terms) changed = t->update_pattern(x) || changed;
  if (!changed) return;
  build_matrix();
  ++m_pattern_id;  // the solver redoes its symbolic analysis
  m_params.trace(Trace::solver, "pattern %ld nnz %zu (structure %zu)", m_pattern_id,
                 m_hessian.values().size(), m_hessian.structure_rows().size());
}

void Integrator::adopt_dynamic_patterns() {
  PAPERSIM_ASSERT(m_factor_pattern < 0,
                  "Integrator::adopt_dynamic_patterns: after a factorisation");
  build_matrix();
}

std::optional<ReusableFactor> Integrator::reusable_factor() const {
  if (!m_reuse_next || m_params.max_factor_reuse <= 0 || m_factor_pattern != m_pattern_id)
    return std::nullopt;
  // m_hessian still holds the factored matrix: a converged solve with m_reuse_next set factored
  // the exact Hessian last (or reused the one before), and nothing assembles between steps.
  return ReusableFactor{m_factor_h, m_reused, m_hessian.values()};
}

void Integrator::adopt_factor(const ReusableFactor& f) {
  PAPERSIM_ASSERT(m_factor_pattern < 0, "Integrator::adopt_factor: after a factorisation");
  if (f.values.size() != m_hessian.values().size())
    throw std::invalid_argument("the saved factorisation's matrix has " +
                                std::to_string(f.values.size()) + " entries, this run's " +
                                std::to_string(m_hessian.values().size()));
  if (!(f.h > 0) || f.reused < 0)
    throw std::invalid_argument("the saved factorisation has time step " + std::to_string(f.h) +
                                " s and " + std::to_string(f.reused) + " reuses");
  if (!std::all_of(f.values.begin(), f.values.end(), [](double a) { return std::isfinite(a); }))
    throw std::invalid_argument("the saved factorisation's matrix holds NaN or inf");
  for (int k : m_hessian.outside_positions())
    if (f.values[k] != 0.0)
      throw std::invalid_argument(
          "the saved factorisation's matrix has an entry outside this run's pattern");
  m_hessian.values() = f.values;
  if (!m_solver.factorize(m_hessian, m_pattern_id))
    throw std::invalid_argument("the saved factorisation's matrix is not positive definite");
  m_factor_pattern = m_pattern_id;
  m_factor_h = f.h;
  m_reused = f.reused;
  m_reuse_next = true;
}

void Integrator::build_matrix() {
  SparsityBuilder pattern(m_static_pattern);
  for (const auto& t : m_terms) t->add_dynamic_pattern(pattern);
  m_hessian = BlockSymmetricMatrix(pattern.finish());
}

EnergyTerm* Integrator::find(const std::string& name) const {
  for (const auto& t : m_terms)
    if (t->name() == name) return t.get();
  return nullptr;
}

double Integrator::energy(const Eigen::VectorXd& x) const {
  double e = 0;
  for (const auto& t : m_terms) {
    e += t->value(x);
    if (!std::isfinite(e)) {
      m_params.trace(Trace::inf, "  infinite: %s", t->name().c_str());
      return INF;
    }
  }
  return e;
}

double Integrator::start_energy(const SheetState& state, double h) {
  Eigen::VectorXd x_t0, v_t0;
  begin_step(state, h, h, x_t0, v_t0);
  const double e = energy(x_t0);
  m_following.clear();
  return e;
}

StepContext Integrator::begin_step(const SheetState& state, double h, double h_whole,
                                   Eigen::VectorXd& x_t0, Eigen::VectorXd& v_t0) {
  x_t0 = with_rigid(state.positions, m_rigid_x);
  v_t0 = with_rigid(state.velocities, m_rigid_v);
  StepContext ctx;
  ctx.time_t0 = state.time;
  ctx.h = h;
  ctx.h_whole = h_whole;
  ctx.x_t0 = &x_t0;
  ctx.v_t0 = &v_t0;
  ctx.contact_stiffness = state.contact_stiffness;
  ctx.self_contact_stiffness = state.self_contact_stiffness;
  begin_step(ctx, x_t0);
  return ctx;
}

void Integrator::begin_step(const StepContext& ctx, const Eigen::VectorXd& x_t0) {
  for (const auto& t : m_terms) t->begin_step(ctx, x_t0);
  // Following moving obstacles: where an obstacle closes in on the sheet during the step, the
  // step starts with the obstacles where they are at its start (where x_t0 is feasible) and
  // moves them to its end inside the Newton solve (follow_obstacles).
  m_following.clear();
  bool can_follow = true;
  for (const auto& t : m_terms) {
    const auto motion = t->obstacle_motion();
    if (motion == EnergyTerm::ObstacleMotion::unsupported) can_follow = false;
    if (motion == EnergyTerm::ObstacleMotion::follow && t->obstacles_close_in(x_t0))
      m_following.push_back(t.get());
  }
  if (!can_follow || !m_params.follow_obstacles) m_following.clear();
  for (EnergyTerm* t : m_following) t->set_obstacle_time(ctx.time_t0);
}

void Integrator::assemble_gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const {
  g.setZero();
  for (const auto& t : m_terms) t->add_gradient(x, g);
}

void Integrator::assemble(const Eigen::VectorXd& x, Eigen::VectorXd& g, bool project) {
  g.setZero();
  m_hessian.set_zero();
  const HessianProjection projection = project ? HessianProjection::psd : HessianProjection::none;
  for (const auto& t : m_terms) t->add_derivatives(x, g, &m_hessian, projection);
}

bool Integrator::factor_newton_matrix(const StepContext& ctx, const Eigen::VectorXd& x,
                                      Eigen::VectorXd& g, StepStats& stats, bool skip_exact) {
  auto t0 = std::chrono::steady_clock::now();
  bool project = !m_params.exact_hessian_first || skip_exact;
  m_have_exact = false;
  assemble(x, g, project);
  stats.seconds_assembly += seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  if (!project && !m_solver.factorize(m_hessian, m_pattern_id)) {
    // The exact Hessian is indefinite here: fall back to the projected one.
    ++stats.projected_hessians;
    project = true;
    if (m_params.trust_region_cg > 0) {
      m_hessian_exact = m_hessian;
      m_have_exact = true;
    }
    const auto t1 = std::chrono::steady_clock::now();
    assemble(x, g, true);
    stats.seconds_assembly += seconds_since(t1);
  }
  // Projected element Hessians are PSD and inertia makes the sum definite; round-off can still
  // stop the factorisation (LinearSolver::factorize_shifted): in the static limit, and where a
  // barrier at a tiny gap puts entries ~1e22 beside inertia (fold seed 12, t = 4.035 s).
  if (project && m_solver.factorize_shifted(m_hessian, m_pattern_id) < 0) {
    const auto& v = m_hessian.values();
    const auto bad = std::count_if(v.begin(), v.end(), [](double a) { return !std::isfinite(a); });
    double largest = 0;
    for (double a : v)
      if (std::isfinite(a)) largest = std::max(largest, std::abs(a));
    char what[160];
    std::snprintf(what, sizeof what,
                  "newton: the Hessian cannot be factored (t = %.6g s, h = %.3g s, %ld non-finite "
                  "entries, largest entry %.3g)",
                  ctx.time_t0, ctx.h, static_cast<long>(bad), largest);
    throw NumericError(what);
  }
  m_factor_pattern = m_pattern_id;
  stats.seconds_solve += seconds_since(t0);
  return project;
}

void Integrator::trace_model(const Eigen::VectorXd& x, const Eigen::VectorXd& sol, bool project) {
  // Each term's change along the full Newton step against its quadratic model (the Hessian
  // with the same projection as the factorisation in use).
  const Eigen::VectorXd dx = sol.head(x.size());
  BlockSymmetricMatrix h = m_hessian;
  std::string text = "  model:";
  for (const auto& t : m_terms) {
    Eigen::VectorXd gt = Eigen::VectorXd::Zero(x.size());
    h.set_zero();
    t->add_derivatives(x, gt, &h, project ? HessianProjection::psd : HessianProjection::none);
    const double lin = gt.dot(dx), quad = 0.5 * sol.dot(h.multiply(sol));
    const double actual = t->value(x + dx) - t->value(x);
    char buf[96];
    std::snprintf(buf, sizeof buf, " %s %.3e/%.3e", t->name().c_str(), actual, lin + quad);
    text += buf;
  }
  m_params.trace.line(Trace::model, text);
}

bool Integrator::newton_matrix(const StepContext& ctx, const Eigen::VectorXd& x, Eigen::VectorXd& g,
                               StepStats& stats, bool reuse, bool factor_projected, ExactSkip& skip,
                               Clock& t0) {
  if (reuse) {
    ++m_reused;
    ++stats.reused_factorizations;
    assemble_gradient(x, g);
    stats.seconds_assembly += seconds_since(t0);
    t0 = std::chrono::steady_clock::now();
    return factor_projected;
  }
  m_reused = 0;
  const bool skipped = skip.left > 0;
  const bool projected = factor_newton_matrix(ctx, x, g, stats, skipped);
  if (skipped) {
    --skip.left;
    ++stats.exact_skipped;
  } else if (m_params.exact_retry_skip_max > 0 && m_params.exact_hessian_first && projected) {
    skip.left = skip.backoff;  // the exact Hessian was indefinite: skip it for a while
    skip.backoff = std::min(2 * skip.backoff, m_params.exact_retry_skip_max);
  } else {
    skip.backoff = 1;
  }
  m_factor_h = ctx.h;
  t0 = std::chrono::steady_clock::now();
  return projected;
}

Integrator::NewtonDirection Integrator::newton_direction(const Eigen::VectorXd& g, double h,
                                                         bool project, NewtonResult& r) {
  NewtonDirection d;
  // Auxiliary unknowns (EnergyTerm::auxiliary_blocks) sit at their optimum, so their part of
  // the right-hand side is zero; their part of the solution is dropped.
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m_hessian.size());
  rhs.head(g.size()) = -g;
  d.sol = m_solver.solve(rhs);
  d.dx = d.sol.head(g.size());
  r.residual = max_vertex_norm(d.dx) / h;  // the stopping test stays the projected step's
  if (r.iterations == 1) m_trust_radius = 0;
  if (project && m_have_exact && r.residual >= m_params.tolerance) {
    const double projected_norm = std::sqrt(d.sol.dot(m_hessian.multiply(d.sol)));
    m_trust_radius = std::max(m_trust_radius, projected_norm);
    const SteihaugResult cg =
        steihaug([&](const Eigen::VectorXd& v) { return m_hessian_exact.multiply(v); },
                 [&](const Eigen::VectorXd& v) { return m_hessian.multiply(v); },
                 [&](const Eigen::VectorXd& v) { return m_solver.solve(v); }, rhs, d.sol,
                 m_trust_radius, m_params.trust_region_cg, 0.1);
    if (cg.model < 0 && cg.z.allFinite()) {  // else the projected step
      d.sol = cg.z;
      d.dx = d.sol.head(g.size());
      d.trust_model = cg.model;
      ++r.trust_region_steps;
    }
    m_params.trace(
        Trace::newton,
        "  trust region: %d iterations, end %d, radius %.3e (projected step %.3e), model %.3e",
        cg.iterations, static_cast<int>(cg.end), m_trust_radius, projected_norm, cg.model);
  }
  return d;
}

Integrator::LineSearch Integrator::line_search(const Eigen::VectorXd& x, const Eigen::VectorXd& dx,
                                               const Eigen::VectorXd& g, double e,
                                               NewtonResult& r) const {
  LineSearch ls;
  const EnergyTerm* limiting = nullptr;
  for (const auto& t : m_terms) {
    const double a = t->max_step(x, dx);
    if (a < ls.alpha) ls.alpha = a, limiting = t.get();
  }
  ls.alpha_feasible = ls.alpha;
  ls.slope = g.dot(dx);
  // A step that would move no vertex by more than a picometre makes no progress: the line
  // search gives up there (at round-off level an energy with a search-based term, such as
  // face contact, can show a decrease that is only noise, and Newton would repeat it).
  ls.min_alpha = std::max(1e-12, 1e-12 / std::max(max_vertex_norm(dx), 1e-300));
  for (; ls.alpha > ls.min_alpha; ls.alpha *= 0.5) {
    ls.x_new = x + ls.alpha * dx;
    ls.e_new = energy(ls.x_new);
    ++r.line_search_evaluations;
    if (std::isfinite(ls.e_new) && ls.e_new <= e + m_params.armijo * ls.alpha * ls.slope) break;
  }
  if (m_params.trace.on(Trace::newton))  // the term's name is a string made on each call
    m_params.trace(Trace::newton, "  step %.3e (feasible %.3e, limited by %s)", ls.alpha,
                   ls.alpha_feasible, limiting ? limiting->name().c_str() : "none");
  if (ls.alpha < 1e-9 && m_params.trace.on(Trace::line_search)) {
    for (double a = 1e-1; a > 1e-13; a *= 0.1) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "   a %.0e", a);
      std::string text = buf;
      for (const auto& t : m_terms) {
        std::snprintf(buf, sizeof buf, " %s %.6e", t->name().c_str(),
                      t->value(x + a * dx) - t->value(x));
        text += buf;
      }
      std::snprintf(buf, sizeof buf, " slope*a %.3e", a * ls.slope);
      m_params.trace.line(Trace::line_search, text + buf);
    }
  }
  return ls;
}

void Integrator::extrapolate(const Eigen::VectorXd& x, const Eigen::VectorXd& dx, double e,
                             LineSearch& ls, NewtonResult& r) const {
  // Lengthen the projected step while the energy keeps falling (sufficient decrease against the
  // longer step too) and every term allows the longer step.
  for (int m = 2; m <= m_params.max_extrapolation; m *= 2) {
    double feasible = 1.0;
    const Eigen::VectorXd dm = m * dx;
    for (const auto& t : m_terms) feasible = std::min(feasible, t->max_step(x, dm));
    if (feasible < 1.0) break;
    Eigen::VectorXd x_try = x + dm;
    const double e_try = energy(x_try);
    ++r.line_search_evaluations;
    if (!(std::isfinite(e_try) && e_try < ls.e_new && e_try <= e + m_params.armijo * m * ls.slope))
      break;
    ls.x_new.swap(x_try);
    ls.e_new = e_try;
    if (m == 2) ++r.extrapolations;
  }
}

void Integrator::update_trust_radius(double alpha, double change, double model) {
  // The radius doubles after a full step whose energy change the exact model predicted within a
  // quarter and shrinks after a shortened one (it never falls below the projected step:
  // newton_direction).
  const double agreement = change / model;
  if (alpha < 1.0 || agreement < 0.25)
    m_trust_radius *= 0.25 + 0.375 * alpha;
  else if (agreement > 0.75)
    m_trust_radius *= 2;
}

NewtonResult Integrator::solve(const StepContext& ctx, Eigen::VectorXd& x, StepStats& stats) {
  NewtonResult r;
  Eigen::VectorXd g(x.size());

  double e = energy(x);
  if (!std::isfinite(e)) {
    r.failure = "the start of the step is infeasible";
    return r;
  }
  // Modified Newton (NewtonParams::max_factor_reuse), in quiet phases only: when the last step
  // converged within 2 iterations on an exact-Hessian factorisation with the same h, this step
  // starts from that factorisation, and its iterations reuse it while Newton converges fast (a
  // full step, the residual falling tenfold or more). `quiet`: the last step needed at most 2
  // iterations.
  const bool quiet = m_reuse_next && m_factor_h == ctx.h;
  bool may_reuse = quiet;
  double residual_before = INF;   // residual of the iteration before the last
  bool factor_projected = false;  // the factorisation in use is of the projected Hessian
  ExactSkip skip;
  for (r.iterations = 1; r.iterations <= m_params.max_iterations; ++r.iterations) {
    auto t0 = std::chrono::steady_clock::now();
    if (r.iterations > 1) {
      bool adapted = false;
      for (const auto& t : m_terms) adapted = t->adapt(x) || adapted;
      if (adapted) {
        e = energy(x);  // the line searches compare energies of the same stiffness
        may_reuse = false;
      }
    }
    update_pattern(x);
    const bool reuse =
        may_reuse && m_reused < m_params.max_factor_reuse && m_factor_pattern == m_pattern_id;
    m_reuse_next = false;
    factor_projected = newton_matrix(ctx, x, g, stats, reuse, factor_projected, skip, t0);
    const bool project = factor_projected;
    const NewtonDirection d = newton_direction(g, ctx.h, project, r);
    stats.seconds_solve += seconds_since(t0);
    if (m_params.trace.on(Trace::model)) trace_model(x, d.sol, project);
    if (m_params.trace.on(Trace::newton))  // the decrement costs a dot product
      m_params.trace(Trace::newton, "t %.4f it %d E %.12g residual %.3e decrement %.3e %s",
                     ctx.time_t0, r.iterations, e, r.residual, -g.dot(d.dx),
                     reuse     ? "reused"
                     : project ? "projected"
                               : "exact");
    if (!d.dx.allFinite()) {
      r.failure = "NaN in the Newton direction";
      return r;
    }
    if (r.residual < m_params.tolerance) {
      r.converged = true;
      // A quiet step (flight, rest) lets the next one start from this factorisation.
      m_reuse_next = !factor_projected && r.iterations <= 2;
      return r;
    }
    t0 = std::chrono::steady_clock::now();
    LineSearch ls = line_search(x, d.dx, g, e, r);
    stats.seconds_line_search += seconds_since(t0);
    if (!(ls.alpha > ls.min_alpha)) {
      // No decrease along the direction: converged to round-off when the step is tiny.
      // (A step blocked by collision detection is not convergence: the step is split instead.)
      if ((ls.alpha_feasible == 1.0 && r.residual < 10 * m_params.tolerance) ||
          std::abs(ls.slope) < 1e-14 * std::abs(e)) {
        r.converged = true;
        return r;
      }
      r.failure = "line search found no decrease";
      return r;
    }
    if (project && ls.alpha == 1.0 && m_params.max_extrapolation > 1)
      extrapolate(x, d.dx, e, ls, r);
    if (d.trust_model < 0) update_trust_radius(ls.alpha, ls.e_new - e, d.trust_model);
    may_reuse = quiet && ls.alpha == 1.0 && !factor_projected &&
                (r.iterations == 1 || r.residual < 0.1 * residual_before);
    residual_before = r.residual;
    x = ls.x_new;
    e = ls.e_new;
  }
  --r.iterations;
  std::ostringstream s;
  s << "no convergence in " << m_params.max_iterations << " iterations (residual " << r.residual
    << " m/s)";
  r.failure = s.str();
  return r;
}

// Following moving obstacles. A step must start where every term is finite, and the barrier
// holds a pressed vertex closer to an obstacle than the obstacle moves in a step (the fold's
// roller moves 2.3 mm per 10 ms step and presses the sheet to gaps of micrometres), so x_t0 is
// often inside the obstacle as it is at the step's end, and halving the step cannot catch up.
// Instead the obstacles start where they are at the step start, tau = t0, and move with the
// sheet: each iteration solves H dx = -(g + (dg/dtau) dtau) with dtau = t1 - tau, the Newton
// step of the incremental potential together with the sheet's linear response to the
// obstacles' motion (a pressed vertex is carried along the obstacle's normal velocity), takes
// the largest joint step a (x + a dx, tau + a dtau) that continuous collision detection on the
// joint motion allows and where the potential is finite, and ends when tau reaches t1. Newton
// (solve) then converges with the obstacles at t1: the step solves the same backward Euler
// problem as without following, from a start that the obstacles' motion does not make
// infeasible.
bool Integrator::follow_obstacles(const StepContext& ctx, Eigen::VectorXd& x, double tau,
                                  StepStats& stats, NewtonResult& r) {
  const double t1 = ctx.time_t1();
  const auto set_time = [&](double t) {
    for (EnergyTerm* term : m_following) term->set_obstacle_time(t);
  };
  Eigen::VectorXd g(x.size());
  m_reuse_next = false;
  while (tau < t1) {
    if (r.iterations >= m_params.max_iterations) {
      std::ostringstream s;
      s << "the obstacles could not be moved with the sheet to the step's end (stopped at t = "
        << tau << " s)";
      r.failure = s.str();
      set_time(t1);
      return false;
    }
    ++r.iterations;
    ++stats.following_iterations;
    auto t0 = std::chrono::steady_clock::now();
    update_pattern(x);
    factor_newton_matrix(ctx, x, g, stats);
    m_reused = 0;
    m_factor_h = ctx.h;
    const double dt = t1 - tau;
    t0 = std::chrono::steady_clock::now();
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m_hessian.size());
    Eigen::VectorXd moving = g;
    for (EnergyTerm* term : m_following) term->add_obstacle_motion_gradient(x, dt, moving);
    rhs.head(g.size()) = -moving;
    const Eigen::VectorXd dx = m_solver.solve(rhs).head(g.size());
    stats.seconds_solve += seconds_since(t0);
    if (!dx.allFinite()) {
      r.failure = "NaN in the Newton direction while following the obstacles";
      set_time(t1);
      return false;
    }
    t0 = std::chrono::steady_clock::now();
    double alpha = 1.0;
    for (const auto& term : m_terms)
      alpha = std::min(alpha, term->max_step_with_obstacles(x, dx, dt));
    for (; alpha > 1e-12; alpha *= 0.5) {
      set_time(alpha == 1.0 ? t1 : tau + alpha * dt);
      ++r.line_search_evaluations;
      if (std::isfinite(energy(x + alpha * dx))) break;
    }
    stats.seconds_line_search += seconds_since(t0);
    if (!(alpha > 1e-12)) {
      std::ostringstream s;
      s << "the obstacles cannot move on with the sheet at t = " << tau << " s";
      r.failure = s.str();
      set_time(t1);
      return false;
    }
    m_params.trace(Trace::newton, "t %.4f following: obstacles at %.6f, step %.3e", ctx.time_t0,
                   tau, alpha);
    x += alpha * dx;
    tau = alpha == 1.0 ? t1 : tau + alpha * dt;
  }
  return true;
}

bool Integrator::advance(SheetState& state, double h, int depth, int max_depth, StepStats& stats) {
  Eigen::VectorXd x_t0, v_t0;
  // A split step is h = h_whole / 2^depth (exact in binary floating point).
  const StepContext ctx = begin_step(state, h, std::ldexp(h, depth), x_t0, v_t0);
  // Start from the explicit prediction x_t0 + h v_t0 when it is feasible (CCD-safe from x_t0
  // and finite energy): Newton then only corrects it, instead of producing the whole motion of
  // the step from rest (measured: about half the iterations on a falling sheet).
  Eigen::VectorXd x = x_t0;
  const Eigen::VectorXd dx0 = h * v_t0;
  double alpha = 1.0;
  for (const auto& t : m_terms) alpha = std::min(alpha, t->max_step(x_t0, dx0));
  if (alpha > 0) {
    const Eigen::VectorXd x_pred = x_t0 + alpha * dx0;
    const double e_pred = energy(x_pred);
    if (std::isfinite(e_pred)) {
      const double e_t0 = energy(x_t0);
      if (e_pred <= e_t0 + 1e-12 * std::abs(e_t0)) x = x_pred;
    }
  }
  NewtonResult r;
  m_params.trace(Trace::newton, "step t %.6f h %.3e: %zu terms follow obstacles", ctx.time_t0, h,
                 m_following.size());
  if (m_following.empty() || follow_obstacles(ctx, x, ctx.time_t0, stats, r)) {
    const int following = r.iterations, evaluations = r.line_search_evaluations;
    r = solve(ctx, x, stats);
    r.iterations += following;
    r.line_search_evaluations += evaluations;
  }
  m_following.clear();
  stats.newton_iterations += r.iterations;
  stats.line_search_evaluations += r.line_search_evaluations;
  stats.extrapolations += r.extrapolations;
  stats.trust_region_steps += r.trust_region_steps;
  stats.residual = std::max(stats.residual, r.residual);
  if (!r.converged) {
    m_params.trace(Trace::newton, "  failed: %s", r.failure.c_str());
    ++stats.failed_solves;
    if (depth >= max_depth) {
      std::ostringstream s;
      s << "time step failed at t = " << state.time << " s with h = " << h << " s: " << r.failure;
      throw NumericError(s.str());
    }
    return advance(state, 0.5 * h, depth + 1, max_depth, stats) &&
           advance(state, 0.5 * h, depth + 1, max_depth, stats);
  }
  const Eigen::Index n = state.positions.size(), nr = m_rigid_x.size();
  state.velocities = (x.head(n) - x_t0.head(n)) / h;
  state.positions = x.head(n);
  m_rigid_v = (x.tail(nr) - x_t0.tail(nr)) / h;
  m_rigid_x = x.tail(nr);
  state.time += h;
  for (const auto& t : m_terms) t->end_step(state);
  ++stats.substeps;
  if (!state.positions.allFinite()) throw NumericError("NaN in the positions after a step");
  return true;
}

StepStats Integrator::step(SheetState& state, double h, int max_halvings) {
  StepStats stats;
  step(state, h, max_halvings, stats);
  return stats;
}

void Integrator::step(SheetState& state, double h, int max_halvings, StepStats& stats) {
  advance(state, h, 0, max_halvings < 0 ? m_params.max_halvings : max_halvings, stats);
}

}  // namespace papersim::simulation
