#include "validation/metrics_plots.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <sstream>

#include "common/atomic_file.hpp"

namespace papersim::validation {
namespace {

namespace fs = std::filesystem;

/// Bin edges lo[k], hi[k] and counts of one or more series over common bins.
struct Histogram {
  std::vector<double> lo, hi;
  std::vector<std::vector<long>> counts;  ///< per series
};

Histogram make_histogram(const std::vector<const std::vector<double>*>& series, int bins,
                         bool logarithmic) {
  double min = HUGE_VAL, max = -HUGE_VAL;
  for (const auto* values : series)
    for (double v : *values) {
      if (logarithmic && !(v > 0.0)) continue;
      min = std::min(min, logarithmic ? std::log10(v) : v);
      max = std::max(max, logarithmic ? std::log10(v) : v);
    }
  if (!(max > min)) {  // one value (or none): a bin around it
    const double pad = std::max(1e-12, 0.5 * std::abs(min == HUGE_VAL ? 0.0 : min));
    min = (min == HUGE_VAL ? 0.0 : min) - pad;
    max = min + 2.0 * pad;
  }
  Histogram h;
  const double step = (max - min) / bins;
  for (int k = 0; k < bins; ++k) {
    const double a = min + k * step, b = min + (k + 1) * step;
    h.lo.push_back(logarithmic ? std::pow(10.0, a) : a);
    h.hi.push_back(logarithmic ? std::pow(10.0, b) : b);
  }
  for (const auto* values : series) {
    std::vector<long> counts(static_cast<std::size_t>(bins), 0);
    for (double v : *values) {
      if (logarithmic && !(v > 0.0)) continue;
      const double x = logarithmic ? std::log10(v) : v;
      const int k = std::clamp(static_cast<int>((x - min) / step), 0, bins - 1);
      ++counts[static_cast<std::size_t>(k)];
    }
    h.counts.push_back(counts);
  }
  return h;
}

void write_dat(const fs::path& path, const Histogram& h) {
  common::write_file_atomically(path, [&](std::ostream& out) {
    out << std::setprecision(10) << "# lo hi count...\n";
    for (std::size_t k = 0; k < h.lo.size(); ++k) {
      out << h.lo[k] << ' ' << h.hi[k];
      for (const auto& counts : h.counts) out << ' ' << counts[k];
      out << '\n';
    }
  });
}

/// True when `path` holds a whole SVG document (gnuplot may exit 0 after a failed write).
bool complete_svg(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto end = text.find_last_not_of(" \n\r\t");
  return end != std::string::npos && end >= 5 && text.compare(end - 5, 6, "</svg>") == 0;
}

/// gnuplot single-quoted string ('' stands for ').
std::string quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

/// POSIX shell single-quoted string.
std::string shell_quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

/// One plot of the script: boxes from lo to hi and 0 to count, one per series.
void write_plot(std::ostream& gp, const std::string& name, const std::string& title,
                const std::string& xlabel, const std::vector<std::string>& series_titles,
                bool logarithmic) {
  gp << "set output " << quoted(name + ".svg.tmp") << "\n"
     << "set title " << quoted(title) << "\nset xlabel " << quoted(xlabel) << "\n"
     << (logarithmic ? "set logscale x\n" : "unset logscale x\n") << "plot ";
  for (std::size_t s = 0; s < series_titles.size(); ++s)
    gp << (s ? ", " : "") << quoted(name + ".dat") << " using (($1+$2)/2):" << s + 3
       << ":1:2:(0):" << s + 3 << " with boxxyerror title " << quoted(series_titles[s]);
  gp << "\n";
}

struct PlotSpec {
  std::string name, title, xlabel;
  std::vector<const std::vector<double>*> series;
  std::vector<std::string> series_titles;
  bool logarithmic = false;
};

std::vector<PlotSpec> plot_specs(const MetricsSamples& s, const std::string& suffix) {
  return {
      {"edge_strain", "Edge strain " + suffix, "l / L - 1", {&s.edge_strain}, {"edges"}, false},
      {"principal_stretch",
       "Principal stretches " + suffix,
       "stretch",
       {&s.s1, &s.s2},
       {"s1", "s2"},
       false},
      {"angle_defect",
       "Angle defect at interior vertices " + suffix,
       "K [rad]",
       {&s.angle_defect},
       {"vertices"},
       false},
      {"crease_length",
       "Crease line lengths " + suffix,
       "length [m]",
       {&s.crease_length},
       {"lines"},
       true},
  };
}

}  // namespace

std::vector<std::string> write_histogram_plots(const std::string& dir,
                                               const MetricsSamples& samples,
                                               const PlotOptions& options) {
  if (options.bins < 1) throw PlotError("plots: bins must be >= 1");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw common::OutputError("plots: cannot create " + dir + ": " + ec.message());
  const fs::path folder(dir);
  std::ostringstream gp;
  gp << "set terminal svg size 800,500 dynamic\nset style fill solid 0.5 border -1\n"
     << "set ylabel 'count'\nset grid\n";
  std::vector<std::string> written;
  for (const PlotSpec& spec : plot_specs(samples, options.title_suffix)) {
    if (spec.series.front()->empty()) continue;
    write_dat(folder / (spec.name + ".dat"),
              make_histogram(spec.series, options.bins, spec.logarithmic));
    write_plot(gp, spec.name, spec.title, spec.xlabel, spec.series_titles, spec.logarithmic);
    written.push_back((folder / (spec.name + ".svg")).string());
  }
  const fs::path script = folder / "histograms.gp";
  common::write_text_atomically(script, gp.str());
  // gnuplot resolves file names against its working directory: run it inside the folder.
  const std::string command = "cd " + shell_quoted(folder.string()) + " && " + options.gnuplot +
                              " histograms.gp 2> gnuplot.log";
  const int status = std::system(command.c_str());
  // gnuplot writes NAME.svg.tmp; only whole files are renamed to NAME.svg.
  std::string incomplete;
  for (const std::string& svg : written)
    if (incomplete.empty() && !complete_svg(svg + ".tmp")) incomplete = svg;
  if (status != 0 || !incomplete.empty()) {
    for (const std::string& svg : written) fs::remove(svg + ".tmp", ec);
    if (status != 0)
      throw PlotError("plots: gnuplot failed; see " + (folder / "gnuplot.log").string());
    throw common::OutputError("plots: cannot write '" + incomplete +
                              "' (incomplete SVG; full disk?)");
  }
  for (const std::string& svg : written) {
    fs::rename(svg + ".tmp", svg, ec);
    if (ec) throw common::OutputError("plots: cannot rename '" + svg + ".tmp': " + ec.message());
  }
  return written;
}

}  // namespace papersim::validation
