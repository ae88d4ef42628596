#include "batch/dataset_stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <ostream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "batch/key_set.hpp"
#include "batch/row_fields.hpp"
#include "batch/runner.hpp"
#include "batch/slurm.hpp"

namespace papersim::batch {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const std::vector<std::string> MESH_FIGURES = {
    "wall_seconds",       "cpu_seconds",   "vertices",
    "newton_iterations",  "max_stretch",   "closest_obstacle_distance",
    "self_intersections", "crease_length", "abs_curvature_integral"};
const std::vector<std::string> RENDER_FIGURES = {"wall_seconds", "cpu_seconds"};

/// Bytes read of the files of a dataset, told to a ReadProgress every 4,096 lines.
struct ReadCount {
  const ReadProgress& progress;
  std::uintmax_t read, total;
};

/// Call `row` with the fields of each well-formed row of a JSON-lines file (none when it is
/// missing), one row at a time; `skipped` counts the other non-empty lines.
/// @throw DatasetError when `path` exists but is not a regular file or cannot be read
template <class F>
void for_each_row(const fs::path& path, const std::vector<std::string>& figures, long long& skipped,
                  ReadCount& count, F row) {
  std::error_code ec;
  const fs::file_type type = fs::status(path, ec).type();
  if (type == fs::file_type::not_found) return;
  if (type != fs::file_type::regular) throw DatasetError("'" + path.string() + "' is not a file");
  std::ifstream in(path);
  if (!in) throw DatasetError("cannot open '" + path.string() + "'");
  std::string line;
  RowFields fields(figures);
  for (std::size_t lines = 1; std::getline(in, line); ++lines) {
    count.read += line.size() + 1;
    if (count.progress && lines % 4096 == 0)
      count.progress(std::min(count.read, count.total), count.total);
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (fields.read(line))
      row(fields);
    else
      ++skipped;
  }
  if (in.bad()) throw DatasetError("cannot read '" + path.string() + "'");
}

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

void write_counts(std::ostream& out, const PartStats& p) {
  std::set<std::string> names;
  for (const auto& [s, n] : p.done) names.insert(s);
  for (const auto& [s, n] : p.failed) names.insert(s);
  out << p.name << ": samples per scenario\n";
  char line[256];
  std::snprintf(line, sizeof line, "  %-16s %10s %10s %12s\n", "scenario", "done", "failed",
                "failure rate");
  out << line;
  long long td = 0, tf = 0;
  for (const auto& s : names) {
    const long long d = p.done.count(s) ? p.done.at(s) : 0,
                    f = p.failed.count(s) ? p.failed.at(s) : 0;
    td += d;
    tf += f;
    std::snprintf(line, sizeof line, "  %-16s %10lld %10lld %11.1f%%\n", s.c_str(), d, f,
                  d + f > 0 ? 100.0 * static_cast<double>(f) / static_cast<double>(d + f) : 0.0);
    out << line;
  }
  std::snprintf(line, sizeof line, "  %-16s %10lld %10lld %11.1f%%\n", "all", td, tf,
                td + tf > 0 ? 100.0 * static_cast<double>(tf) / static_cast<double>(td + tf) : 0.0);
  out << line;
  if (p.skipped_lines > 0)
    out << p.name << ": " << p.skipped_lines
        << " lines left out: not a JSON object with a string key (cut short, or edited by hand)\n";
  if (!p.reasons.empty()) {
    out << p.name << ": failures by reason (" << p.failed_attempts << " failed attempts in all)\n";
    for (const auto& [r, n] : p.reasons) {
      std::snprintf(line, sizeof line, "  %-40s %8lld  %5.1f%% of samples\n", r.c_str(), n,
                    100.0 * static_cast<double>(n) / static_cast<double>(td + tf));
      out << line;
    }
  }
}

void write_distributions(std::ostream& out, const PartStats& p) {
  char line[256];
  for (const auto& [figure, per] : p.values) {
    out << p.name << ": " << figure << "\n";
    std::snprintf(line, sizeof line, "  %-16s %7s %10s %10s %10s %10s %10s %10s\n", "scenario", "n",
                  "min", "p10", "median", "p90", "max", "mean");
    out << line;
    std::map<std::string, Distribution> dists;
    for (const auto& [s, v] : per) {
      const Distribution d = dists[s] = distribution(v.to_vector());
      std::snprintf(line, sizeof line, "  %-16s %7zu %10s %10s %10s %10s %10s %10s\n", s.c_str(),
                    d.count, fmt(d.min).c_str(), fmt(d.p10).c_str(), fmt(d.median).c_str(),
                    fmt(d.p90).c_str(), fmt(d.max).c_str(), fmt(d.mean).c_str());
      out << line;
    }
    if (figure == "wall_seconds" || figure == "cpu_seconds") {
      double total = 0;
      for (const auto& [s, d] : dists) {
        total += d.sum;
        out << "  " << s << ": " << fmt(3600.0 / d.mean) << " samples per core-hour\n";
      }
      out << "  total " << fmt(total / 3600.0) << " core-hours"
          << (figure == "wall_seconds" ? " (one sample per core)\n" : " of CPU time\n");
    }
  }
}

std::string gp_quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

/// Write `text` to `path`, flushed, closed and checked. @throw PlotsOutputError naming the file
void write_checked(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw PlotsOutputError("cannot write '" + path.string() + "'");
}

/// Whether `path` is a whole SVG file (gnuplot closes it with </svg>).
bool whole_svg(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  const std::string text = s.str();
  const auto end = text.find_last_not_of(" \n");
  return end != std::string::npos && end >= 5 && text.compare(end - 5, 6, "</svg>") == 0;
}

/// One histogram file: bin centre, then one count column per scenario.
std::string write_histogram(const fs::path& dat, const std::map<std::string, FigureValues>& per,
                            int bins) {
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& [s, v] : per)
    v.for_each([&](double x) { lo = std::min(lo, x), hi = std::max(hi, x); });
  if (!(hi > lo)) hi = lo + 1;
  const double w = (hi - lo) / bins;
  std::vector<std::vector<long long>> counts(
      per.size(), std::vector<long long>(static_cast<std::size_t>(bins), 0));
  std::size_t k = 0;
  for (const auto& [s, v] : per) {
    v.for_each([&](double x) {
      ++counts[k][std::min(static_cast<std::size_t>(bins - 1),
                           static_cast<std::size_t>((x - lo) / w))];
    });
    ++k;
  }
  std::ostringstream text;
  for (int b = 0; b < bins; ++b) {
    text << lo + (b + 0.5) * w;
    for (const auto& c : counts) text << ' ' << c[static_cast<std::size_t>(b)];
    text << '\n';
  }
  write_checked(dat, text.str());
  return fmt(w);
}

}  // namespace

FigureValues::FigureValues(std::initializer_list<double> values) {
  for (double v : values) push_back(v);
}

void FigureValues::push_back(double v) {
  if (m_blocks.empty() || m_blocks.back().size() == kBlock) {
    m_blocks.emplace_back();
    m_blocks.back().reserve(kBlock);
  }
  m_blocks.back().push_back(v);
  ++m_size;
}

std::vector<double> FigureValues::to_vector() const {
  std::vector<double> v;
  v.reserve(m_size);
  for (const auto& block : m_blocks) v.insert(v.end(), block.begin(), block.end());
  return v;
}

Distribution distribution(std::vector<double> v) {
  Distribution d;
  if (v.empty()) return d;
  d.count = v.size();
  for (double x : v) d.sum += x;  // in the order read
  d.mean = d.sum / static_cast<double>(v.size());
  // The order statistics the quantiles interpolate between, selected rather than sorted (a sort
  // of ten million values took a fifth of a dataset's statistics, perf): in increasing order,
  // each found in the part not yet placed, which the one before left holding the larger values.
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  d.min = *lo;
  d.max = *hi;
  std::size_t placed = 0;  // v[0, placed) holds the smallest values, up to the last found
  const auto order = [&v, &placed](std::size_t k) {
    if (k >= placed) {
      std::nth_element(v.begin() + static_cast<std::ptrdiff_t>(placed),
                       v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
      placed = k + 1;
    }
    return v[k];
  };
  const auto quantile_of = [&](double q) {
    const double pos = q * static_cast<double>(v.size() - 1);
    const auto i = static_cast<std::size_t>(std::floor(pos));
    const std::size_t j = std::min(i + 1, v.size() - 1);
    const double a = order(i);
    return a + (pos - static_cast<double>(i)) * (order(j) - a);
  };
  d.p10 = quantile_of(0.1);
  d.median = quantile_of(0.5);
  d.p90 = quantile_of(0.9);
  return d;
}

PartStats read_part(const std::string& name, const fs::path& manifest, const fs::path& failures,
                    const std::vector<std::string>& figures, const ReadProgress& progress,
                    std::uintmax_t read_before, std::uintmax_t total) {
  ReadCount count{progress, read_before, total};
  PartStats p;
  p.name = name;
  // Rows are read one at a time and only what the report needs is kept: the done keys, compactly
  // (KeySet), and the figures, in fixed blocks (FigureValues) (ten million rows: docs/batch.md,
  // "Statistics").
  KeySet done_keys;
  std::map<std::string, std::vector<FigureValues*>> per_scenario;  // scenario -> per figure
  for_each_row(manifest, figures, p.skipped_lines, count, [&](const RowFields& row) {
    if (!done_keys.insert(row.key())) return;
    const std::string s = row.scenario();
    ++p.done[s];
    auto [it, added] = per_scenario.try_emplace(s);
    if (added)
      for (const auto& f : figures) it->second.push_back(&p.values[f][s]);
    for (std::size_t i = 0; i < figures.size(); ++i)
      if (!std::isnan(row.value(i))) it->second[i]->push_back(row.value(i));
  });
  // A figure no row of a scenario gives is left out.
  for (auto& [figure, per] : p.values) {
    for (auto it = per.begin(); it != per.end();)
      it = it->second.empty() ? per.erase(it) : std::next(it);
  }
  for (auto it = p.values.begin(); it != p.values.end();)
    it = it->second.empty() ? p.values.erase(it) : std::next(it);
  std::map<std::string, std::pair<std::string, std::string>>
      latest_failure;  // key -> scenario, reason
  for_each_row(failures, {}, p.skipped_lines, count, [&](const RowFields& row) {
    ++p.failed_attempts;
    latest_failure[row.key()] = {row.scenario(), row.reason()};
  });
  for (const auto& [key, failure] : latest_failure) {
    if (done_keys.contains(key)) continue;
    ++p.failed[failure.first];
    ++p.reasons[failure.second];
  }
  return p;
}

std::vector<PartStats> read_dataset(const fs::path& root, const ReadProgress& progress) {
  if (!fs::is_directory(root)) throw DatasetError("'" + root.string() + "' is not a folder");
  const auto size = [](const fs::path& file) {
    std::error_code ec;
    const auto n = fs::file_size(file, ec);
    return ec ? std::uintmax_t{0} : n;
  };
  std::uintmax_t total = 0, read = 0;
  for (const char* f :
       {"manifest.jsonl", "failures.jsonl", "renders.jsonl", "renders_failures.jsonl"})
    total += size(root / f);
  std::vector<PartStats> parts;
  const auto add = [&](const std::string& name, const char* manifest, const char* failures,
                       const std::vector<std::string>& figures) {
    if (fs::exists(root / manifest) || fs::exists(root / failures))
      parts.push_back(
          read_part(name, root / manifest, root / failures, figures, progress, read, total));
    read += size(root / manifest) + size(root / failures);
  };
  add("meshes", "manifest.jsonl", "failures.jsonl", MESH_FIGURES);
  add("renders", "renders.jsonl", "renders_failures.jsonl", RENDER_FIGURES);
  return parts;
}

void write_dataset_report(std::ostream& out, const std::vector<PartStats>& parts) {
  if (parts.empty()) out << "no manifest or failures file: nothing has run in this dataset yet\n";
  for (const auto& p : parts) {
    write_counts(out, p);
    write_distributions(out, p);
  }
}

std::vector<std::string> write_dataset_plots(const fs::path& dir,
                                             const std::vector<PartStats>& parts, int bins) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw PlotsOutputError("cannot create '" + dir.string() + "': " + ec.message());
  // Every file is made in a staging folder inside `dir` and moved into `dir` only once all of
  // them are whole: a failure (full disk, gnuplot missing or failing) leaves `dir` as it was.
  const fs::path stage = dir / ".dataset-stats-partial";
  fs::remove_all(stage, ec);
  fs::create_directories(stage, ec);
  if (ec) throw PlotsOutputError("cannot create '" + stage.string() + "': " + ec.message());
  std::vector<std::string> written, names;
  try {
    std::ostringstream gp;
    gp << "set terminal svg size 800,500 dynamic\nset style fill transparent solid 0.4 border -1\n"
       << "set ylabel 'samples'\nset grid\nset key top right\n";
    for (const auto& p : parts) {
      for (const auto& [figure, per] : p.values) {
        const std::string name = p.name + "_" + figure;
        const std::string width = write_histogram(stage / (name + ".dat"), per, bins);
        gp << "set output " << gp_quoted(name + ".svg") << "\nset title "
           << gp_quoted(p.name + ": " + figure) << "\nset xlabel " << gp_quoted(figure)
           << "\nset boxwidth " << width << "\nplot ";
        int col = 2;
        for (const auto& [s, v] : per) {
          gp << (col > 2 ? ", " : "") << gp_quoted(name + ".dat") << " using 1:" << col
             << " with boxes title " << gp_quoted(s);
          ++col;
        }
        gp << "\n";
        names.push_back(name);
      }
    }
    if (!names.empty()) {
      write_checked(stage / "stats.gp", gp.str());
      const std::string command =
          "cd " + shell_quote(stage.string()) + " && gnuplot stats.gp 2> gnuplot.log";
      if (std::system(command.c_str()) != 0) {
        std::ifstream log(stage / "gnuplot.log");
        std::stringstream text;
        text << log.rdbuf();
        std::string log_text = text.str();
        if (log_text.size() > 600) log_text = "..." + log_text.substr(log_text.size() - 600);
        throw GnuplotError("gnuplot failed: " + log_text);
      }
      for (const auto& name : names)
        if (!whole_svg(stage / (name + ".svg")))
          throw PlotsOutputError("gnuplot did not write '" + (dir / (name + ".svg")).string() +
                                 "' whole (a full disk?)");
      for (const auto& name : names)
        for (const char* ext : {".dat", ".svg"}) {
          fs::rename(stage / (name + ext), dir / (name + ext), ec);
          if (ec)
            throw PlotsOutputError("cannot write '" + (dir / (name + ext)).string() +
                                   "': " + ec.message());
        }
      fs::rename(stage / "stats.gp", dir / "stats.gp", ec);
      if (ec)
        throw PlotsOutputError("cannot write '" + (dir / "stats.gp").string() +
                               "': " + ec.message());
      for (const auto& name : names) written.push_back((dir / (name + ".svg")).string());
    }
  } catch (...) {
    fs::remove_all(stage, ec);
    throw;
  }
  fs::remove_all(stage, ec);
  return written;
}

}  // namespace papersim::batch
