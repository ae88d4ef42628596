#pragma once
/// Histograms of per-element metrics drawn by gnuplot (Debian's gnuplot-nox) as SVG files.
/// Only called when the user asks for plots: it starts an external program.
#include <stdexcept>
#include <string>
#include <vector>

#include "validation/metrics.hpp"

namespace papersim::validation {

/// Plotting failed: the folder cannot be written or gnuplot is missing or reported an error.
struct PlotError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Options of write_histogram_plots.
struct PlotOptions {
  int bins = 40;                    ///< bins per histogram (>= 1)
  std::string gnuplot = "gnuplot";  ///< the gnuplot program (looked up in PATH)
  std::string title_suffix;         ///< appended to every title (e.g. "(1000 meshes)")
};

/// Write, in `dir` (created if missing), one histogram per quantity that has samples:
/// edge_strain.svg (l / L - 1), principal_stretch.svg (s1 and s2), angle_defect.svg (interior
/// K_i [rad]) and crease_length.svg (crease line lengths [m], logarithmic bins), together with
/// their .dat tables and the gnuplot script histograms.gp, then run gnuplot once.
/// @return the SVG files written
/// @throw PlotError when the folder cannot be created or gnuplot fails, common::OutputError when
///        a file cannot be written (an SVG is renamed into place only when complete).
std::vector<std::string> write_histogram_plots(const std::string& dir,
                                               const MetricsSamples& samples,
                                               const PlotOptions& options = {});

}  // namespace papersim::validation
