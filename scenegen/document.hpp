#pragma once
/// The built-in document generator: a random page (title, headings, justified paragraphs in
/// real TrueType fonts, a table, a figure, a page number) written as a POV-Ray scene that
/// POV-Ray renders orthographically into the page image, so no user asset is needed.
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace papersim::scenegen {

/// Parameters of the generated page.
struct DocumentParams {
  double page_width_mm = 210.0;   ///< page size [mm] (the sheet's size)
  double page_height_mm = 297.0;  ///< [mm]
  double dpi = 150.0;             ///< raster resolution of the page image [dots per inch]
};

/// A line of text placed on the page (baseline origin, page millimetres, y down from the top).
struct TextLine {
  std::string font;  ///< file name of the TrueType font (copied into the job)
  std::string text;
  double x = 0, y = 0, size = 3.5;  ///< [mm]
  double justify_width = 0.0;       ///< > 0: stretch or shrink the line to this width [mm]
  double max_width = 0.0;           ///< the line is shrunk when wider than this [mm]
  bool centred = false;             ///< x is the line's centre
};

/// A filled rectangle (rules, table lines, figure marks), page millimetres, y down.
struct Rect {
  double x = 0, y = 0, w = 0, h = 0;  ///< [mm]
  double r = 0, g = 0, b = 0;         ///< linear RGB
};

/// A generated page: what is drawn, plus a summary recorded in meta.json.
struct DocumentLayout {
  DocumentParams params;
  std::uint64_t seed = 0;
  int columns = 1;
  std::vector<TextLine> lines;
  std::vector<Rect> rects;
  std::vector<std::string> fonts;  ///< fonts used (file names)
  std::string figure_kind;         ///< line-plot | bar-chart
  int table_rows = 0, table_cols = 0, paragraphs = 0, headings = 0;
  int width_px() const;
  int height_px() const;
};

/// Lay out a random page from `seed`.
DocumentLayout generate_document(std::uint64_t seed, const DocumentParams& params);

/// POV-Ray scene rendering the page (orthographic, emission only, white paper, black ink).
void write_document_pov(std::ostream& out, const DocumentLayout& doc);

/// System paths of the fonts the generator uses (in the order of their file names).
/// @throw IoError when a font file is missing.
std::vector<std::pair<std::string, std::string>> document_font_files();

}  // namespace papersim::scenegen
