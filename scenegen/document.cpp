#include "scenegen/document.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "scenegen/errors.hpp"
#include "scenegen/random.hpp"

namespace papersim::scenegen {
namespace {

const char* const WORDS[] = {
    "paper",    "sheet",    "model",       "energy",     "bending",    "surface",  "contact",
    "method",   "results",  "data",        "image",      "the",        "of",       "and",
    "a",        "in",       "to",          "is",         "for",        "with",     "on",
    "that",     "by",       "we",          "this",       "are",        "from",     "which",
    "be",       "as",       "an",          "at",         "or",         "each",     "our",
    "analysis", "measured", "stiffness",   "friction",   "simulation", "mesh",     "figure",
    "table",    "error",    "samples",     "render",     "camera",     "light",    "material",
    "document", "crease",   "deformation", "strain",     "curvature",  "solver",   "step",
    "time",     "section",  "value",       "experiment", "dataset",    "training", "network",
    "geometry", "texture",  "shows",       "given",      "between",    "under",    "across",
    "after",    "before",   "small",       "large",      "mean",       "total",    "observed",
    "reported", "proposed", "compared",    "linear",     "stable",     "fold",     "grid",
    "quality",  "distance", "normal",      "point",      "smooth",     "robust",   "exact",
    "random",   "field"};
constexpr int N_WORDS = sizeof(WORDS) / sizeof(WORDS[0]);

struct Fonts {
  std::string body, bold, heading;
};

std::string word(Rng& rng) { return WORDS[rng.randint(0, N_WORDS - 1)]; }

std::string capitalised(std::string s) {
  if (!s.empty() && s[0] >= 'a' && s[0] <= 'z') s[0] = static_cast<char>(s[0] - 'a' + 'A');
  return s;
}

/// Approximate advance of a string (the POV-Ray scene measures and corrects it) [mm].
double text_width(const std::string& s, double size) { return 0.53 * size * s.size(); }

class Flow {
 public:
  Flow(DocumentLayout& doc, double top, double bottom, double left, double col_w, double gap)
      : m_doc(doc),
        m_top(top),
        m_bottom(bottom),
        m_left(left),
        m_col_w(col_w),
        m_gap(gap),
        m_y(top) {}
  double x() const { return m_left + m_col * (m_col_w + m_gap); }
  double width() const { return m_col_w; }
  /// Reserve `h` mm; false when the page is full.
  bool reserve(double h) {
    if (m_y + h <= m_bottom) return true;
    if (m_col + 1 >= m_doc.columns) return false;
    ++m_col;
    m_y = m_top;
    return m_y + h <= m_bottom;
  }
  double y() const { return m_y; }
  void advance(double h) { m_y += h; }

 private:
  DocumentLayout& m_doc;
  double m_top, m_bottom, m_left, m_col_w, m_gap, m_y;
  int m_col = 0;
};

bool paragraph(Rng& rng, DocumentLayout& doc, Flow& flow, const Fonts& f, double size) {
  const double lead = 1.4 * size;
  const int n_words = rng.randint(25, 90);
  std::vector<std::string> lines(1);
  for (int i = 0; i < n_words; ++i) {
    std::string w = word(rng);
    if (i == 0) w = capitalised(w);
    if (i + 1 == n_words)
      w += ".";
    else if (rng.uniform() < 0.08)
      w += ",";
    const std::string candidate = lines.back().empty() ? w : lines.back() + " " + w;
    if (text_width(candidate, size) > flow.width() && !lines.back().empty())
      lines.push_back(w);
    else
      lines.back() = candidate;
  }
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (!flow.reserve(lead)) return false;
    TextLine t{f.body, lines[i], flow.x(), flow.y() + size, size, 0.0, flow.width(), false};
    if (i + 1 < lines.size()) t.justify_width = flow.width();
    doc.lines.push_back(t);
    flow.advance(lead);
  }
  ++doc.paragraphs;
  flow.advance(0.6 * size);
  return true;
}

bool heading(Rng& rng, DocumentLayout& doc, Flow& flow, const Fonts& f, int number) {
  const double size = 4.6;
  if (!flow.reserve(2.2 * size)) return false;
  std::string text = std::to_string(number) + "  " + capitalised(word(rng));
  for (int i = rng.randint(1, 3); i > 0; --i) text += " " + word(rng);
  doc.lines.push_back(
      {f.heading, text, flow.x(), flow.y() + 1.4 * size, size, 0, flow.width(), false});
  flow.advance(2.0 * size);
  ++doc.headings;
  return true;
}

bool table(Rng& rng, DocumentLayout& doc, Flow& flow, const Fonts& f, double size) {
  const int rows = rng.randint(3, 6), cols = rng.randint(3, 5);
  const double row_h = 1.6 * size, h = (rows + 1) * row_h + 3 * size;
  if (!flow.reserve(h)) return false;
  const double x0 = flow.x(), w = flow.width(), cw = w / cols;
  double y = flow.y();
  doc.lines.push_back({f.bold,
                       "Table 1: " + capitalised(word(rng)) + " " + word(rng) + " " + word(rng), x0,
                       y + size, size, 0, w, false});
  y += 1.6 * size;
  doc.rects.push_back({x0, y, w, 0.35, 0, 0, 0});
  for (int r = 0; r <= rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      std::ostringstream s;
      if (r == 0 || c == 0)  // the header row and the first column: words
        s << capitalised(word(rng));
      else
        s << std::fixed << std::setprecision(rng.randint(1, 3)) << rng.uniform(0, 100);
      doc.lines.push_back({r == 0 ? f.bold : f.body, s.str(), x0 + c * cw + 0.5 * cw,
                           y + row_h * (r + 0.75), size, 0, 0.9 * cw, true});
    }
    if (r == 0) doc.rects.push_back({x0, y + row_h, w, 0.2, 0, 0, 0});
  }
  doc.rects.push_back({x0, y + row_h * (rows + 1) + 0.3, w, 0.35, 0, 0, 0});
  doc.table_rows = rows;
  doc.table_cols = cols;
  flow.advance(h);
  return true;
}

bool figure(Rng& rng, DocumentLayout& doc, Flow& flow, const Fonts& f, double size) {
  const double w = flow.width(), plot_h = std::min(0.55 * w, 60.0), h = plot_h + 4 * size;
  if (!flow.reserve(h)) return false;
  const double x0 = flow.x() + 0.08 * w, y0 = flow.y() + 1.0, pw = 0.84 * w;
  const double axis = 0.3;
  doc.rects.push_back({x0, y0 + plot_h, pw, axis, 0, 0, 0});  // x axis
  doc.rects.push_back({x0, y0, axis, plot_h, 0, 0, 0});       // y axis
  for (int k = 1; k <= 4; ++k)                                // grid
    doc.rects.push_back({x0, y0 + plot_h * (1 - k / 5.0), pw, 0.12, 0.75, 0.75, 0.75});
  const double palette[4][3] = {
      {0.05, 0.2, 0.7}, {0.75, 0.08, 0.05}, {0.05, 0.5, 0.1}, {0.85, 0.45, 0.0}};
  if (rng.uniform() < 0.5) {
    doc.figure_kind = "bar-chart";
    const int n = rng.randint(4, 9);
    for (int i = 0; i < n; ++i) {
      const double bh = plot_h * rng.uniform(0.15, 0.95);
      const auto& c = palette[i % 2 == 0 ? 0 : 3];
      doc.rects.push_back(
          {x0 + pw * (i + 0.2) / n, y0 + plot_h - bh, 0.6 * pw / n, bh, c[0], c[1], c[2]});
    }
  } else {
    doc.figure_kind = "line-plot";
    const int curves = rng.randint(1, 3);
    for (int c = 0; c < curves; ++c) {
      const double a = rng.uniform(0.1, 0.4), fr = rng.uniform(1.0, 4.0), ph = rng.uniform(0, 6.28);
      const double base = rng.uniform(0.3, 0.7);
      for (int i = 0; i < 120; ++i) {
        const double t = i / 119.0;
        const double v =
            base + a * std::sin(fr * 6.28 * t + ph) * std::exp(-t * rng.uniform(0, 0.1));
        doc.rects.push_back({x0 + pw * t, y0 + plot_h * (1 - std::clamp(v, 0.02, 0.98)),
                             pw / 119.0 + 0.1, 0.55, palette[c][0], palette[c][1], palette[c][2]});
      }
    }
  }
  doc.lines.push_back({f.body,
                       "Figure 1: " + capitalised(word(rng)) + " " + word(rng) + " of the " +
                           word(rng) + " " + word(rng) + ".",
                       flow.x() + 0.5 * w, y0 + plot_h + 2.6 * size, size, 0, w, true});
  flow.advance(h);
  return true;
}

}  // namespace

int DocumentLayout::width_px() const {
  return static_cast<int>(std::lround(params.page_width_mm / 25.4 * params.dpi));
}
int DocumentLayout::height_px() const {
  return static_cast<int>(std::lround(params.page_height_mm / 25.4 * params.dpi));
}

std::vector<std::pair<std::string, std::string>> document_font_files() {
  std::vector<std::pair<std::string, std::string>> fonts = {
      {"DejaVuSerif.ttf", "/usr/share/fonts/truetype/dejavu/DejaVuSerif.ttf"},
      {"DejaVuSans-Bold.ttf", "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf"},
      {"DejaVuSans.ttf", "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"},
      {"LiberationSerif-Regular.ttf",
       "/usr/share/fonts/truetype/liberation/LiberationSerif-Regular.ttf"},
      {"LiberationSerif-Bold.ttf", "/usr/share/fonts/truetype/liberation/LiberationSerif-Bold.ttf"},
      {"LiberationSans-Regular.ttf",
       "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf"},
      {"LiberationSans-Bold.ttf", "/usr/share/fonts/truetype/liberation/LiberationSans-Bold.ttf"}};
  for (const auto& [name, path] : fonts)
    if (!std::filesystem::exists(path))
      throw IoError("font '" + path +
                    "' not found (install fonts-dejavu-core and fonts-liberation)");
  return fonts;
}

DocumentLayout generate_document(std::uint64_t seed, const DocumentParams& params) {
  Rng rng(seed, "document");
  DocumentLayout doc;
  doc.params = params;
  doc.seed = seed;
  const Fonts families[] = {
      {"DejaVuSerif.ttf", "DejaVuSans-Bold.ttf", "DejaVuSans-Bold.ttf"},
      {"LiberationSerif-Regular.ttf", "LiberationSerif-Bold.ttf", "LiberationSerif-Bold.ttf"},
      {"LiberationSans-Regular.ttf", "LiberationSans-Bold.ttf", "LiberationSans-Bold.ttf"},
      {"DejaVuSans.ttf", "DejaVuSans-Bold.ttf", "DejaVuSans-Bold.ttf"}};
  const Fonts& f = families[rng.randint(0, 3)];
  doc.fonts = {f.body, f.bold};
  const double W = params.page_width_mm, H = params.page_height_mm, margin = 0.1 * W;
  doc.columns = rng.uniform() < 0.4 ? 2 : 1;
  const double size = doc.columns == 2 ? rng.uniform(2.8, 3.3) : rng.uniform(3.2, 4.0);
  // Title block across the page.
  std::string title = capitalised(word(rng));
  for (int i = rng.randint(3, 6); i > 0; --i) title += " " + word(rng);
  doc.lines.push_back({f.heading, title, 0.5 * W, margin + 8.0, 7.0, 0, W - 2 * margin, true});
  doc.lines.push_back({f.body,
                       capitalised(word(rng)) + " " + capitalised(word(rng)) + ", " +
                           capitalised(word(rng)) + " " + capitalised(word(rng)),
                       0.5 * W, margin + 16.0, 3.6, 0, W - 2 * margin, true});
  const double gap = 6.0, col_w = (W - 2 * margin - (doc.columns - 1) * gap) / doc.columns;
  Flow flow(doc, margin + 24.0, H - margin - 6.0, margin, col_w, gap);
  const int table_at = rng.randint(1, 3), figure_at = rng.randint(1, 4);
  bool ok = true, table_done = false, figure_done = false;
  for (int block = 0; ok && block < 40; ++block) {
    if (block % 3 == 0)
      ok = heading(rng, doc, flow, f, block / 3 + 1);
    else if (!table_done && block >= table_at) {
      ok = table(rng, doc, flow, f, size);
      table_done = ok;
    } else if (!figure_done && block >= figure_at) {
      ok = figure(rng, doc, flow, f, size);
      figure_done = ok;
    } else
      ok = paragraph(rng, doc, flow, f, size);
  }
  doc.lines.push_back(
      {f.body, std::to_string(rng.randint(1, 40)), 0.5 * W, H - 0.6 * margin, 3.2, 0, 0, true});
  return doc;
}

void write_document_pov(std::ostream& out, const DocumentLayout& doc) {
  const double W = doc.params.page_width_mm, H = doc.params.page_height_mm;
  out << "// papersim scenegen: built-in document page, seed " << doc.seed << "\n"
      << "#version 3.7;\n#include \"document.inc\"\n"
      << "SG_Page(" << W << ", " << H << ")\n";
  out << std::setprecision(6);
  for (const TextLine& t : doc.lines)
    out << "SG_Line(\"" << t.font << "\", \"" << t.text << "\", " << t.x << ", " << H - t.y << ", "
        << t.size << ", " << t.justify_width << ", " << t.max_width << ", " << (t.centred ? 1 : 0)
        << ")\n";
  for (const Rect& r : doc.rects)
    out << "SG_Rect(" << r.x << ", " << H - r.y - r.h << ", " << r.w << ", " << r.h << ", <" << r.r
        << ", " << r.g << ", " << r.b << ">)\n";
}

}  // namespace papersim::scenegen
