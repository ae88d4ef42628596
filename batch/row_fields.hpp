#pragma once
/// A reader of the fields of one JSON-lines row without building the row: what `papersim
/// dataset-stats` counts and what a batch looks up in its manifest.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace papersim::batch {

/// What is read of one JSON-lines row (a manifest's or failures file's), gathered by a SAX handler
/// so that no row is built as a JSON value: its top-level "key", "scenario" and "reason" and the
/// wanted figures. A name given twice takes its last value, as parsing the row into an object
/// would. `figures` must outlive the reader.
class RowFields : public nlohmann::json_sax<nlohmann::json> {
 public:
  explicit RowFields(const std::vector<std::string>& figures)
      : m_figures(figures), m_values(figures.size()) {}

  /// Parse `line`: whether it is a JSON object whose "key" is a string (a row a batch counts).
  /// A line of plain JSON (ASCII strings without escapes, integers of at most 18 digits, nesting
  /// at most 64 deep: every row a batch writes) is read by a scanner of that subset, which gives
  /// this handler the events nlohmann's parser would; any other line, or one the scanner is
  /// unsure of, by nlohmann's parser (tests/batch: RowFields.*, and fuzz_dataset_stats).
  bool read_key(const std::string& line) {
    reset();
    if (m_simple_scan && scan_plain_json(line)) {
      ++m_plain_lines;
    } else {
      reset();
      if (!nlohmann::json::sax_parse(line, this)) return false;
    }
    return m_seen_object && m_key.given && m_key.is_string;
  }
  /// Whether lines are tried with the scanner of plain JSON first (the default); off, every
  /// line goes through nlohmann's parser (a test compares the two).
  void use_simple_scan(bool on) { m_simple_scan = on; }
  /// Lines read so far by the scanner of plain JSON.
  std::size_t plain_lines() const { return m_plain_lines; }
  /// read_key, and "scenario" and "reason" are strings where present (a row the report counts).
  bool read(const std::string& line) {
    return read_key(line) && (!m_scenario.given || m_scenario.is_string) &&
           (!m_reason.given || m_reason.is_string);
  }
  const std::string& key() const { return m_key.text; }
  std::string scenario() const { return m_scenario.given ? m_scenario.text : "?"; }
  std::string reason() const { return m_reason.given ? m_reason.text : "?"; }
  /// Figure i when the row gives it as a number, else NaN.
  double value(std::size_t i) const { return m_values[i]; }

  bool null() override { return scalar(nullptr, NAN); }
  bool boolean(bool) override { return scalar(nullptr, NAN); }
  bool number_integer(number_integer_t v) override {
    return scalar(nullptr, static_cast<double>(v));
  }
  bool number_unsigned(number_unsigned_t v) override {
    return scalar(nullptr, static_cast<double>(v));
  }
  bool number_float(number_float_t v, const string_t&) override { return scalar(nullptr, v); }
  bool string(string_t& v) override { return scalar(&v, NAN); }
  bool binary(binary_t&) override { return scalar(nullptr, NAN); }
  bool start_object(std::size_t) override { return open(true); }
  bool start_array(std::size_t) override { return open(false); }
  bool end_object() override { return --m_depth, true; }
  bool end_array() override { return --m_depth, true; }
  bool key(string_t& name) override {
    if (m_depth == 1) m_name = name;
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
    return false;
  }

 private:
  void reset() {
    m_depth = 0;
    m_seen_object = false;
    m_name.clear();
    m_key = m_scenario = m_reason = Field{};
    std::fill(m_values.begin(), m_values.end(), NAN);
  }
  /// The scanner of plain JSON: true when `line` is plain JSON and its events were given; false
  /// when it is not or the scanner cannot tell (events given so far must be reset).
  bool scan_plain_json(const std::string& line);

  struct Field {
    bool given = false, is_string = false;
    std::string text;
  };

  /// The top-level value named `m_name` is a string (`text`), a number (`number`) or neither.
  bool scalar(const std::string* text, double number) {
    if (m_depth != 1) return true;
    Field* f = m_name == "key"        ? &m_key
               : m_name == "scenario" ? &m_scenario
               : m_name == "reason"   ? &m_reason
                                      : nullptr;
    if (f) {
      f->given = true;
      f->is_string = text != nullptr;
      if (text) f->text = *text;
      return true;
    }
    for (std::size_t i = 0; i < m_figures.size(); ++i)
      if (m_name == m_figures[i]) m_values[i] = number;
    return true;
  }
  bool open(bool object) {
    if (m_depth == 0)
      m_seen_object = object;
    else if (m_depth == 1)
      scalar(nullptr, NAN);  // a container is neither a string nor a number
    ++m_depth;
    return true;
  }

  const std::vector<std::string>& m_figures;
  std::vector<double> m_values;
  Field m_key, m_scenario, m_reason;
  std::string m_name;
  int m_depth = 0;
  bool m_seen_object = false;
  bool m_simple_scan = true;
  std::size_t m_plain_lines = 0;
  std::string m_scan_text;  ///< the scanner's text of a string (its capacity kept across lines)
};

}  // namespace papersim::batch
