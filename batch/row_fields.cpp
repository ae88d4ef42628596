#include "batch/row_fields.hpp"

#include <charconv>
#include <cstdint>
#include <system_error>

namespace papersim::batch {

/// Recursive descent over the subset of JSON every batch row is written in, giving RowFields the
/// events nlohmann::json::sax_parse gives for it: start_object / key / value / end_object (and
/// arrays), an integer as number_unsigned (>= 0) or number_integer (< 0), any other number as
/// number_float. Anything outside the subset makes it give up (false): a byte outside
/// 0x20-0x7f or an escape in a string, an integer of more than 18 digits, a float that is not
/// finite or that from_chars finds out of range, nesting deeper than 64, malformed JSON.
class PlainJsonScan {
 public:
  /// `text` holds a string's bytes while it is given to the handler.
  PlainJsonScan(RowFields& h, const std::string& line, std::string& text)
      : m_h(h), m_p(line.data()), m_end(line.data() + line.size()), m_text(text) {}

  bool run() {
    skip_space();
    if (!value(0)) return false;
    skip_space();
    return m_p == m_end;
  }

 private:
  static constexpr int kMaxDepth = 64;

  static bool digit(char c) { return c >= '0' && c <= '9'; }
  void skip_space() {
    while (m_p < m_end && (*m_p == ' ' || *m_p == '\t' || *m_p == '\n' || *m_p == '\r')) ++m_p;
  }
  bool at(char c) const { return m_p < m_end && *m_p == c; }

  /// A string at m_p into m_text (only when `keep`: a value or name deeper than the top level
  /// is not looked at).
  bool string(bool keep) {
    const char* begin = ++m_p;  // after the opening quote
    while (m_p < m_end) {
      const auto c = static_cast<unsigned char>(*m_p);
      if (c == '"') {
        if (keep) m_text.assign(begin, m_p);
        ++m_p;
        return true;
      }
      if (c < 0x20 || c > 0x7f || c == '\\') return false;
      ++m_p;
    }
    return false;
  }

  bool literal(const char* word, std::size_t n) {
    if (static_cast<std::size_t>(m_end - m_p) < n || std::string_view(m_p, n) != word) return false;
    m_p += n;
    return true;
  }

  bool number() {
    const char* begin = m_p;
    const bool negative = at('-');
    if (negative) ++m_p;
    if (at('0')) {
      ++m_p;
    } else if (m_p < m_end && *m_p >= '1' && *m_p <= '9') {
      while (m_p < m_end && digit(*m_p)) ++m_p;
    } else {
      return false;
    }
    const char* integer_end = m_p;
    bool is_float = false;
    if (at('.')) {
      is_float = true;
      ++m_p;
      if (!(m_p < m_end && digit(*m_p))) return false;
      while (m_p < m_end && digit(*m_p)) ++m_p;
    }
    if (at('e') || at('E')) {
      is_float = true;
      ++m_p;
      if (at('+') || at('-')) ++m_p;
      if (!(m_p < m_end && digit(*m_p))) return false;
      while (m_p < m_end && digit(*m_p)) ++m_p;
    }
    if (!is_float) {
      const char* first = begin + (negative ? 1 : 0);
      if (integer_end - first > 18) return false;  // may not fit: nlohmann's parser decides
      std::int64_t v = 0;
      for (const char* c = first; c < integer_end; ++c) v = 10 * v + (*c - '0');
      if (negative) return m_h.number_integer(-v);  // "-0" is the integer 0, as for nlohmann
      return m_h.number_unsigned(static_cast<std::uint64_t>(v));
    }
    // nlohmann reads the token with strtod (in the C locale's terms); from_chars rounds
    // correctly as glibc's strtod does, whatever the locale.
    double v = 0;
    const auto [end, error] = std::from_chars(begin, m_p, v);
    if (error != std::errc() || end != m_p || !std::isfinite(v)) return false;
    return m_h.number_float(v, m_no_text);
  }

  bool value(int depth) {
    if (m_p >= m_end) return false;
    switch (*m_p) {
      case '{':
        return container(depth + 1, true);
      case '[':
        return container(depth + 1, false);
      case '"':
        if (!string(depth == 1)) return false;
        return m_h.string(m_text);
      case 't':
        return literal("true", 4) && m_h.boolean(true);
      case 'f':
        return literal("false", 5) && m_h.boolean(false);
      case 'n':
        return literal("null", 4) && m_h.null();
      default:
        return number();
    }
  }

  /// An object or an array at m_p: comma-separated members (a name, a colon and a value) or
  /// elements between its brackets.
  bool container(int depth, bool object) {
    if (depth > kMaxDepth) return false;
    const char close = object ? '}' : ']';
    ++m_p;
    if (object)
      m_h.start_object(static_cast<std::size_t>(-1));
    else
      m_h.start_array(static_cast<std::size_t>(-1));
    skip_space();
    for (bool first = true;; first = false) {
      if (first && at(close)) break;  // empty; after a comma, a value must follow
      if (object) {
        if (!at('"') || !string(depth == 1)) return false;
        if (depth == 1) m_h.key(m_text);
        skip_space();
        if (!at(':')) return false;
        ++m_p;
        skip_space();
      }
      if (!value(depth)) return false;
      skip_space();
      if (!at(',')) break;
      ++m_p;
      skip_space();
    }
    if (!at(close)) return false;
    ++m_p;
    return object ? m_h.end_object() : m_h.end_array();
  }

  RowFields& m_h;
  const char* m_p;
  const char* m_end;
  std::string& m_text;
  const std::string m_no_text;
};

bool RowFields::scan_plain_json(const std::string& line) {
  return PlainJsonScan(*this, line, m_scan_text).run();
}

}  // namespace papersim::batch
