// scenegen_bench: render cost at full resolution (default 1024 x 1440) on this machine, plus
// the exactness and backward-map figures on the full-resolution sample with the built-in page.
//   scenegen_bench [--size WxH] [--seed N] [--mesh cylinder|fold|bump|flat] [--keep DIR]
// 1. each pass timed alone (one POV-Ray process with all threads, draft and final photo);
// 2. a whole final-quality sample as `scenegen render` runs it (one single-threaded POV-Ray
//    process per core, reproducible), wall time.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "scenegen/decode.hpp"
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

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void exactness(const fs::path& dir, const std::string& mesh_path) {
  std::ifstream in(dir / "meta.json");
  const auto meta = nlohmann::json::parse(in);
  // Exact for the surface rendered: the mesh refined at the recorded level.
  sg::SurfaceParams surface;
  surface.level = meta["surface"]["level"];
  const auto& st = meta["stage"];
  const sg::SheetMesh mesh = sg::lift_above_plane(sg::refine_surface(sg::read_sheet_obj(mesh_path), surface),
                                                  Eigen::Vector3d(st["origin"][0], st["origin"][1], st["origin"][2]),
                                                  Eigen::Vector3d(st["up"][0], st["up"][1], st["up"][2]));
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
    const auto [x, y] = px[static_cast<std::size_t>(rng.randint(0, static_cast<int>(px.size()) - 1))];
    const auto p = loc.world_point({uv.at(x, y, 0), uv.at(x, y, 1)});
    if (!p) { std::printf("  uv outside the sheet at %d %d\n", x, y); continue; }
    mw = std::max(mw, (*p - Eigen::Vector3d(xyz.at(x, y, 0), xyz.at(x, y, 1), xyz.at(x, y, 2))).norm());
    mp = std::max(mp, (cam.project(*p) - Eigen::Vector2d(x + 0.5, y + 0.5)).norm());
    ml = std::max(ml, std::abs(Eigen::Vector3d(nrm.at(x, y, 0), nrm.at(x, y, 1), nrm.at(x, y, 2)).norm() - 1));
  }
  std::printf("exactness (1000 random mask pixels of %zu): max |world(uv) - coords| = %.3g m, "
              "max reprojection = %.3g px, max ||n| - 1| = %.3g\n", px.size(), mw, mp, ml);
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
  std::printf("backward map %dx%d: %ld visible points, PSNR(unwarped albedo, flat page) = %.2f dB\n",
              back.width, back.height, visible, 10 * std::log10(1.0 / (se / n)));
}

}  // namespace

int main(int argc, char** argv) {
  int width = 1024, height = 1440;
  std::uint64_t seed = 1;
  std::string kind = "cylinder", keep;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--size")) std::sscanf(argv[i + 1], "%dx%d", &width, &height);
    else if (!std::strcmp(argv[i], "--seed")) seed = std::stoull(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--mesh")) kind = argv[i + 1];
    else if (!std::strcmp(argv[i], "--keep")) keep = argv[i + 1];
  }
  try {
    const fs::path dir = fs::temp_directory_path() / ("scenegen_bench_" + std::to_string(seed));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string mesh = (dir / "sheet.obj").string();
    { std::ofstream out(mesh); sg::write_sheet_obj(out, sg::make_example_sheet(kind)); }
    std::printf("scenegen_bench: %s sheet, %dx%d, seed %llu, %u cores\n", kind.c_str(), width, height,
                static_cast<unsigned long long>(seed), std::thread::hardware_concurrency());
    sg::SampleOptions o;
    o.mesh_path = mesh;
    o.seed = seed;
    o.width = width;
    o.height = height;
    // 1. Each pass alone, one POV-Ray process with all threads.
    sg::RunOptions one;
    one.parallel = 1;
    for (sg::Quality q : {sg::Quality::draft, sg::Quality::final}) {
      o.quality = q;
      o.threads = 0;
      o.passes = q == sg::Quality::draft ? sg::all_passes() : std::vector<sg::Pass>{sg::Pass::image, sg::Pass::shading};
      const fs::path job = dir / ("job_" + sg::quality_name(q));
      sg::prepare_job(o, job.string());
      const auto report = sg::run_job(job.string(), one);
      double exact = 0;
      for (const auto& [name, sec] : report.seconds) {
        const bool gt = name != "image" && name != "shading" && name != "document";
        if (gt) exact += sec;
        std::printf("  %-6s %-12s %6.2f s%s\n", sg::quality_name(q).c_str(), name.c_str(), sec,
                    gt ? "  (ground truth)" : "");
      }
      if (q == sg::Quality::draft) std::printf("  all ground-truth renders together: %.2f s\n", exact);
    }
    // 2. A whole final sample as `scenegen render` runs it.
    o.quality = sg::Quality::final;
    o.threads = 1;
    o.passes = sg::all_passes();
    const auto t0 = std::chrono::steady_clock::now();
    const auto report = sg::render_sample(o, (dir / "sample").string(), sg::RunOptions{});
    const double wall = seconds_since(t0);
    std::printf("whole final sample (render = prepare + POV-Ray + finish), wall: %.2f s\n", wall);
    for (const auto& [name, sec] : report.seconds) std::printf("    %-12s %6.2f s (1 thread)\n", name.c_str(), sec);
    exactness(dir / "sample", mesh);
    if (!keep.empty()) {
      fs::remove_all(keep);
      fs::rename(dir / "sample", keep);
    }
    fs::remove_all(dir);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scenegen_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
