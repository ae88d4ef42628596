// libFuzzer target: `papersim dataset-stats`' reader of a manifest and its failures file
// (batch::read_part: rows read as streams of JSON events, keys in a KeySet, values in blocks),
// checked against parsing every line into a JSON object; and the batch's search of the manifest
// for its tasks' keys (batch::keys_in_json_lines, which parses only lines that may name one),
// checked the same way for every quoted text of the input as a wanted key. The input is the
// manifest, then a form feed and the failures file (a form feed is no JSON whitespace, so a line
// with one is malformed either way; without one, the failures file is empty). Any difference in the
// counts, the reasons, the lines left out or any figure's values, any exception, a crash or a
// sanitizer report is a finding.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "../batch/parsed_rows.hpp"
#include "batch/dataset_stats.hpp"
#include "batch/key_set.hpp"
#include "batch/runner.hpp"

namespace fs = std::filesystem;
using papersim::batch::PartStats;

namespace {

const std::vector<std::string> FIGURES = {"wall_seconds", "vertices", "key", "seed"};

/// Values equal to the bit, NaN included (a figure is never NaN, but a difference must show).
bool same_values(const PartStats& a, const PartStats& b) {
  if (a.values.size() != b.values.size()) return false;
  for (const auto& [figure, per] : a.values) {
    const auto it = b.values.find(figure);
    if (it == b.values.end() || it->second.size() != per.size()) return false;
    for (const auto& [s, v] : per) {
      const auto jt = it->second.find(s);
      if (jt == it->second.end()) return false;
      const std::vector<double> x = v.to_vector(), y = jt->second.to_vector();
      if (x.size() != y.size()) return false;
      for (std::size_t i = 0; i < x.size(); ++i)
        if (std::memcmp(&x[i], &y[i], sizeof(double)) != 0) return false;
    }
  }
  return true;
}

const fs::path& dir() {
  static const fs::path d = [] {
    fs::path p = fs::temp_directory_path() / ("papersim_fuzz_stats_" + std::to_string(getpid()));
    fs::create_directories(p);
    return p;
  }();
  return d;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  const std::size_t cut = std::min(input.find('\f'), input.size());
  const std::string manifest = input.substr(0, cut),
                    failures = cut < input.size() ? input.substr(cut + 1) : std::string();
  std::ofstream(dir() / "manifest.jsonl", std::ios::binary | std::ios::trunc) << manifest;
  std::ofstream(dir() / "failures.jsonl", std::ios::binary | std::ios::trunc) << failures;
  const PartStats got = papersim::batch::read_part("meshes", dir() / "manifest.jsonl",
                                                   dir() / "failures.jsonl", FIGURES);
  const PartStats want = papersim::batch::testing::parse_every_line(manifest, failures, FIGURES);
  const bool same = got.done == want.done && got.failed == want.failed &&
                    got.reasons == want.reasons && got.failed_attempts == want.failed_attempts &&
                    got.skipped_lines == want.skipped_lines && same_values(got, want);
  if (!same) {
    std::fprintf(stderr, "read_part differs from parsing every line into an object\n");
    std::abort();
  }
  // Wanted: every text between two quotes (rows' keys, nested ones, names, values, pieces).
  papersim::batch::KeySet wanted;
  for (std::size_t a = manifest.find('"'); a != std::string::npos;) {
    const std::size_t b = manifest.find('"', a + 1);
    if (b == std::string::npos) break;
    wanted.insert(std::string_view(manifest).substr(a + 1, b - a - 1));
    a = b;
  }
  const papersim::batch::KeySet found =
      papersim::batch::keys_in_json_lines(dir() / "manifest.jsonl", wanted);
  papersim::batch::KeySet rows;  // the rows' own keys that are wanted, from whole objects
  std::size_t start = 0;
  while (start < manifest.size()) {
    const std::size_t end = std::min(manifest.find('\n', start), manifest.size());
    const nlohmann::json j =
        nlohmann::json::parse(manifest.substr(start, end - start), nullptr, false);
    if (!j.is_discarded() && j.is_object()) {
      const auto k = j.find("key");
      if (k != j.end() && k->is_string() && wanted.contains(k->get_ref<const std::string&>()))
        rows.insert(k->get_ref<const std::string&>());
    }
    start = end + 1;
  }
  bool keys_same = found.size() == rows.size();
  for (std::size_t a = manifest.find('"'); keys_same && a != std::string::npos;) {
    const std::size_t b = manifest.find('"', a + 1);
    if (b == std::string::npos) break;
    const std::string_view k = std::string_view(manifest).substr(a + 1, b - a - 1);
    keys_same = found.contains(k) == rows.contains(k);
    a = b;
  }
  if (!keys_same) {
    std::fprintf(stderr, "keys_in_json_lines differs from parsing every line into an object\n");
    std::abort();
  }
  return 0;
}
