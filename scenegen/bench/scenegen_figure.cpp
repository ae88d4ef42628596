// scenegen_figure: the figures of the docs from rendered sample folders.
//   scenegen_figure passes SAMPLE_DIR --out FILE.png [--shrink N]
//     one sample: photo, albedo, shading, UV (R = u, G = v, B = mask), normals (0.5 (n + 1)),
//     world coordinates (normalised over the sheet) side by side (docs/images/scenegen_sample.png)
//   scenegen_figure photos DIR... --out FILE.png [--shrink N] [--columns C]
//     the photos of several samples in a grid (before / after comparisons)
// Each panel is shrunk by an integer factor (box filter); panels are 4 pixels apart on white.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_args.hpp"
#include "scenegen/image_io.hpp"

namespace fs = std::filesystem;
namespace sg = papersim::scenegen;

namespace {

constexpr int GAP = 4;  // [pixels]

/// Box-filter shrink by `n` (values averaged per channel), keeping 3 channels.
sg::ImageF shrink(const sg::ImageF& in, int n) {
  sg::ImageF out(in.width / n, in.height / n, 3);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < 3; ++c) {
        double s = 0;
        for (int j = 0; j < n; ++j)
          for (int i = 0; i < n; ++i)
            s += in.at(x * n + i, y * n + j, std::min(c, in.channels - 1));
        out.at(x, y, c) = static_cast<float>(s / (n * n));
      }
  return out;
}

/// Panels side by side in a grid of `columns`, white gaps.
sg::ImageF grid(const std::vector<sg::ImageF>& panels, int columns) {
  const int w = panels[0].width, h = panels[0].height;
  const int rows = (static_cast<int>(panels.size()) + columns - 1) / columns;
  sg::ImageF out(columns * w + (columns - 1) * GAP, rows * h + (rows - 1) * GAP, 3);
  std::fill(out.data.begin(), out.data.end(), 1.0f);
  for (std::size_t k = 0; k < panels.size(); ++k) {
    const int x0 = static_cast<int>(k % columns) * (w + GAP),
              y0 = static_cast<int>(k / columns) * (h + GAP);
    for (int y = 0; y < std::min(h, panels[k].height); ++y)
      for (int x = 0; x < std::min(w, panels[k].width); ++x)
        for (int c = 0; c < 3; ++c) out.at(x0 + x, y0 + y, c) = panels[k].at(x, y, c);
  }
  return out;
}

/// Normals 0.5 (n + 1) and coordinates normalised to [0, 1] per axis over the sheet; 0 off it.
sg::ImageF visualise(const sg::ImageF& v, const sg::ImageF& uv, bool normals) {
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
  for (int y = 0; y < v.height; ++y)
    for (int x = 0; x < v.width; ++x)
      if (uv.at(x, y, 2) > 0.5f)
        for (int c = 0; c < 3; ++c) {
          lo[c] = std::min(lo[c], v.at(x, y, c));
          hi[c] = std::max(hi[c], v.at(x, y, c));
        }
  sg::ImageF out(v.width, v.height, 3);
  for (int y = 0; y < v.height; ++y)
    for (int x = 0; x < v.width; ++x)
      for (int c = 0; c < 3; ++c) {
        if (uv.at(x, y, 2) <= 0.5f) continue;
        const float a = v.at(x, y, c);
        out.at(x, y, c) =
            normals ? 0.5f * (a + 1.0f) : (a - lo[c]) / std::max(hi[c] - lo[c], 1e-9f);
      }
  return out;
}

std::vector<sg::ImageF> pass_panels(const fs::path& dir) {
  const sg::ImageF uv = sg::read_exr((dir / "uv.exr").string(), {"R", "G", "B"});
  return {sg::read_png((dir / "image.png").string()),
          sg::read_png((dir / "albedo.png").string()),
          sg::read_png((dir / "shading.png").string()),
          uv,
          visualise(sg::read_exr((dir / "normal.exr").string(), {"R", "G", "B"}), uv, true),
          visualise(sg::read_exr((dir / "coords.exr").string(), {"R", "G", "B"}), uv, false)};
}

}  // namespace

constexpr const char* usage =
    "usage: scenegen_figure passes SAMPLE_DIR --out FILE.png [--shrink N]\n"
    "       scenegen_figure photos DIR... --out FILE.png [--shrink N] [--columns C]\n"
    "A figure of one sample's photo, albedo, shading, UV, normals and world coordinates side by\n"
    "side, or of the photos of several samples in a grid; --shrink N averages N x N pixels\n"
    "(default 4), --columns C puts C photos in a row (default all).\n";

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
      std::fputs(usage, stdout);
      return 0;
    }
  if (argc < 3 || (std::strcmp(argv[1], "passes") && std::strcmp(argv[1], "photos"))) {
    std::fputs(usage, stderr);
    return 2;
  }
  const bool passes = !std::strcmp(argv[1], "passes");
  std::vector<std::string> dirs;
  std::string out;
  int n = 4, columns = 0;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if ((a == "--out" || a == "--shrink" || a == "--columns") && i + 1 >= argc) {
      std::fprintf(stderr, "scenegen_figure: option '%s' needs a value\n", a.c_str());
      return 2;
    }
    if (a == "--out")
      out = argv[++i];
    else if (a == "--shrink" || a == "--columns") {
      try {
        (a == "--shrink" ? n : columns) =
            static_cast<int>(sg::bench::whole_number(a, argv[++i], 1, 1000));
      } catch (const std::exception& e) {
        std::fprintf(stderr, "scenegen_figure: %s\n", e.what());
        return 2;
      }
    } else if (a.rfind("--", 0) == 0) {
      std::fprintf(stderr, "scenegen_figure: unknown option '%s'\n", a.c_str());
      return 2;
    } else
      dirs.push_back(a);
  }
  if (out.empty() || dirs.empty() || (passes && dirs.size() != 1)) {
    std::fprintf(stderr, "scenegen_figure: give --out FILE.png and %s\n",
                 passes ? "one sample folder" : "sample folders");
    return 2;
  }
  try {
    std::vector<sg::ImageF> panels;
    if (passes)
      panels = pass_panels(dirs[0]);
    else
      for (const auto& d : dirs)
        panels.push_back(sg::read_png((fs::path(d) / "image.png").string()));
    for (auto& p : panels) p = shrink(p, n);
    const int cols = columns > 0 ? columns : static_cast<int>(panels.size());
    const std::string tmp = out + ".partial.png";
    sg::write_png(tmp, grid(panels, cols), 8);
    fs::rename(tmp, out);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scenegen_figure: %s\n", e.what());
    return 1;
  }
  return 0;
}
