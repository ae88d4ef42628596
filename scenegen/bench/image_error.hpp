#pragma once
/// Image error measures and the converged reference settings shared by scenegen_bench and
/// scenegen_quality_study.
#include <cmath>
#include <cstdio>
#include <string>

#include "scenegen/image_io.hpp"
#include "scenegen/pov_writer.hpp"

namespace papersim::scenegen::bench {

/// The converged reference of the photo: every setting well past the presets (dense radiosity,
/// 5 x 5 area-light samples refined 3 times, fine antialiasing), rendered whole (1 band).
inline QualitySettings reference_quality() {
  QualitySettings q = quality_settings(Quality::final);
  q.radiosity_count = 600;
  q.radiosity_error = 0.25;
  q.radiosity_nearest = 5;
  q.radiosity_pretrace_end = 0.02;
  q.area_samples = 5;
  q.area_adaptive = 3;
  q.area_jitter = false;
  q.dim_light_share = 0.0;
  q.antialias_method = 2;
  q.antialias_threshold = 0.02;
  q.antialias_depth = 3;
  q.bands = 1;
  return q;
}

/// One line describing the settings of the lit passes.
inline std::string describe(const QualitySettings& q) {
  char buf[256];
  std::snprintf(
      buf, sizeof buf,
      "radiosity %s count %d error %.2g, area %dx%d adaptive %d%s, AA %s %.2g depth %d, %d band(s)",
      q.radiosity ? "on" : "off", q.radiosity_count, q.radiosity_error, q.area_samples,
      q.area_samples, q.area_adaptive, q.area_jitter ? " jitter" : "", q.antialias ? "on" : "off",
      q.antialias_threshold, q.antialias_depth, q.bands);
  return buf;
}

/// PSNR [dB] of two images of the same size, values in [0, 1], every channel.
inline double psnr(const ImageF& a, const ImageF& b) {
  double se = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i)
    se += (a.data[i] - b.data[i]) * (a.data[i] - b.data[i]);
  return 10 * std::log10(1.0 / (se / static_cast<double>(a.data.size())));
}

inline double luminance(const ImageF& im, int x, int y) {
  return (im.at(x, y, 0) + im.at(x, y, 1) + im.at(x, y, 2)) / 3.0;
}

/// Mean SSIM of the luminance (Wang et al. 2004: 11 x 11 Gaussian window, sigma 1.5,
/// C1 = (0.01)^2, C2 = (0.03)^2 for values in [0, 1]).
inline double ssim(const ImageF& a, const ImageF& b) {
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
  return total / static_cast<double>(n);
}

}  // namespace papersim::scenegen::bench
