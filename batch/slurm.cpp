#include "batch/slurm.hpp"

#include <algorithm>
#include <cctype>
#include <sstream>
#include <stdexcept>
#include <string_view>

namespace papersim::batch {

std::string shell_quote(const std::string& word) {
  std::string q = "'";
  for (char c : word) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string shell_word(const std::string& word) {
  const bool plain = !word.empty() && std::all_of(word.begin(), word.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) ||
           std::string_view("%+,-./:=@_").find(c) != std::string_view::npos;
  });
  return plain ? word : shell_quote(word);
}

std::string directive_word(const std::string& word, const std::string& what) {
  if (word.empty()) throw std::invalid_argument(what + " is empty");
  std::string out = "\"";
  for (const char c : word) {
    if (c == '\n' || c == '\r')
      throw std::invalid_argument(what + " '" + word +
                                  "' has a line break: no line of a Slurm script can hold it");
    if (c == '\\')
      throw std::invalid_argument(what + " '" + word +
                                  "' has a backslash, which sbatch reads as an escape");
    if (c == '"') out += '\\';
    out += c;
  }
  return out + "\"";
}

namespace {

/// LOG_DIR/name as a #SBATCH value; `name` holds sbatch's file name patterns (%A, %a).
std::string log_word(const std::filesystem::path& log_dir, const std::string& name) {
  const std::string dir = log_dir.string();
  if (dir.find('%') != std::string::npos)
    throw std::invalid_argument("the Slurm log folder '" + dir +
                                "' has a '%', which sbatch reads as a file name pattern (the "
                                "tasks could not open their logs): use a dataset path without it");
  return directive_word((log_dir / name).string(), "the Slurm log folder");
}

}  // namespace

std::string slurm_script(const std::vector<std::string>& command, const SlurmOptions& o,
                         const std::filesystem::path& log_dir) {
  if (o.shards < 1) throw std::invalid_argument("--slurm needs at least 1 shard");
  if (o.cpus_per_task < 1) throw std::invalid_argument("--slurm-cpus must be >= 1");
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# Slurm job array: task I runs shard I/" << o.shards << " of the batch below. A task that\n"
    << "# died (node lost, time limit, scancel) is simply submitted again: it resumes its shard.\n"
    << "#   sbatch --array=I THIS_FILE\n"
    << "#SBATCH --job-name=" << directive_word(o.job_name, "the job name") << "\n"
    << "#SBATCH --array=0-" << o.shards - 1
    << (o.max_running > 0 ? "%" + std::to_string(o.max_running) : "") << "\n"
    << "#SBATCH --ntasks=1\n"
    << "#SBATCH --cpus-per-task=" << o.cpus_per_task << "\n"
    << "#SBATCH --mem=" << directive_word(o.mem, "--slurm-mem") << "\n"
    << "#SBATCH --time=" << directive_word(o.time, "--slurm-time") << "\n"
    << "#SBATCH --output=" << log_word(log_dir, "%A_%a.out") << "\n"
    << "#SBATCH --error=" << log_word(log_dir, "%A_%a.err") << "\n";
  if (!o.partition.empty())
    s << "#SBATCH --partition=" << directive_word(o.partition, "--slurm-partition") << "\n";
  s << "set -euo pipefail\n"
    << "exec";
  for (const auto& w : command) s << ' ' << shell_quote(w);
  s << " --shard \"${SLURM_ARRAY_TASK_ID}/" << o.shards << "\" --jobs \"${SLURM_CPUS_PER_TASK:-"
    << o.cpus_per_task << "}\"\n";
  return s.str();
}

}  // namespace papersim::batch
