#include "batch/slurm.hpp"

#include <sstream>
#include <stdexcept>

namespace papersim::batch {

std::string shell_quote(const std::string& word) {
  std::string q = "'";
  for (char c : word) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string slurm_script(const std::vector<std::string>& command, const SlurmOptions& o,
                         const std::filesystem::path& log_dir) {
  if (o.shards < 1) throw std::invalid_argument("--slurm needs at least 1 shard");
  if (o.cpus_per_task < 1) throw std::invalid_argument("--slurm-cpus must be >= 1");
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# Slurm job array: task I runs shard I/" << o.shards << " of the batch below. A task that\n"
    << "# died (node lost, time limit, scancel) is simply submitted again: it resumes its shard.\n"
    << "#   sbatch --array=I THIS_FILE\n"
    << "#SBATCH --job-name=" << o.job_name << "\n"
    << "#SBATCH --array=0-" << o.shards - 1
    << (o.max_running > 0 ? "%" + std::to_string(o.max_running) : "") << "\n"
    << "#SBATCH --ntasks=1\n"
    << "#SBATCH --cpus-per-task=" << o.cpus_per_task << "\n"
    << "#SBATCH --mem=" << o.mem << "\n"
    << "#SBATCH --time=" << o.time << "\n"
    << "#SBATCH --output=" << (log_dir / "%A_%a.out").string() << "\n"
    << "#SBATCH --error=" << (log_dir / "%A_%a.err").string() << "\n";
  if (!o.partition.empty()) s << "#SBATCH --partition=" << o.partition << "\n";
  s << "set -euo pipefail\n"
    << "exec";
  for (const auto& w : command) s << ' ' << shell_quote(w);
  s << " --shard \"${SLURM_ARRAY_TASK_ID}/" << o.shards << "\" --jobs \"${SLURM_CPUS_PER_TASK:-"
    << o.cpus_per_task << "}\"\n";
  return s.str();
}

}  // namespace papersim::batch
