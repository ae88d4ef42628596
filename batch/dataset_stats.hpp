#pragma once
/// `papersim dataset-stats DATASET`: what a dataset holds, read from its manifests and failure
/// files only (no mesh is opened): counts per scenario, failure rate by reason, run-time and
/// quality distributions, and histograms drawn with gnuplot.
#include <filesystem>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

namespace papersim::batch {

/// Distribution of one figure over samples.
struct Distribution {
  std::size_t count = 0;
  double min = 0, p10 = 0, median = 0, p90 = 0, max = 0, mean = 0, sum = 0;
};

/// min / quantiles / max / mean of `values` (quantiles by linear interpolation).
Distribution distribution(std::vector<double> values);

/// One part of a dataset (meshes or renders) as its manifest and failures file describe it.
struct PartStats {
  std::string name;                              ///< "meshes" or "renders"
  std::map<std::string, long long> done;         ///< finished samples per scenario
  std::map<std::string, long long> failed;       ///< samples whose latest state is failed, per scenario
  std::map<std::string, long long> reasons;      ///< those failures by reason
  long long failed_attempts = 0;                 ///< every failure row, retried ones included
  /// figure -> scenario -> values over finished samples (wall_seconds, max_stretch, ...)
  std::map<std::string, std::map<std::string, std::vector<double>>> values;
};

/// Read `manifest` and `failures` (JSON lines; missing files are empty). A key with a manifest
/// row counts as done even when it also failed earlier; duplicate rows count once.
PartStats read_part(const std::string& name, const std::filesystem::path& manifest,
                    const std::filesystem::path& failures, const std::vector<std::string>& figures);

/// The meshes (manifest.jsonl, failures.jsonl) and renders (renders.jsonl,
/// renders_failures.jsonl) of a dataset; a part with no file at all is left out.
/// @throw std::runtime_error when `root` is not a folder
std::vector<PartStats> read_dataset(const std::filesystem::path& root);

/// The report as text tables.
void write_dataset_report(std::ostream& out, const std::vector<PartStats>& parts);

/// Histograms per figure (one series per scenario) as SVG files in `dir` via gnuplot, with
/// their data (.dat) and the gnuplot script (stats.gp); returns the SVG files written. All are
/// made in a staging folder and moved into `dir` only when every one is whole, so a failure
/// leaves `dir` as it was.
/// @throw std::runtime_error when the folder cannot be written or gnuplot fails
std::vector<std::string> write_dataset_plots(const std::filesystem::path& dir,
                                             const std::vector<PartStats>& parts, int bins = 30);

}  // namespace papersim::batch
