// --layout syntheticdoc: the files read back with the reference's conventions (names, shape,
// dtype, value range, grid orientation) and agree with our own passes of the same sample.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "scenegen/errors.hpp"
#include "scenegen/image_io.hpp"
#include "scenegen/job.hpp"
#include "test_support.hpp"

namespace papersim::scenegen {
namespace {
namespace fs = std::filesystem;

/// A .npy read the way numpy does: magic, version 1.0 header, then raw data.
struct Npy {
  std::string header;
  std::vector<float> data;
};
Npy read_npy(const fs::path& path) {
  const std::string bytes = test::file_bytes(path);
  EXPECT_EQ(bytes.substr(0, 6), "\x93NUMPY");
  const std::size_t len =
      static_cast<unsigned char>(bytes[8]) | (static_cast<unsigned char>(bytes[9]) << 8);
  Npy n;
  n.header = bytes.substr(10, len);
  EXPECT_EQ((10 + len) % 64, 0u) << "numpy aligns the data to 64 bytes";
  n.data.resize((bytes.size() - 10 - len) / sizeof(float));
  std::memcpy(n.data.data(), bytes.data() + 10 + len, n.data.size() * sizeof(float));
  return n;
}

TEST(Layout, SyntheticDocFilesReadBackWithTheReferenceConventions) {
  test::TempDir dir("layout");
  SampleOptions o;
  o.mesh_path = test::write_example(dir, "cylinder", "cylinder.obj");
  o.seed = 6;
  o.width = 96;
  o.height = 136;
  o.quality = Quality::draft;
  o.document_dpi = 30;
  o.fine_passes = false;
  render_sample(o, dir.str("ours"), RunOptions{});
  o.layout = "syntheticdoc";
  render_sample(o, dir.str("ref"), RunOptions{});
  const fs::path ours = dir.path() / "ours", ref = dir.path() / "ref";
  for (const char* f : {"render.png", "shadow.png", "albedo.png", "uv_inverse.exr", "3d.exr",
                        "normal.exr", "backward_map.npy", "metadata.json"})
    EXPECT_TRUE(fs::exists(ref / f)) << f;
  EXPECT_FALSE(fs::exists(ref / "meta.json"));
  // Same sample, other names: identical pixels.
  EXPECT_EQ(test::file_bytes(ref / "render.png"), test::file_bytes(ours / "image.png"));
  EXPECT_EQ(test::file_bytes(ref / "shadow.png"), test::file_bytes(ours / "shading.png"));
  EXPECT_EQ(read_exr((ref / "3d.exr").string(), {"R", "G", "B"}).data,
            read_exr((ours / "coords.exr").string(), {"R", "G", "B"}).data);
  EXPECT_EQ(read_exr((ref / "uv_inverse.exr").string(), {"R", "G", "B"}).data,
            read_exr((ours / "uv.exr").string(), {"R", "G", "B"}).data);
  // backward_map.npy: float32 little endian, C order, shape (177, 121, 2), values in [-1, 1],
  // row 0 = top of the page, x right: (gx, gy) = (2 x / W - 1, 2 y / H - 1) of our map.
  const Npy npy = read_npy(ref / "backward_map.npy");
  EXPECT_NE(npy.header.find("'descr': '<f4'"), std::string::npos) << npy.header;
  EXPECT_NE(npy.header.find("'fortran_order': False"), std::string::npos) << npy.header;
  EXPECT_NE(npy.header.find("'shape': (177, 121, 2)"), std::string::npos) << npy.header;
  ASSERT_EQ(npy.data.size(), 177u * 121u * 2u);
  const ImageF back = read_exr((ours / "backward.exr").string(), {"R", "G", "B"});
  double worst = 0;
  int visible = 0;
  for (int r = 0; r < 177; ++r)
    for (int c = 0; c < 121; ++c) {
      const float gx = npy.data[(static_cast<std::size_t>(r) * 121 + c) * 2];
      const float gy = npy.data[(static_cast<std::size_t>(r) * 121 + c) * 2 + 1];
      ASSERT_TRUE(gx >= -1.0f && gx <= 1.0f && gy >= -1.0f && gy <= 1.0f) << r << "," << c;
      if (back.at(c, r, 2) < 0.5f) continue;
      ++visible;
      worst = std::max({worst, std::abs(gx - (2.0 * back.at(c, r, 0) / o.width - 1.0)),
                        std::abs(gy - (2.0 * back.at(c, r, 1) / o.height - 1.0))});
    }
  ASSERT_GT(visible, 177 * 121 / 2);
  EXPECT_LT(worst, 1e-6);
  // Orientation: the page's top-left corner (row 0, column 0) lies left of and above its
  // bottom-right corner in the image (the page is upright, roll at most 8 degrees).
  const auto g = [&](int r, int c, int k) {
    return npy.data[(static_cast<std::size_t>(r) * 121 + c) * 2 + k];
  };
  EXPECT_LT(g(0, 0, 0), g(176, 120, 0));
  EXPECT_LT(g(0, 0, 1), g(176, 120, 1));
  std::ifstream in(ref / "metadata.json");
  const auto meta = nlohmann::json::parse(in);
  EXPECT_EQ(meta["layout"], "syntheticdoc");
  EXPECT_TRUE(meta["files"].contains("backward_map.npy"));
}

TEST(Layout, UnknownLayoutIsAnInputErrorNamingIt) {
  test::TempDir dir("badlayout");
  SampleOptions o;
  o.mesh_path = test::write_example(dir, "flat", "flat.obj");
  o.layout = "nope";
  try {
    prepare_job(o, dir.str("job"));
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'nope'"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir.path() / "job"));
}

}  // namespace
}  // namespace papersim::scenegen
