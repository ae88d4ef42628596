// The reader of a row's fields gives the same key, scenario, reason and figures (to the bit)
// whether a line goes through its scanner of plain JSON or through nlohmann's parser, for rows
// as a batch writes them and for every kind of line the scanner leaves to the parser.
#include "batch/row_fields.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

using papersim::batch::RowFields;

namespace {

const std::vector<std::string> FIGURES = {"wall_seconds", "vertices", "seed", "x", "key"};

struct Read {
  bool row = false, counted = false;
  std::string key, scenario, reason;
  std::vector<double> values;
};

Read read_with(RowFields& r, const std::string& line) {
  Read out;
  out.counted = r.read(line);
  out.row = r.read_key(line);
  out.key = r.key();
  out.scenario = r.scenario();
  out.reason = r.reason();
  for (std::size_t i = 0; i < FIGURES.size(); ++i) out.values.push_back(r.value(i));
  return out;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

TEST(RowFields, TheScannerOfPlainJsonReadsAsNlohmannsParser) {
  // plain: read by the scanner; others left to the parser (also when they are valid JSON).
  const std::vector<std::pair<std::string, bool>> lines = {
      {R"({"key":"meshes/pull/0/1","scenario":"pull","seed":1,"wall_seconds":0.43,"set":{"duration":0.02,"a":[1,{"b":"c"}]},"vertices":682})",
       true},
      {R"(  {"key" : "k" , "scenario":"fold", "reason":"time limit", "wall_seconds": 1e-3 }	 )",
       true},
      {"{\"key\"\r:\"m/14\",\"x\":\r\n-0}", true},
      {R"({"key":"a","x":-0.0})", true},
      {R"({"key":"a","x":0.1,"x":2.5E+3})", true},  // the last one counts
      {R"({"key":"a","x":123456789012345678})", true},
      {R"({"key":"a","x":-123456789012345678})", true},
      {R"({"key":"a","x":5e-324,"seed":1.7976931348623157e308})", true},
      {R"({"key":"a","x":true,"seed":null,"vertices":false,"wall_seconds":[]})", true},
      {R"({"key":"a","scenario":3})", true},
      {R"({"key":{"key":"b"}})", true},
      {R"({"key":"b","key":"c"})", true},
      {R"({"scenario":"pull"})", true},
      {R"(["key","a"])", true},
      {R"("key")", true},
      {"{\"key\":\"a\x7f\"}", true},
      {R"({})", true},
      // Valid, left to the parser.
      {R"({"key":"a","x":1234567890123456789})", false},
      {R"({"key":"a","x":18446744073709551615})", false},
      {R"({"key":"a","x":-9223372036854775808})", false},
      {R"({"key":"a","x":99999999999999999999999})", false},
      {R"({"key":"a","x":1e-400})", false},
      {R"({"key":"a\"b","x":1})", false},
      {R"({"key":"a\u00e9","x":1})", false},
      {"{\"key\":\"\xc3\xa9\",\"x\":1}", false},
      {"\xef\xbb\xbf{\"key\":\"a\"}", false},
      {std::string(70, '[') + std::string(70, ']'), false},
      {"{\"key\":\"a\",\"x\":" + std::string(70, '[') + std::string(70, ']') + "}", false},
      // Not JSON.
      {R"({"key":"a","x":1e400})", false},
      {R"({"key":"a","x":01})", false},
      {R"({"key":"a","x":1.})", false},
      {R"({"key":"a","x":.5})", false},
      {R"({"key":"a","x":+1})", false},
      {R"({"key":"a","x":-})", false},
      {R"({"key":"a","x":1e})", false},
      {R"({"key":"a","x":tru})", false},
      {R"({"key":"a",})", false},
      {R"({"key":"a"} x)", false},
      {R"({"key":"a")", false},
      {R"({"key" "a"})", false},
      {"{\"key\":\"a\tb\"}", false},
      {"{\"key\":\"a\"}\f", false},
      {R"({"key":"a"}{"key":"b"})", false},
      {R"({"key":"a","x":[1,]})", false},
      {R"({key:"a"})", false},
  };
  RowFields plain(FIGURES), parsed(FIGURES);
  parsed.use_simple_scan(false);
  for (const auto& [line, is_plain] : lines) {
    const std::size_t before = plain.plain_lines();
    const Read a = read_with(plain, line), b = read_with(parsed, line);
    EXPECT_EQ(plain.plain_lines() - before, is_plain ? 2u : 0u) << line;
    EXPECT_EQ(a.row, b.row) << line;
    EXPECT_EQ(a.counted, b.counted) << line;
    EXPECT_EQ(a.key, b.key) << line;
    EXPECT_EQ(a.scenario, b.scenario) << line;
    EXPECT_EQ(a.reason, b.reason) << line;
    for (std::size_t i = 0; i < FIGURES.size(); ++i)
      EXPECT_TRUE(same_bits(a.values[i], b.values[i]))
          << line << ": " << FIGURES[i] << " " << a.values[i] << " vs " << b.values[i];
  }
  EXPECT_EQ(parsed.plain_lines(), 0u);
  // A few of the answers, spelled out.
  const Read first = read_with(plain, lines[0].first);
  EXPECT_TRUE(first.counted);
  EXPECT_EQ(first.key, "meshes/pull/0/1");
  EXPECT_EQ(first.values[2], 1.0);
  EXPECT_EQ(first.values[0], 0.43);
  EXPECT_EQ(first.values[1], 682.0);
  EXPECT_TRUE(std::isnan(first.values[3]));
  EXPECT_TRUE(std::isnan(first.values[4]));  // a string is not a figure
  const Read zero = read_with(plain, lines[2].first);
  EXPECT_EQ(zero.key, "m/14");
  EXPECT_FALSE(std::signbit(zero.values[3]));  // the integer -0 is 0
  EXPECT_TRUE(std::signbit(read_with(plain, lines[3].first).values[3]));
  EXPECT_EQ(read_with(plain, lines[4].first).values[3], 2500.0);
  EXPECT_FALSE(read_with(plain, lines[9].first).counted);  // scenario not a string
  EXPECT_FALSE(read_with(plain, lines[10].first).row);     // key not a string
  EXPECT_EQ(read_with(plain, lines[11].first).key, "c");
}

// Numbers in every form a row may hold them, drawn at random: the scanner's value is the parser's
// to the bit (or it leaves the line to the parser).
TEST(RowFields, TheScannersNumbersAreTheParsersToTheBit) {
  std::mt19937_64 rng(20261207);
  const auto digits = [&](int n, bool lead_nonzero) {
    std::string d;
    for (int i = 0; i < n; ++i)
      d += static_cast<char>('0' + (i == 0 && lead_nonzero ? 1 + rng() % 9 : rng() % 10));
    return d;
  };
  RowFields plain(FIGURES), parsed(FIGURES);
  parsed.use_simple_scan(false);
  std::size_t scanned = 0;
  constexpr int n = 20000;
  for (int i = 0; i < n; ++i) {
    std::string number;
    switch (i % 4) {
      case 0: {  // an integer of 1-20 digits
        const int k = 1 + static_cast<int>(rng() % 20);
        number = k == 1 ? digits(1, false) : digits(k, true);
        break;
      }
      case 1: {  // a double printed with 17 significant digits
        double v;
        do {
          const std::uint64_t bits = rng();
          std::memcpy(&v, &bits, sizeof v);
        } while (!std::isfinite(v));
        char b[40];
        std::snprintf(b, sizeof b, "%.17g", v);
        number = b;
        break;
      }
      case 2:  // digits, a fraction and an exponent from -340 to 320
        number = digits(1 + static_cast<int>(rng() % 25), true) + "." +
                 digits(1 + static_cast<int>(rng() % 25), false) + (rng() % 2 ? "e" : "E") +
                 std::to_string(static_cast<int>(rng() % 661) - 340);
        break;
      default:  // a short decimal, as a timer writes it
        number = digits(1, false) + "." + digits(1 + static_cast<int>(rng() % 9), false);
    }
    if (rng() % 2 && number[0] != '-') number = "-" + number;
    const std::string line = R"({"key":"k","x":)" + number + "}";
    const std::size_t before = plain.plain_lines();
    const Read a = read_with(plain, line), b = read_with(parsed, line);
    scanned += plain.plain_lines() - before;
    ASSERT_EQ(a.row, b.row) << line;
    ASSERT_TRUE(same_bits(a.values[3], b.values[3]))
        << line << ": " << a.values[3] << " vs " << b.values[3];
  }
  // Most lines are plain: integers over 18 digits, and exponents out of range, are not.
  EXPECT_GT(scanned, 2u * n * 3 / 4) << scanned;
}
