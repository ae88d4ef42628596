// scenegen_quality_study: render time against image error of the photo. A converged reference
// (dense radiosity, 5 x 5 area-light samples, fine antialiasing) and candidate presets of one
// sample; for each: wall time of the photo render (one single-threaded POV-Ray process) and
// PSNR / SSIM against the reference. Writes a CSV.
//   scenegen_quality_study [--size WxH] [--seed N] [--mesh fold|cylinder|bump|flat] [--csv FILE]
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

namespace fs = std::filesystem;
namespace sg = papersim::scenegen;

namespace {

struct Preset {
  std::string name;
  sg::QualitySettings q;
};

std::vector<Preset> presets() {
  std::vector<Preset> p;
  p.push_back({"draft", sg::quality_settings(sg::Quality::draft)});
  const sg::QualitySettings fin = sg::quality_settings(sg::Quality::final);
  p.push_back({"final (today)", fin});
  sg::QualitySettings q = fin;
  q.antialias = false;
  p.push_back({"final, no antialiasing", q});
  q = fin;
  q.radiosity_count = 100;
  p.push_back({"final, radiosity count 100", q});
  q = fin;
  q.radiosity_error = 0.8;
  p.push_back({"final, error bound 0.8", q});
  q = fin;
  q.area_samples = 2;
  p.push_back({"final, 2x2 area samples", q});
  q = fin;
  q.area_samples = 5;
  p.push_back({"final, 5x5 area samples", q});
  return p;
}

/// The converged reference: every setting well past the presets.
sg::QualitySettings reference() {
  sg::QualitySettings q = sg::quality_settings(sg::Quality::final);
  q.radiosity_count = 600;
  q.radiosity_error = 0.25;
  q.area_samples = 5;
  q.area_adaptive = 3;
  q.antialias_threshold = 0.02;
  q.antialias_depth = 3;
  return q;
}

double luminance(const sg::ImageF& im, int x, int y) {
  return (im.at(x, y, 0) + im.at(x, y, 1) + im.at(x, y, 2)) / 3.0;
}

double psnr(const sg::ImageF& a, const sg::ImageF& b) {
  double se = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) se += (a.data[i] - b.data[i]) * (a.data[i] - b.data[i]);
  return 10 * std::log10(1.0 / (se / a.data.size()));
}

/// Mean SSIM of the luminance (Wang et al. 2004: 11 x 11 Gaussian window, sigma 1.5,
/// C1 = (0.01)^2, C2 = (0.03)^2 for values in [0, 1]).
double ssim(const sg::ImageF& a, const sg::ImageF& b) {
  const int r = 5;
  double w[11], wsum = 0;
  for (int k = -r; k <= r; ++k) wsum += (w[k + r] = std::exp(-k * k / (2 * 1.5 * 1.5)));
  const double c1 = 1e-4, c2 = 9e-4;
  double total = 0;
  long n = 0;
  for (int y = r; y + r < a.height; ++y)
    for (int x = r; x + r < a.width; ++x) {
      double ma = 0, mb = 0, va = 0, vb = 0, cov = 0;
      for (int j = -r; j <= r; ++j)
        for (int i = -r; i <= r; ++i) {
          const double g = w[i + r] * w[j + r] / (wsum * wsum);
          const double pa = luminance(a, x + i, y + j), pb = luminance(b, x + i, y + j);
          ma += g * pa;
          mb += g * pb;
          va += g * pa * pa;
          vb += g * pb * pb;
          cov += g * pa * pb;
        }
      va -= ma * ma;
      vb -= mb * mb;
      cov -= ma * mb;
      total += (2 * ma * mb + c1) * (2 * cov + c2) / ((ma * ma + mb * mb + c1) * (va + vb + c2));
      ++n;
    }
  return total / n;
}

/// Render the photo with `q`; returns its wall time [s] and the image.
double render(sg::SampleOptions o, const sg::QualitySettings& q, const fs::path& out, sg::ImageF& image) {
  o.quality_override = q;
  const sg::RunReport report = sg::render_sample(o, out.string(), sg::RunOptions{});
  image = sg::read_png((out / "image.png").string());
  for (const auto& [name, sec] : report.seconds)
    if (name == "image") return sec;
  return report.total();
}

}  // namespace

int main(int argc, char** argv) {
  int width = 256, height = 360;
  std::uint64_t seed = 1;
  std::string kind = "fold", csv = "scenegen_quality.csv";
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--size")) std::sscanf(argv[i + 1], "%dx%d", &width, &height);
    else if (!std::strcmp(argv[i], "--seed")) seed = std::stoull(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--mesh")) kind = argv[i + 1];
    else if (!std::strcmp(argv[i], "--csv")) csv = argv[i + 1];
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
    sg::ImageF ref;
    const double ref_time = render(o, reference(), dir / "reference", ref);
    std::printf("reference: %.2f s\n", ref_time);
    const std::string tmp = csv + ".partial";
    std::ofstream out(tmp);
    out << "preset,seconds,psnr_db,ssim,radiosity,radiosity_count,radiosity_error,area_samples,antialias\n";
    const auto row = [&](const std::string& name, const sg::QualitySettings& q, double sec, double p, double s) {
      out << '"' << name << "\"," << sec << ',' << p << ',' << s << ',' << q.radiosity << ',' << q.radiosity_count
          << ',' << q.radiosity_error << ',' << q.area_samples << ',' << q.antialias << '\n';
      std::printf("%-28s %7.2f s  PSNR %6.2f dB  SSIM %.4f\n", name.c_str(), sec, p, s);
    };
    for (const Preset& p : presets()) {
      sg::ImageF im;
      const double sec = render(o, p.q, dir / "preset", im);
      row(p.name, p.q, sec, psnr(im, ref), ssim(im, ref));
      fs::remove_all(dir / "preset");
    }
    row("reference", reference(), ref_time, INFINITY, 1.0);
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
