// scenegen_quality_study: render time against image error of the photo. A converged reference
// (dense radiosity, 5 x 5 area-light samples, fine antialiasing) and candidate presets of one
// sample; for each: wall time of the photo render (one single-threaded POV-Ray process) and
// PSNR / SSIM against the reference. Writes a CSV.
//   scenegen_quality_study [--size WxH] [--seed N] [--mesh fold|cylinder|bump|flat] [--subdivision
//   L]
//                          [--csv FILE] [--reference FILE.png] [--match TEXT]
//   scenegen_quality_study --compare REFERENCE.png IMAGE.png
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bench_args.hpp"
#include "image_error.hpp"
#include "scenegen/errors.hpp"
#include "scenegen/example_sheets.hpp"
#include "scenegen/image_io.hpp"
#include "scenegen/job.hpp"

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
  q.area_jitter = false;
  q.antialias_threshold = 0.1;
  q.antialias_depth = 1;
  q.bands = 1;
  return q;
}

/// The final preset before issue 19's cheaper photo (commit 9b9e633): 2 x 2 area samples,
/// antialiasing threshold 0.9 at depth 2, radiosity nearest_count 5 and pretrace to 0.02.
sg::QualitySettings final_9b9e633() {
  sg::QualitySettings q = sg::quality_settings(sg::Quality::final);
  q.area_samples = 2;
  q.area_adaptive = 1;
  q.area_jitter = false;
  q.dim_light_share = 0.0;
  q.antialias_method = 2;
  q.antialias_threshold = 0.9;
  q.antialias_depth = 2;
  q.radiosity_nearest = 5;
  q.radiosity_pretrace_end = 0.02;
  return q;
}

/// The final preset of commit 4731a3c (issue 19's first cheaper photo): 9b9e633's with
/// radiosity nearest_count 2, pretrace to 0.04 and antialiasing threshold 0.8.
sg::QualitySettings final_4731a3c() {
  sg::QualitySettings q = final_9b9e633();
  q.radiosity_nearest = 2;
  q.radiosity_pretrace_end = 0.04;
  q.antialias_threshold = 0.8;
  return q;
}

std::vector<Preset> presets() {
  std::vector<Preset> p;
  p.push_back({"draft", sg::quality_settings(sg::Quality::draft)});
  const sg::QualitySettings old = previous_final();
  p.push_back({"final (180441f)", old});
  p.push_back({"final (9b9e633)", final_9b9e633()});
  p.push_back({"final (4731a3c)", final_4731a3c()});
  p.push_back({"final (new)", sg::quality_settings(sg::Quality::final)});
  // The final preset before its area lights were jittered (commit 4939aeb): 2 x 2 samples on a
  // grid.
  sg::QualitySettings grid = sg::quality_settings(sg::Quality::final);
  grid.area_jitter = false;
  p.push_back({"final (4939aeb)", grid});
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
  q = final_9b9e633();
  q.bands = 1;
  p.push_back({"final (9b9e633), 1 band", q});
  // Issue 19's cheaper photo: fewer shadow rays for dim lights, antialiasing method 1.
  const sg::QualitySettings fin = final_9b9e633();
  q = fin;
  q.dim_light_share = 0.2;
  q.dim_area_samples = 1;
  p.push_back({"final, lights < 20% as point lights", q});
  q.dim_area_samples = 0;
  p.push_back({"final, lights < 20% shadowless", q});
  q = fin;
  q.area_samples = 1;
  p.push_back({"final, point lights", q});
  q = fin;
  q.antialias_method = 1;
  p.push_back({"final, AA method 1 0.9 depth 2", q});
  q.antialias_threshold = 0.3;
  p.push_back({"final, AA method 1 0.3 depth 2", q});
  q = fin;
  q.dim_light_share = 0.2;
  q.dim_area_samples = 1;
  q.antialias_threshold = 0.6;
  p.push_back({"lights < 20% point, AA 0.6 depth 2", q});
  q = fin;
  q.radiosity_nearest = 2;
  p.push_back({"final, radiosity nearest 2", q});
  q.radiosity_pretrace_end = 0.04;
  p.push_back({"final, radiosity nearest 2, pretrace to 0.04", q});
  q.dim_light_share = 0.2;
  q.dim_area_samples = 1;
  p.push_back({"lights < 20% point, radiosity nearest 2, pretrace to 0.04", q});
  q.antialias_threshold = 0.6;
  p.push_back({"lights < 20% point, radiosity nearest 2, pretrace to 0.04, AA 0.6", q});
  q = fin;
  q.radiosity_nearest = 1;
  q.radiosity_pretrace_end = 0.04;
  p.push_back({"final, radiosity nearest 1, pretrace to 0.04", q});
  q = fin;
  q.radiosity_nearest = 2;
  q.radiosity_pretrace_end = 0.08;
  p.push_back({"final, radiosity nearest 2, pretrace 0.08 only", q});
  q = fin;
  q.radiosity_nearest = 2;
  q.radiosity_pretrace_end = 0.04;
  q.antialias_threshold = 0.8;
  p.push_back({"radiosity nearest 2, pretrace to 0.04, AA 0.8", q});
  q.antialias_threshold = 0.7;
  p.push_back({"radiosity nearest 2, pretrace to 0.04, AA 0.7", q});
  // Radiosity nearest_count 1 (each lookup takes its nearest sample) with the antialiasing pair.
  q = final_4731a3c();
  q.radiosity_nearest = 1;
  for (const double t : {0.9, 0.8, 0.7}) {
    q.antialias_threshold = t;
    char name[96];
    std::snprintf(name, sizeof name, "radiosity nearest 1, pretrace to 0.04, AA %.1f", t);
    p.push_back({name, q});
  }
  // Smooth penumbrae: the best preset, and its 3 x 3 grid at adaptive depth 0 without jitter.
  p.push_back({"best", sg::quality_settings(sg::Quality::best)});
  q = sg::quality_settings(sg::Quality::best);
  q.area_jitter = false;
  p.push_back({"best without jitter", q});
  return p;
}

/// Render the photo with `q`; returns its wall time [s] and the image.
double render(sg::SampleOptions o, const sg::QualitySettings& q, const fs::path& out,
              sg::ImageF& image) {
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
  std::string match;          // --match TEXT: only the presets whose name contains TEXT
  std::string reference_png;  // --reference FILE: read the reference from FILE if it exists, else
                              // render and write it there
  // --compare REF.png IMAGE.png: PSNR / SSIM of one photo against a reference (e.g. a photo
  // rendered with edited templates, `scenegen render --templates`, against a kept reference).
  if (argc == 4 && !std::strcmp(argv[1], "--compare")) {
    try {
      const sg::ImageF ref = sg::read_png(argv[2]), im = sg::read_png(argv[3]);
      std::printf("PSNR %.2f dB  SSIM %.4f\n", sg::bench::psnr(im, ref), sg::bench::ssim(im, ref));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "scenegen_quality_study: %s\n", e.what());
      return 1;
    }
    return 0;
  }
  static const char* usage =
      "usage: scenegen_quality_study [--size WxH] [--seed N] [--mesh fold|cylinder|bump|flat] "
      "[--subdivision L]\n"
      "                              [--csv FILE] [--reference FILE.png] [--match TEXT]\n"
      "       scenegen_quality_study --compare REFERENCE.png IMAGE.png\n"
      "Renders the photo of one sample (scenegen example MESH, default fold, seed 1, 256x360, "
      "level 2) with a\n"
      "converged reference setting and with candidate presets, and writes each preset's photo "
      "render time,\n"
      "PSNR and SSIM against the reference to the CSV (default scenegen_quality.csv). --reference "
      "FILE reads\n"
      "the reference from FILE if it exists, else renders it and writes it there; --match TEXT "
      "renders only\n"
      "the presets whose name contains TEXT. --compare prints PSNR and SSIM of IMAGE against "
      "REFERENCE.\n";
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
      std::fputs(usage, stdout);
      return 0;
    }
  for (int i = 1; i < argc; i += 2) {
    if (i + 1 >= argc) {
      std::fprintf(stderr, "scenegen_quality_study: option '%s' needs a value\n%s", argv[i], usage);
      return 2;
    }
    try {
      if (!std::strcmp(argv[i], "--size"))
        sg::bench::image_size("--size", argv[i + 1], width, height);
      else if (!std::strcmp(argv[i], "--seed"))
        seed = sg::bench::whole_number("--seed", argv[i + 1], 0, 9223372036854775807ULL);
      else if (!std::strcmp(argv[i], "--mesh"))
        kind = argv[i + 1];
      else if (!std::strcmp(argv[i], "--csv"))
        csv = argv[i + 1];
      else if (!std::strcmp(argv[i], "--subdivision"))
        level = static_cast<int>(sg::bench::whole_number("--subdivision", argv[i + 1], 0, 4));
      else if (!std::strcmp(argv[i], "--reference"))
        reference_png = argv[i + 1];
      else if (!std::strcmp(argv[i], "--match"))
        match = argv[i + 1];
      else {
        std::fprintf(stderr, "scenegen_quality_study: unknown option '%s'\n%s", argv[i], usage);
        return 2;
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "scenegen_quality_study: %s\n", e.what());
      return 2;
    }
  }
  try {
    const fs::path dir = fs::temp_directory_path() / ("scenegen_quality_" + std::to_string(seed));
    fs::remove_all(dir);
    fs::create_directories(dir);
    sg::SampleOptions o;
    o.mesh_path = (dir / "sheet.obj").string();
    {
      std::ofstream out(o.mesh_path);
      sg::write_sheet_obj(out, sg::make_example_sheet(kind));
    }
    o.seed = seed;
    o.width = width;
    o.height = height;
    o.passes = {sg::Pass::image};
    o.surface.level = level;
    sg::ImageF ref;
    double ref_time = NAN;
    if (!reference_png.empty() && fs::exists(reference_png)) {
      ref = sg::read_png(reference_png);
      std::printf("reference: read %s\n", reference_png.c_str());
    } else {
      ref_time = render(o, sg::bench::reference_quality(), dir / "reference", ref);
      std::printf("reference: %.2f s\n", ref_time);
      if (!reference_png.empty()) fs::copy_file(dir / "reference" / "image.png", reference_png);
    }
    const std::string tmp = csv + ".partial";
    std::ofstream out(tmp);
    out << "preset,seconds,psnr_db,ssim,radiosity,radiosity_count,radiosity_error,area_samples,"
           "area_adaptive,antialias,antialias_threshold,antialias_depth,bands,dim_light_share,dim_"
           "area_samples,antialias_method,radiosity_nearest,radiosity_pretrace_end,area_jitter\n";
    const auto row = [&](const std::string& name, const sg::QualitySettings& q, double sec,
                         double p, double s) {
      out << '"' << name << "\"," << sec << ',' << p << ',' << s << ',' << q.radiosity << ','
          << q.radiosity_count << ',' << q.radiosity_error << ',' << q.area_samples << ','
          << q.area_adaptive << ',' << q.antialias << ',' << q.antialias_threshold << ','
          << q.antialias_depth << ',' << q.bands << ',' << q.dim_light_share << ','
          << q.dim_area_samples << ',' << q.antialias_method << ',' << q.radiosity_nearest << ','
          << q.radiosity_pretrace_end << ',' << q.area_jitter << '\n';
      std::printf("%-28s %7.2f s  PSNR %6.2f dB  SSIM %.4f\n", name.c_str(), sec, p, s);
    };
    for (const Preset& p : presets()) {
      if (p.name.find(match) == std::string::npos) continue;
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
