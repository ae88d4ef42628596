// scenegen_quality_study: render time against image error of the photo. A converged reference
// (dense radiosity, 5 x 5 area-light samples, fine antialiasing) and candidate presets of one
// sample; for each: wall time of the photo render (one single-threaded POV-Ray process) and
// PSNR / SSIM against the reference. Writes a CSV.
//   scenegen_quality_study [--size WxH] [--seed N] [--mesh fold|cylinder|bump|flat] [--subdivision L]
//                          [--csv FILE]
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "scenegen/errors.hpp"
#include "scenegen/example_sheets.hpp"
#include "scenegen/image_io.hpp"
#include "scenegen/job.hpp"
#include "image_error.hpp"

namespace fs = std::filesystem;
namespace sg = papersim::scenegen;

namespace {

struct Preset {
  std::string name;
  sg::QualitySettings q;
};

/// Today's final preset before this study (commit 180441f): 3 x 3 area samples, antialiasing
/// threshold 0.1 at depth 1, the photo rendered whole.
sg::QualitySettings previous_final() {
  sg::QualitySettings q = sg::quality_settings(sg::Quality::final);
  q.area_samples = 3;
  q.area_adaptive = 1;
  q.antialias_threshold = 0.1;
  q.antialias_depth = 1;
  q.bands = 1;
  return q;
}

std::vector<Preset> presets() {
  std::vector<Preset> p;
  p.push_back({"draft", sg::quality_settings(sg::Quality::draft)});
  const sg::QualitySettings old = previous_final();
  p.push_back({"final (180441f)", old});
  p.push_back({"final (new)", sg::quality_settings(sg::Quality::final)});
  sg::QualitySettings q = old;
  q.antialias = false;
  p.push_back({"180441f, no antialiasing", q});
  q = old;
  q.radiosity_count = 100;
  p.push_back({"180441f, radiosity count 100", q});
  q = old;
  q.area_samples = 2;
  p.push_back({"180441f, 2x2 area samples", q});
  q = old;
  q.area_adaptive = 0;
  p.push_back({"180441f, 3x3 area adaptive 0", q});
  q = old;
  q.area_samples = 2;
  q.antialias_threshold = 0.6;
  q.antialias_depth = 2;
  p.push_back({"2x2 area, AA 0.6 depth 2", q});
  q.antialias_threshold = 0.3;
  p.push_back({"2x2 area, AA 0.3 depth 2", q});
  q = sg::quality_settings(sg::Quality::final);
  q.bands = 1;
  p.push_back({"final (new), 1 band", q});
  return p;
}

/// Render the photo with `q`; returns its wall time [s] and the image.
double render(sg::SampleOptions o, const sg::QualitySettings& q, const fs::path& out, sg::ImageF& image) {
  o.quality_override = q;
  const sg::RunReport report = sg::render_sample(o, out.string(), sg::RunOptions{});
  image = sg::read_png((out / "image.png").string());
  // The photo's POV-Ray time, summed over its row bands (each one single-threaded process).
  double photo = 0;
  for (const auto& [name, sec] : report.seconds)
    if (name.rfind("image", 0) == 0) photo += sec;
  return photo;
}

}  // namespace

int main(int argc, char** argv) {
  int width = 256, height = 360;
  std::uint64_t seed = 1;
  std::string kind = "fold", csv = "scenegen_quality.csv";
  int level = 2;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--size")) std::sscanf(argv[i + 1], "%dx%d", &width, &height);
    else if (!std::strcmp(argv[i], "--seed")) seed = std::stoull(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--mesh")) kind = argv[i + 1];
    else if (!std::strcmp(argv[i], "--csv")) csv = argv[i + 1];
    else if (!std::strcmp(argv[i], "--subdivision")) level = std::atoi(argv[i + 1]);
    else {
      std::fprintf(stderr, "scenegen_quality_study: unknown option '%s'\n", argv[i]);
      return 2;
    }
  }
  try {
    const fs::path dir = fs::temp_directory_path() / ("scenegen_quality_" + std::to_string(seed));
    fs::remove_all(dir);
    fs::create_directories(dir);
    sg::SampleOptions o;
    o.mesh_path = (dir / "sheet.obj").string();
    { std::ofstream out(o.mesh_path); sg::write_sheet_obj(out, sg::make_example_sheet(kind)); }
    o.seed = seed;
    o.width = width;
    o.height = height;
    o.passes = {sg::Pass::image};
    o.surface.level = level;
    sg::ImageF ref;
    const double ref_time = render(o, sg::bench::reference_quality(), dir / "reference", ref);
    std::printf("reference: %.2f s\n", ref_time);
    const std::string tmp = csv + ".partial";
    std::ofstream out(tmp);
    out << "preset,seconds,psnr_db,ssim,radiosity,radiosity_count,radiosity_error,area_samples,area_adaptive,antialias,antialias_threshold,antialias_depth,bands\n";
    const auto row = [&](const std::string& name, const sg::QualitySettings& q, double sec, double p, double s) {
      out << '"' << name << "\"," << sec << ',' << p << ',' << s << ',' << q.radiosity << ',' << q.radiosity_count
          << ',' << q.radiosity_error << ',' << q.area_samples << ',' << q.area_adaptive << ',' << q.antialias
          << ',' << q.antialias_threshold << ',' << q.antialias_depth << ',' << q.bands << '\n';
      std::printf("%-28s %7.2f s  PSNR %6.2f dB  SSIM %.4f\n", name.c_str(), sec, p, s);
    };
    for (const Preset& p : presets()) {
      sg::ImageF im;
      const double sec = render(o, p.q, dir / "preset", im);
      row(p.name, p.q, sec, sg::bench::psnr(im, ref), sg::bench::ssim(im, ref));
      fs::remove_all(dir / "preset");
    }
    row("reference", sg::bench::reference_quality(), ref_time, INFINITY, 1.0);
    if (!out.flush()) throw sg::IoError("cannot write '" + tmp + "'");
    out.close();
    fs::rename(tmp, csv);
    fs::remove_all(dir);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scenegen_quality_study: %s\n", e.what());
    return 1;
  }
  return 0;
}
