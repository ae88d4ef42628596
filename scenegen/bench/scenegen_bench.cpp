// scenegen_bench: cost of a whole sample at full resolution (default 1024 x 1440) against a
// baseline scenegen executable (an older build), in the same run, interleaved, and the error
// of each one's photo against a converged reference.
//   scenegen_bench --baseline EXE [--scenegen EXE] [--runs N] [--size WxH] [--seed N]
//                  [--mesh fold|cylinder|bump|flat] [--no-reference] [--keep DIR]
// For each mode (final: every pass; draft: every pass at draft quality; ground truth: every
// pass but the photo and the shading) and round, `scenegen render` runs as a child process for
// the baseline and for this build on the refined surface (--subdivision 2) and on the raw mesh
// (--subdivision 0), one after the other (interleaved, so the load of a shared machine falls
// on all of them alike). Reported per configuration: median wall time and median CPU time of
// scenegen and its POV-Ray children (wait4), their ratios to the baseline, whether the runs of
// this build gave identical files, and PSNR / SSIM of the final photo against a converged
// reference of the same surface, rendered with this program's library (so --scenegen must be
// the same build, as the default is; the baseline's figure then also measures every change of
// the scene since it, e.g. exposure). Then the exactness figures of this build's sample.
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench_args.hpp"
#include "image_error.hpp"
#include "scenegen/decode.hpp"
#include "scenegen/edge_lift.hpp"
#include "scenegen/example_sheets.hpp"
#include "scenegen/geometry.hpp"
#include "scenegen/image_io.hpp"
#include "scenegen/job.hpp"
#include "scenegen/meta.hpp"
#include "scenegen/random.hpp"
#include "scenegen/smooth_surface.hpp"

namespace fs = std::filesystem;
namespace sg = papersim::scenegen;

namespace {

struct Timing {
  double wall = 0, cpu = 0;  ///< [s]
};

/// Run a command (argv) to completion; wall time and CPU time (user + system) of it and its
/// waited-for descendants. @throw std::runtime_error when it fails
Timing run_command(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    const int null = open("/dev/null", O_WRONLY);
    if (null >= 0) dup2(null, 1);
    execv(args[0], args.data());
    _exit(127);
  }
  int status = 0;
  rusage ru{};
  if (wait4(pid, &status, 0, &ru) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error("'" + argv[0] + " " + argv[1] + "' failed (status " +
                             std::to_string(status) + ")");
  Timing t;
  t.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  t.cpu =
      ru.ru_utime.tv_sec + ru.ru_stime.tv_sec + 1e-6 * (ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
  return t;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct Config {
  std::string name, exe;
  int level = -1;  ///< --subdivision; -1: not passed (the baseline has no such option)
};

struct Mode {
  std::string name, quality, passes;
};

/// Every file of a sample folder and its bytes.
std::map<std::string, std::string> sample_bytes(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path(), std::ios::binary);
    out[e.path().filename().string()] = std::string(std::istreambuf_iterator<char>(in), {});
  }
  return out;
}

void exactness(const fs::path& dir, const std::string& mesh_path) {
  std::ifstream in(dir / "meta.json");
  const auto meta = nlohmann::json::parse(in);
  // Exact for the surface rendered: the mesh refined at the recorded level, lifted, curled.
  sg::SurfaceParams surface;
  surface.level = meta["surface"]["level"];
  const auto& st = meta["stage"];
  const sg::SheetMesh mesh =
      sg::rendered_surface(sg::read_sheet_obj(mesh_path),
                           Eigen::Vector3d(st["origin"][0], st["origin"][1], st["origin"][2]),
                           Eigen::Vector3d(st["up"][0], st["up"][1], st["up"][2]), surface,
                           sg::edge_lift_from_json(meta["surface"]))
          .surface;
  const sg::UvLocator loc(mesh);
  const sg::Camera cam = sg::camera_from_json(meta["camera"]);
  const sg::ImageF uv = sg::read_exr((dir / "uv.exr").string(), {"R", "G", "B"});
  const sg::ImageF xyz = sg::read_exr((dir / "coords.exr").string(), {"R", "G", "B"});
  const sg::ImageF nrm = sg::read_exr((dir / "normal.exr").string(), {"R", "G", "B"});
  std::vector<std::pair<int, int>> px;
  for (int y = 0; y < uv.height; ++y)
    for (int x = 0; x < uv.width; ++x)
      if (uv.at(x, y, 2) > 0.5f) px.emplace_back(x, y);
  sg::Rng rng(7);
  double mw = 0, mp = 0, ml = 0;
  for (int i = 0; i < 1000; ++i) {
    const auto [x, y] =
        px[static_cast<std::size_t>(rng.randint(0, static_cast<int>(px.size()) - 1))];
    const auto p = loc.world_point({uv.at(x, y, 0), uv.at(x, y, 1)});
    if (!p) {
      std::printf("  uv outside the sheet at %d %d\n", x, y);
      continue;
    }
    mw = std::max(mw,
                  (*p - Eigen::Vector3d(xyz.at(x, y, 0), xyz.at(x, y, 1), xyz.at(x, y, 2))).norm());
    mp = std::max(mp, (cam.project(*p) - Eigen::Vector2d(x + 0.5, y + 0.5)).norm());
    ml = std::max(
        ml,
        std::abs(Eigen::Vector3d(nrm.at(x, y, 0), nrm.at(x, y, 1), nrm.at(x, y, 2)).norm() - 1));
  }
  std::printf(
      "exactness (1000 random mask pixels of %zu): max |world(uv) - coords| = %.3g m, "
      "max reprojection = %.3g px, max ||n| - 1| = %.3g\n",
      px.size(), mw, mp, ml);
  // Backward map on the rendered albedo against the flat page (built-in document).
  const sg::ImageF albedo = sg::read_png((dir / "albedo.png").string());
  const sg::ImageF mask = sg::read_png((dir / "mask.png").string());
  const sg::ImageF back = sg::read_exr((dir / "backward.exr").string(), {"R", "G", "B"});
  const sg::ImageF flat = sg::unwarp(albedo, mask, back);
  const sg::ImageF doc = sg::read_png((dir / "document.png").string());
  sg::ImageF ones(doc.width, doc.height, 1);
  std::fill(ones.data.begin(), ones.data.end(), 1.0f);
  const double floor = meta["paper"]["ink_floor"];
  double se = 0;
  long n = 0, visible = 0;
  for (int r = 0; r < back.height; ++r)
    for (int c = 0; c < back.width; ++c) {
      if (back.at(c, r, 2) < 0.5f) continue;
      ++visible;
      const double u = double(c) / (back.width - 1), v = 1.0 - double(r) / (back.height - 1);
      float d[4];
      sg::sample_masked(doc, ones, std::clamp(u * doc.width, 0.5, doc.width - 0.5),
                        std::clamp((1 - v) * doc.height, 0.5, doc.height - 0.5), d);
      for (int k = 0; k < 3; ++k) {
        const double e = sg::linear_to_srgb(meta["paper"]["colour"][k].get<double>() *
                                            (floor + (1 - floor) * sg::srgb_to_linear(d[k])));
        se += (flat.at(c, r, k) - e) * (flat.at(c, r, k) - e);
        ++n;
      }
    }
  std::printf(
      "backward map %dx%d: %ld visible points, PSNR(unwarped albedo, flat page) = %.2f dB\n",
      back.width, back.height, visible, 10 * std::log10(1.0 / (se / n)));
}

struct Args {
  int width = 1024, height = 1440, runs = 5;
  std::uint64_t seed = 1;
  std::string kind = "fold", keep, baseline, scenegen;
  bool reference = true, help = false;
};

/// What `--help` prints (docs/scenegen.md, "Cost").
const char* const USAGE =
    "Usage: scenegen_bench --baseline EXE [--scenegen EXE] [--runs N] [--size WxH] [--seed N]\n"
    "                      [--mesh KIND] [--no-reference] [--keep DIR]\n"
    "Times whole samples of an example sheet (default fold, seed 1, 1024x1440, 5 runs) made by\n"
    "`scenegen render` child processes: the baseline EXE (a scenegen of an older commit), this\n"
    "build on the refined surface (--subdivision 2) and on the raw mesh (--subdivision 0),\n"
    "interleaved run by run, in three modes (final, draft, ground truth only). Prints the median\n"
    "wall and CPU time (scenegen and its POV-Ray children), their ratios to the baseline, whether\n"
    "each configuration's runs gave byte-identical files, the sample's exactness figures and,\n"
    "unless --no-reference, PSNR / SSIM of each final photo against a converged reference.\n"
    "  --scenegen EXE  this build's scenegen (default: the one beside this program)\n"
    "  --keep DIR      keep the samples in DIR\n";

Args parse(int argc, char** argv) {
  Args a;
  a.scenegen = (fs::absolute(fs::path(argv[0])).parent_path() / "scenegen").string();
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (k == "--no-reference") {
      a.reference = false;
      continue;
    }
    if (k == "--help" || k == "-h") {
      a.help = true;
      return a;
    }
    if (i + 1 >= argc) throw std::runtime_error("option '" + k + "' needs a value");
    const char* v = argv[++i];
    if (k == "--size")
      sg::bench::image_size(k, v, a.width, a.height);
    else if (k == "--seed")
      a.seed = sg::bench::whole_number(k, v, 0, 9223372036854775807ULL);
    else if (k == "--runs")
      a.runs = static_cast<int>(sg::bench::whole_number(k, v, 1, 1000));
    else if (k == "--mesh")
      a.kind = v;
    else if (k == "--keep")
      a.keep = v;
    else if (k == "--baseline")
      a.baseline = fs::absolute(v).string();
    else if (k == "--scenegen")
      a.scenegen = fs::absolute(v).string();
    else
      throw std::runtime_error("unknown option '" + k + "'");
  }
  if (a.baseline.empty())
    throw std::runtime_error(
        "--baseline EXE is required (a scenegen built from the baseline commit)");
  for (const auto& [option, exe] :
       {std::pair<std::string, std::string>{"--baseline", a.baseline}, {"--scenegen", a.scenegen}})
    if (!fs::is_regular_file(exe) || ::access(exe.c_str(), X_OK) != 0)
      throw std::runtime_error(option + " '" + exe + "' is not an executable file");
  return a;
}

/// The converged reference photo of a surface level (bench_reference_quality), rendered once.
sg::ImageF reference_photo(const Args& a, const std::string& mesh, int level, const fs::path& dir) {
  sg::SampleOptions o;
  o.mesh_path = mesh;
  o.seed = a.seed;
  o.width = a.width;
  o.height = a.height;
  o.passes = {sg::Pass::image};
  o.surface.level = level;
  o.quality_override = sg::bench::reference_quality();
  o.threads = 0;  // all threads: the reference need not be reproducible
  sg::RunOptions run;
  run.parallel = 1;
  const auto t0 = std::chrono::steady_clock::now();
  sg::render_sample(o, (dir / ("reference_L" + std::to_string(level))).string(), run);
  std::printf("  reference photo, level %d: %.1f s wall\n", level,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  std::fflush(stdout);
  return sg::read_png((dir / ("reference_L" + std::to_string(level)) / "image.png").string());
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  try {
    a = parse(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scenegen_bench: %s\n", e.what());
    return 2;
  }
  try {
    if (a.help) {
      std::fputs(USAGE, stdout);
      return 0;
    }
    const fs::path dir = fs::temp_directory_path() / ("scenegen_bench_" + std::to_string(getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string mesh = (dir / "sheet.obj").string();
    {
      std::ofstream out(mesh);
      sg::write_sheet_obj(out, sg::make_example_sheet(a.kind));
    }
    std::printf(
        "scenegen_bench: %s sheet, %dx%d, seed %llu, %d runs per configuration\n  baseline %s\n  "
        "new      %s\n",
        a.kind.c_str(), a.width, a.height, static_cast<unsigned long long>(a.seed), a.runs,
        a.baseline.c_str(), a.scenegen.c_str());
    const std::vector<Config> configs = {{"baseline", a.baseline, -1},
                                         {"new, level 2", a.scenegen, 2},
                                         {"new, level 0", a.scenegen, 0}};
    const std::vector<Mode> modes = {
        {"final", "final", "all"},
        {"draft", "draft", "all"},
        {"ground truth", "final", "albedo,uv,coords,normal,mask,backward"}};
    const std::string size = std::to_string(a.width) + "x" + std::to_string(a.height);
    std::map<std::string, sg::ImageF> photos;  // first final photo of each configuration
    for (const Mode& m : modes) {
      std::vector<std::vector<Timing>> t(configs.size());
      std::vector<bool> identical(configs.size(), true);
      std::vector<std::map<std::string, std::string>> first(configs.size());
      for (int r = 0; r < a.runs; ++r)
        for (std::size_t c = 0; c < configs.size(); ++c) {
          const fs::path out = dir / ("run_" + std::to_string(c));
          fs::remove_all(out);
          std::vector<std::string> cmd = {configs[c].exe,
                                          "render",
                                          mesh,
                                          "--out",
                                          out.string(),
                                          "--seed",
                                          std::to_string(a.seed),
                                          "--size",
                                          size,
                                          "--quality",
                                          m.quality,
                                          "--passes",
                                          m.passes,
                                          "--quiet"};
          if (configs[c].level >= 0) {
            cmd.push_back("--subdivision");
            cmd.push_back(std::to_string(configs[c].level));
          }
          t[c].push_back(run_command(cmd));
          std::printf("  %-12s %-13s run %d: %6.2f s wall, %6.2f CPU-s\n", m.name.c_str(),
                      configs[c].name.c_str(), r + 1, t[c].back().wall, t[c].back().cpu);
          std::fflush(stdout);
          auto bytes = sample_bytes(out);
          if (r == 0) {
            first[c] = std::move(bytes);
            if (m.name == "final")
              photos[configs[c].name] = sg::read_png((out / "image.png").string());
            if (m.name == "final" && c == 1) {
              exactness(out, mesh);
              if (!a.keep.empty()) {
                fs::remove_all(a.keep);
                fs::copy(out, a.keep, fs::copy_options::recursive);
              }
            }
          } else if (bytes != first[c]) {
            identical[c] = false;
          }
        }
      std::vector<double> w0, c0;
      for (const Timing& x : t[0]) {
        w0.push_back(x.wall);
        c0.push_back(x.cpu);
      }
      std::printf("%s sample, median of %d runs:\n", m.name.c_str(), a.runs);
      for (std::size_t c = 0; c < configs.size(); ++c) {
        std::vector<double> w, cpu;
        for (const Timing& x : t[c]) {
          w.push_back(x.wall);
          cpu.push_back(x.cpu);
        }
        std::printf(
            "  %-13s wall %6.2f s (%.2fx baseline)  CPU %6.2f s (%.2fx)  runs identical: %s\n",
            configs[c].name.c_str(), median(w), median(w) / median(w0), median(cpu),
            median(cpu) / median(c0), a.runs > 1 ? (identical[c] ? "yes" : "NO") : "n/a");
      }
      std::fflush(stdout);
    }
    if (a.reference) {
      // The reference is rendered by this program's own library (the same build as the default
      // --scenegen): the baseline's figure also holds every change of the scene since it
      // (draws, exposure, vignetting), not only its render settings.
      std::printf(
          "final photo against a converged reference of the same surface (%s), rendered by this "
          "build:\n",
          sg::bench::describe(sg::bench::reference_quality()).c_str());
      const sg::ImageF ref2 = reference_photo(a, mesh, 2, dir),
                       ref0 = reference_photo(a, mesh, 0, dir);
      for (const Config& c : configs)
        for (int level : {2, 0}) {
          if (c.level >= 0 && c.level != level) continue;
          const sg::ImageF& ref = level == 2 ? ref2 : ref0;
          std::printf("  %-13s vs reference level %d: PSNR %.2f dB, SSIM %.4f\n", c.name.c_str(),
                      level, sg::bench::psnr(photos[c.name], ref),
                      sg::bench::ssim(photos[c.name], ref));
        }
    }
    fs::remove_all(dir);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scenegen_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
