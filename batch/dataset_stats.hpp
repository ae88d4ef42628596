#pragma once
/// `papersim dataset-stats DATASET`: what a dataset holds, read from its manifests and failure
/// files only (no mesh is opened): counts per scenario, failure rate by reason, run-time and
/// quality distributions, and histograms drawn with gnuplot.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <iosfwd>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "batch/errors.hpp"

namespace papersim::batch {

/// The plots' folder or one of their files cannot be written (full disk, permission, a file in
/// the way). Exit status 5.
struct PlotsOutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// gnuplot is missing or failed. Exit status 6.
struct GnuplotError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Distribution of one figure over samples.
struct Distribution {
  std::size_t count = 0;
  double min = 0, p10 = 0, median = 0, p90 = 0, max = 0, mean = 0, sum = 0;
};

/// min / quantiles / max / mean of `values` (quantiles by linear interpolation).
Distribution distribution(std::vector<double> values);

/// One figure's values over the samples of a scenario, in the order read. They are kept in
/// blocks of fixed size, so that millions of them grow with no copy and no slack, and copied
/// into one vector only where a distribution is computed, one figure at a time.
class FigureValues {
 public:
  FigureValues() = default;
  FigureValues(std::initializer_list<double> values);
  void push_back(double v);
  std::size_t size() const { return m_size; }
  bool empty() const { return m_size == 0; }
  /// Call `f(v)` on each value in order.
  template <class F>
  void for_each(F f) const {
    for (const auto& block : m_blocks)
      for (double v : block) f(v);
  }
  std::vector<double> to_vector() const;
  bool operator==(const FigureValues& other) const { return to_vector() == other.to_vector(); }

 private:
  static constexpr std::size_t kBlock = 8192;
  std::vector<std::vector<double>> m_blocks;  ///< each reserved to kBlock values
  std::size_t m_size = 0;
};

/// One part of a dataset (meshes or renders) as its manifest and failures file describe it.
struct PartStats {
  std::string name;                          ///< "meshes" or "renders"
  std::map<std::string, long long> done;     ///< finished samples per scenario
  std::map<std::string, long long> failed;   ///< samples whose latest state is failed, per scenario
  std::map<std::string, long long> reasons;  ///< those failures by reason
  long long failed_attempts = 0;             ///< every failure row, retried ones included
  /// Lines of the two files that are not a JSON object with a string "key" (and a string
  /// "scenario" and "reason" where present), left out and counted: a line cut short by a
  /// killed writer, or a file edited by hand.
  long long skipped_lines = 0;
  /// figure -> scenario -> values over finished samples (wall_seconds, max_stretch, ...)
  std::map<std::string, std::map<std::string, FigureValues>> values;
};

/// Told the bytes read so far of the files read_dataset reads, and their total size, every few
/// thousand rows.
using ReadProgress = std::function<void(std::uintmax_t read, std::uintmax_t total)>;

/// Read `manifest` and `failures` (JSON lines; missing files are empty) one row at a time. A key
/// with a manifest row counts as done even when it also failed earlier; duplicate rows count
/// once. `progress` is told the bytes read, counted from `read_before` of `total`.
PartStats read_part(const std::string& name, const std::filesystem::path& manifest,
                    const std::filesystem::path& failures, const std::vector<std::string>& figures,
                    const ReadProgress& progress = {}, std::uintmax_t read_before = 0,
                    std::uintmax_t total = 0);

/// The meshes (manifest.jsonl, failures.jsonl) and renders (renders.jsonl,
/// renders_failures.jsonl) of a dataset; a part with no file at all is left out.
/// @throw DatasetError when `root` is not a folder
std::vector<PartStats> read_dataset(const std::filesystem::path& root,
                                    const ReadProgress& progress = {});

/// The report as text tables.
void write_dataset_report(std::ostream& out, const std::vector<PartStats>& parts);

/// Histograms per figure (one series per scenario) as SVG files in `dir` via gnuplot, with
/// their data (.dat) and the gnuplot script (stats.gp); returns the SVG files written. All are
/// made in a staging folder and moved into `dir` only when every one is whole, so a failure
/// leaves `dir` as it was.
/// @throw PlotsOutputError when the folder or a file cannot be written; GnuplotError when
/// gnuplot is missing or fails
std::vector<std::string> write_dataset_plots(const std::filesystem::path& dir,
                                             const std::vector<PartStats>& parts, int bins = 30);

}  // namespace papersim::batch
