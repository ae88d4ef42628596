#include "simulation/linear_solver.hpp"

#include <cholmod.h>
#include <dlfcn.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/assert.hpp"
#include "simulation/errors.hpp"

namespace {
std::atomic<long> g_serial_openmp_regions{0};
}  // namespace

/// OpenMP parallel regions on the calling thread, in place of libgomp's GOMP_parallel (the entry
/// point GCC compiles `#pragma omp parallel` to, ABI GOMP_4.0). Debian's CHOLMOD is built with
/// OpenMP, and cholmod_super_numeric opens several regions per supernode, each with an `if`
/// clause that is false for a sheet's small supernodes; libgomp still makes a team of one for
/// each and wakes its barrier with a futex system call at the end (strace: 1,043,388 futex calls
/// in 50 steps of a remeshed fall-cylinder run, all from these regions). papersim runs CHOLMOD on
/// one thread anyway (limit_openmp_threads below; its own parallelism is TBB), so here a region is
/// simply a call of its body: the same arithmetic in the same order, without the team. The
/// linker exports this definition from the executable because libcholmod refers to the symbol,
/// and the dynamic linker binds CHOLMOD's calls to it before libgomp's. Measured: the same
/// meshes to the bit at 0.67-0.90 of the CPU time by scenario (docs/performance.md,
/// "OpenMP regions as plain calls"). Work-sharing loops inside a region see one thread
/// (omp_get_num_threads() = 1 outside a team) and run whole.
extern "C" void GOMP_parallel(void (*fn)(void*), void* data, unsigned /*num_threads*/,
                              unsigned /*flags*/) {
  g_serial_openmp_regions.fetch_add(1, std::memory_order_relaxed);
  fn(data);
}

/// SuiteSparse's wall clock, in place of libsuitesparseconfig's. CHOLMOD's supernodal
/// factorisation reads the clock twice around every BLAS call it makes, for each update of a
/// supernode by a descendant, only to add the time to its statistics (Common's
/// CHOLMOD_CPU_GEMM_TIME, _SYRK_TIME, _POTRF_TIME, _TRSM_TIME), which papersim never reads. On a
/// virtual machine a clock read is not free: SuiteSparse_time and its clock_gettime were 1.8%
/// of pull seed 0's samples and 1.0% of the fold's (perf). Bound as GOMP_parallel above is;
/// CHOLMOD's only calls are these statistics, whose times now read 0.
extern "C" double SuiteSparse_time() { return 0.0; }

namespace papersim::simulation {

long serial_openmp_regions() { return g_serial_openmp_regions.load(std::memory_order_relaxed); }

std::string blas_kernels() {
  using CoreName = char* (*)();
  const auto corename = reinterpret_cast<CoreName>(dlsym(RTLD_DEFAULT, "openblas_get_corename"));
  const char* name = corename ? corename() : nullptr;
  return name ? std::string(name) : std::string();
}

namespace {

/// OpenBLAS picks its dense kernels by the CPU's model number; on a CPU it does not know (a
/// virtual machine's "Intel Xeon Processor" with AVX-512, measured) it falls back to its
/// Prescott (SSE3) kernels, which made CHOLMOD's supernodal factorisation, most of a Newton
/// iteration, up to 1.4 times slower (docs/performance.md, "BLAS kernels"). When OPENBLAS_CORETYPE
/// is not set and OpenBLAS chose a kernel set older than the CPU's instructions (the CPU and the OS
/// support AVX-512 or AVX2 with FMA), its dynamic dispatch is re-run with SkylakeX or Haswell
/// kernels, as OPENBLAS_CORETYPE would select them at start-up. Runs before the first BLAS call
/// of the process (the first solver). Symbols looked up at run time: any other BLAS links and
/// is left alone.
void select_blas_kernels() {
#if defined(__x86_64__) && defined(__GNUC__)
  if (std::getenv("OPENBLAS_CORETYPE")) return;
  using Dispatch = void (*)();
  const auto quit = reinterpret_cast<Dispatch>(dlsym(RTLD_DEFAULT, "gotoblas_dynamic_quit"));
  const auto init = reinterpret_cast<Dispatch>(dlsym(RTLD_DEFAULT, "gotoblas_dynamic_init"));
  std::string current = blas_kernels();
  if (!quit || !init || current.empty()) return;
  for (char& c : current) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  static const char* const older[] = {"prescott", "core2",      "penryn",     "dunnington",
                                      "nehalem",  "atom",       "banias",     "northwood",
                                      "katmai",   "coppermine", "sandybridge"};
  if (std::find(std::begin(older), std::end(older), current) == std::end(older)) return;
  __builtin_cpu_init();
  const char* wanted = nullptr;
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") &&
      __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") &&
      __builtin_cpu_supports("avx512vl"))
    wanted = "SkylakeX";
  else if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
    wanted = "Haswell";
  if (!wanted) return;
  setenv("OPENBLAS_CORETYPE", wanted, 1);
  quit();
  init();
  unsetenv("OPENBLAS_CORETYPE");
#endif
}

/// A multi-threaded BLAS (Debian's OpenBLAS pthreads build) spins its threads on the small
/// supernodes of a sheet and competes with TBB and with the other simulations of a batch: it
/// made factorisations slower and burned system time. One BLAS thread per solver; the symbol
/// is looked up at run time so any BLAS links.
void limit_blas_threads() {
  static std::once_flag once;
  std::call_once(once, [] {
    using SetThreads = void (*)(int);
    for (const char* name : {"openblas_set_num_threads", "goto_set_num_threads"})
      if (auto f = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, name))) {
        f(1);
        return;
      }
  });
}

/// Debian's CHOLMOD is built with OpenMP: cholmod_super_numeric opens parallel regions (with an
/// explicit thread count, so omp_set_num_threads does not apply) whose thread wake-ups cost more
/// than the small supernodes of a sheet gain (measured on fall-spheres seed 1, 682 vertices:
/// 37% of the samples in futex calls). Setting the maximum number of active parallel levels to
/// 0 makes every region run on the calling thread; nothing else in the process uses OpenMP
/// (papersim's own parallelism is TBB). Looked up at run time so a CHOLMOD without OpenMP links.
void limit_openmp_threads() {
  static std::once_flag once;
  std::call_once(once, [] {
    using SetLevels = void (*)(int);
    if (auto f = reinterpret_cast<SetLevels>(dlsym(RTLD_DEFAULT, "omp_set_max_active_levels")))
      f(0);
  });
}

}  // namespace

struct LinearSolver::Impl {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  long pattern_id = -1;
  int n = 0;
  Impl() {
    cholmod_start(&common);
    common.print = 0;  // library code stays silent; failures are returned or thrown
    common.error_handler = nullptr;
    // CHOLMOD picks supernodal (BLAS on dense blocks) when the fill is large, which the wide
    // bending stencil makes it; BLAS runs on one thread (see limit_blas_threads) (measured: see
    // docs/performance.md).
    static std::once_flag kernels;
    std::call_once(kernels, select_blas_kernels);
    limit_blas_threads();
    limit_openmp_threads();
    common.supernodal = CHOLMOD_AUTO;
    // A simplicial factorisation (CHOLMOD's choice for small systems, such as a coarsely
    // remeshed sheet) is LDL' by default, which succeeds on an indefinite matrix: factorize()
    // must fail there, so that Newton projects the Hessian instead of stepping uphill. LL'
    // stops at the first non-positive pivot in both the simplicial and supernodal methods.
    common.final_ll = true;
  }
  ~Impl() {
    if (factor) cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }
  /// A cholmod_sparse of A's structure (BlockSymmetricMatrix::structure_starts): the pattern
  /// for the analysis, and with `gathered` filled by gather() the matrix for a simplicial
  /// factorisation.
  std::vector<double> gathered;
  cholmod_sparse structure(const BlockSymmetricMatrix& A) {
    cholmod_sparse s{};
    s.nrow = s.ncol = A.size();
    s.nzmax = A.structure_rows().size();
    s.p = const_cast<int*>(A.structure_starts().data());
    s.i = const_cast<int*>(A.structure_rows().data());
    gathered.resize(s.nzmax);
    s.x = gathered.data();
    s.stype = 1;
    s.itype = CHOLMOD_INT;
    s.xtype = CHOLMOD_REAL;
    s.dtype = CHOLMOD_DOUBLE;
    s.sorted = 1;
    s.packed = 1;
    return s;
  }
  /// Returns false when a gathered value is NaN or infinite.
  bool gather(const BlockSymmetricMatrix& A) {
    const auto& at = A.structure_positions();
    const auto& x = A.values();
    bool finite = true;
    for (std::size_t k = 0; k < at.size(); ++k) {
      gathered[k] = x[at[k]];
      finite &= std::isfinite(gathered[k]);
    }
    return finite;
  }

  /// The supernodal factorisation takes the lower triangle of P A P' (P the analysis's
  /// fill-reducing permutation). cholmod_factorize makes it from our upper triangle by a
  /// permuted transpose at every call (5% of a fall's CPU time in the profile, with its
  /// allocations); its pattern only changes with A's, so it is built once per analysis and
  /// each factorisation only copies the values through a map. The values and their order in
  /// each column are the transpose's, so the factor is the same to the bit.
  std::vector<int> lower_p, lower_i, to_lower;
  std::vector<double> lower_x;

  void build_permuted_lower(const BlockSymmetricMatrix& A) {
    const int n = A.size();
    const int* perm = static_cast<const int*>(factor->Perm);
    std::vector<int> inverse(n);
    for (int k = 0; k < n; ++k) inverse[perm[k]] = k;
    const auto& Ap = A.structure_starts();
    const auto& Ai = A.structure_rows();
    const std::size_t nnz = Ai.size();
    // Entry k = (i, j), i <= j, lands in column min(P i, P j), row max(P i, P j).
    std::vector<int> column(nnz), row(nnz);
    lower_p.assign(n + 1, 0);
    for (int j = 0; j < n; ++j)
      for (int k = Ap[j]; k < Ap[j + 1]; ++k) {
        const int a = inverse[Ai[k]], b = inverse[j];
        column[k] = std::min(a, b);
        row[k] = std::max(a, b);
        ++lower_p[column[k] + 1];
      }
    for (int c = 0; c < n; ++c) lower_p[c + 1] += lower_p[c];
    std::vector<int> next(lower_p.begin(), lower_p.end() - 1), entry(nnz);
    for (std::size_t k = 0; k < nnz; ++k) entry[next[column[k]]++] = static_cast<int>(k);
    lower_i.resize(nnz);
    to_lower.resize(nnz);
    for (int c = 0; c < n; ++c) {
      const auto first = entry.begin() + lower_p[c], last = entry.begin() + lower_p[c + 1];
      std::sort(first, last, [&](int x, int y) { return row[x] < row[y]; });
      for (int q = lower_p[c]; q < lower_p[c + 1]; ++q) {
        lower_i[q] = row[entry[q]];
        to_lower[entry[q]] = q;
      }
    }
    lower_x.assign(nnz, 0.0);
  }

  /// Supernodal factorisation of A's values through the permuted lower triangle; false (and
  /// nothing factored) when a value is NaN or infinite.
  bool factor_permuted_lower(const BlockSymmetricMatrix& A) {
    const auto& x = A.values();
    const auto& at = A.structure_positions();
    bool finite = true;
    for (std::size_t k = 0; k < at.size(); ++k) {
      const double v = x[at[k]];
      lower_x[to_lower[k]] = v;
      finite &= std::isfinite(v);
    }
    if (!finite) return false;
    cholmod_sparse s{};
    s.nrow = s.ncol = A.size();
    s.nzmax = lower_x.size();
    s.p = lower_p.data();
    s.i = lower_i.data();
    s.x = lower_x.data();
    s.stype = -1;
    s.itype = CHOLMOD_INT;
    s.xtype = CHOLMOD_REAL;
    s.dtype = CHOLMOD_DOUBLE;
    s.sorted = 1;
    s.packed = 1;
    double beta[2] = {0, 0};
    cholmod_super_numeric(&s, nullptr, beta, factor, &common);
    return true;
  }
};

LinearSolver::LinearSolver(Trace trace)
    : m_impl(std::make_unique<Impl>()), m_trace(std::move(trace)) {}
LinearSolver::~LinearSolver() = default;

bool LinearSolver::factorize(const BlockSymmetricMatrix& A, long pattern_id) {
  const auto& values = A.values();
  const char* const non_finite = "linear solver: the matrix holds NaN or inf";
  for (int k : A.outside_positions()) {
    if (values[k] == 0.0) continue;
    if (!std::isfinite(values[k])) throw NumericError(non_finite);
    // A value outside the structure would be dropped from the factorisation without a sign.
    throw std::logic_error("linear solver: an energy term wrote outside its declared sparsity");
  }
  auto& c = m_impl->common;
  cholmod_sparse s = m_impl->structure(A);
  if (!m_impl->factor || pattern_id != m_impl->pattern_id || m_impl->n != A.size()) {
    if (m_impl->factor) cholmod_free_factor(&m_impl->factor, &c);
    m_impl->factor = cholmod_analyze(&s, &c);
    if (!m_impl->factor) throw NumericError("linear solver: CHOLMOD analysis failed");
    m_impl->pattern_id = pattern_id;
    m_impl->n = A.size();
    ++m_analyses;
    m_trace(Trace::solver, "analyse n %d nnz(A) %zu lnz %.0f flops %.3g ordering %d %s", A.size(),
            s.nzmax, c.lnz, c.fl, c.selected,
            m_impl->factor->is_super ? "supernodal" : "simplicial");
    if (m_impl->factor->is_super) m_impl->build_permuted_lower(A);
  }
  int ok = 1;
  if (m_impl->factor->is_super) {
    if (!m_impl->factor_permuted_lower(A)) throw NumericError(non_finite);
  } else {
    if (!m_impl->gather(A)) throw NumericError(non_finite);
    ok = cholmod_factorize(&s, m_impl->factor, &c);
  }
  if (c.status < CHOLMOD_OK) ok = 0;
  if (!ok && c.status != CHOLMOD_NOT_POSDEF)
    throw NumericError("linear solver: CHOLMOD factorisation failed, status " +
                       std::to_string(c.status));
  return c.status != CHOLMOD_NOT_POSDEF && m_impl->factor->minor == m_impl->factor->n;
}

double LinearSolver::factorize_shifted(BlockSymmetricMatrix& A, long pattern_id) {
  Eigen::VectorXd diagonal;
  double shift = 0;
  while (!factorize(A, pattern_id)) {
    if (shift == 0) diagonal = A.diagonal().cwiseAbs();
    const double next = shift == 0 ? 1e-10 : 10 * shift;
    A.add_diagonal((next - shift) * (Eigen::VectorXd::Ones(diagonal.size()) + 1e-3 * diagonal));
    shift = next;
    if (shift > 1e3) return -1;
  }
  return shift;
}

Eigen::VectorXd LinearSolver::solve(const Eigen::VectorXd& b) {
  PAPERSIM_ASSERT(m_impl->factor != nullptr && b.size() == m_impl->n,
                  "LinearSolver::solve: no factorisation, or b is not of its size");
  auto& c = m_impl->common;
  cholmod_dense rhs{};
  rhs.nrow = b.size();
  rhs.ncol = 1;
  rhs.nzmax = b.size();
  rhs.d = b.size();
  rhs.x = const_cast<double*>(b.data());
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  cholmod_dense* x = cholmod_solve(CHOLMOD_A, m_impl->factor, &rhs, &c);
  if (!x) throw NumericError("linear solver: CHOLMOD solve failed");
  Eigen::VectorXd out = Eigen::Map<Eigen::VectorXd>(static_cast<double*>(x->x), b.size());
  cholmod_free_dense(&x, &c);
  return out;
}

}  // namespace papersim::simulation
