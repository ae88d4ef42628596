#include "dataset_tree.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "batch/runner.hpp"

namespace papersim::test {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

bool is_wall_time_key(const std::string& k) {
  return k == "wall_seconds" || k == "seconds" || k.rfind("seconds_", 0) == 0;
}

json without_wall_times(const json& j) {
  if (!j.is_object()) return j;
  json out = json::object();
  for (const auto& [k, v] : j.items())
    if (!is_wall_time_key(k)) out[k] = without_wall_times(v);
  return out;
}

std::set<std::string> files_under(const fs::path& root) {
  std::set<std::string> out;
  if (!fs::exists(root)) return out;
  for (const auto& e : fs::recursive_directory_iterator(root))
    if (e.is_regular_file()) out.insert(fs::relative(e.path(), root).generic_string());
  return out;
}

std::map<std::string, json> manifest_rows(const fs::path& file) {
  std::map<std::string, json> rows;
  for (json r : papersim::batch::read_json_lines(file)) {
    r.erase("wall_seconds");
    r.erase("sim_wall_seconds");
    r.erase("cpu_seconds");
    rows[r["key"].get<std::string>()] = r;
  }
  return rows;
}

}  // namespace

std::string read_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> dataset_differences(const fs::path& a, const fs::path& b,
                                             const std::string& part, const std::string& manifest) {
  std::vector<std::string> diffs;
  const auto fa = files_under(a / part), fb = files_under(b / part);
  if (fa.empty()) diffs.push_back("no files under " + (a / part).string());
  for (const auto& f : fa)
    if (!fb.count(f)) diffs.push_back("only in " + a.string() + ": " + f);
  for (const auto& f : fb)
    if (!fa.count(f)) diffs.push_back("only in " + b.string() + ": " + f);
  for (const auto& f : fa) {
    if (!fb.count(f)) continue;
    const std::string ta = read_text(a / part / f), tb = read_text(b / part / f);
    if (part == "meshes" && fs::path(f).filename() == "meta.json") {
      if (without_wall_times(json::parse(ta)) != without_wall_times(json::parse(tb)))
        diffs.push_back("meta.json differs beyond wall times: " + f);
    } else if (ta != tb) {
      diffs.push_back("bytes differ: " + f);
    }
  }
  const auto ma = manifest_rows(a / manifest), mb = manifest_rows(b / manifest);
  if (ma != mb)
    diffs.push_back("manifests differ (" + std::to_string(ma.size()) + " and " +
                    std::to_string(mb.size()) + " rows)");
  if (line_count(a / manifest) != ma.size() || line_count(b / manifest) != mb.size())
    diffs.push_back("a manifest has duplicate rows");
  for (const fs::path& root : {a, b})
    if (fs::exists(root / ".staging") && !fs::is_empty(root / ".staging"))
      diffs.push_back("staging leftovers in " + root.string());
  return diffs;
}

pid_t start(const std::vector<std::string>& argv, const fs::path& log) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    execv(args[0], args.data());
    _exit(127);
  }
  return pid;
}

int wait_status(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::size_t line_count(const fs::path& file) {
  std::ifstream in(file);
  std::size_t n = 0;
  for (std::string l; std::getline(in, l);) n += !l.empty();
  return n;
}

}  // namespace papersim::test
