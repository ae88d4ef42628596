#pragma once
/// What a run tells about its inner workings, by topic, when asked (`papersim run --trace
/// newton,remesh`): each line goes to a writer, stderr unless another is given. A Trace is a
/// value handed to the parts of a run with their parameters (NewtonParams, ContactParams,
/// SelfContactParams, Run), never read from the environment: off, it costs one test of a bit.
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace papersim::simulation {

class Trace {
 public:
  enum Topic : unsigned {
    newton = 1u << 0,       ///< each Newton iteration: energy, residual, decrement, step, failures
    model = 1u << 1,        ///< each term's change along a Newton step against its quadratic model
    line_search = 1u << 2,  ///< each term's change along a step the line search cut below 1e-9
    inf = 1u << 3,          ///< the term whose energy is infinite at a trial point
    solver = 1u << 4,       ///< Hessian patterns and CHOLMOD's symbolic analyses
    contact = 1u << 5,      ///< obstacle and self-contact stiffness and friction per step
    intersect = 1u << 6,    ///< triangle pairs a step allowed by the self-contact CCD makes cross
    lift = 1u << 7,         ///< loads and rises of obstacles that yield upwards
    remesh = 1u << 8,       ///< each remeshing pass: edits, vertices, energy jump, undone passes
  };
  using Writer = std::function<void(const std::string& line)>;

  Trace() = default;  ///< off
  /// `topics`: a set of Topic bits; `write` gets each line without its newline (null: stderr).
  explicit Trace(unsigned topics, Writer write = {})
      : m_topics(topics), m_write(std::move(write)) {}

  bool on(Topic t) const { return (m_topics & t) != 0; }
  unsigned topics() const { return m_topics; }
  /// A printf-formatted line on topic `t` (nothing when it is off).
  void operator()(Topic t, const char* format, ...) const __attribute__((format(printf, 3, 4)));
  /// A whole line on topic `t` (nothing when it is off).
  void line(Topic t, const std::string& text) const;

  /// The topics' names, as `--trace` takes them.
  static const std::vector<std::pair<std::string, Topic>>& names();
  /// Topics from a comma list of names, or "all".
  /// @throw std::invalid_argument naming an unknown topic and listing the known ones
  static unsigned parse(const std::string& list);

 private:
  unsigned m_topics = 0;
  Writer m_write;
};

}  // namespace papersim::simulation
