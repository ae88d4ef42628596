#pragma once
// The oracle for dataset-stats' row reader (batch::read_part), shared by its unit test and its
// fuzz target: what parsing every line of a manifest and its failures file into a JSON object
// gives. Header-only, so that the fuzz build (clang, no test libraries) can include it.
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "batch/dataset_stats.hpp"

namespace papersim::batch::testing {

inline PartStats parse_every_line(const std::string& manifest, const std::string& failures,
                                  const std::vector<std::string>& figures) {
  using nlohmann::json;
  PartStats want;
  const auto well_formed = [](const json& j) {
    if (!j.is_object() || !j.contains("key") || !j["key"].is_string()) return false;
    for (const char* k : {"scenario", "reason"})
      if (j.contains(k) && !j[k].is_string()) return false;
    return true;
  };
  const auto rows = [&](const std::string& text, auto row) {
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      const json j = json::parse(line, nullptr, false);
      if (j.is_discarded() || !well_formed(j))
        ++want.skipped_lines;
      else
        row(j);
    }
  };
  std::set<std::string> done;
  rows(manifest, [&](const json& j) {
    if (!done.insert(j["key"].get<std::string>()).second) return;
    const std::string s = j.value("scenario", std::string("?"));
    ++want.done[s];
    for (const auto& f : figures)
      if (j.contains(f) && j[f].is_number()) want.values[f][s].push_back(j[f].get<double>());
  });
  std::map<std::string, json> latest;
  rows(failures, [&](const json& j) {
    ++want.failed_attempts;
    latest[j["key"].get<std::string>()] = j;
  });
  for (const auto& [key, j] : latest)
    if (!done.count(key)) {
      ++want.failed[j.value("scenario", std::string("?"))];
      ++want.reasons[j.value("reason", std::string("?"))];
    }
  return want;
}

}  // namespace papersim::batch::testing
