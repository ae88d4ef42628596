#include "test_support.hpp"

#include <unistd.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "scenegen/sheet_obj.hpp"

namespace papersim::scenegen::test {
namespace fs = std::filesystem;

TempDir::TempDir(const std::string& tag) {
  static int counter = 0;
  m_path = fs::temp_directory_path() / ("scenegen_test_" + tag + "_" + std::to_string(getpid()) +
                                        "_" + std::to_string(counter++));
  fs::remove_all(m_path);
  fs::create_directories(m_path);
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(m_path, ec);
}

std::string TempDir::str(const std::string& child) const {
  return child.empty() ? m_path.string() : (m_path / child).string();
}

std::string write_example(const TempDir& dir, const std::string& kind, const std::string& name,
                          const ExampleSheetParams& params) {
  const std::string path = dir.str(name);
  std::ofstream out(path);
  write_sheet_obj(out, make_example_sheet(kind, params));
  return path;
}

std::string write_smooth_document(const TempDir& dir, int width, int height) {
  ImageF img(width, height, 3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const double u = (x + 0.5) / width, v = (y + 0.5) / height;
      const double blob = std::exp(-((u - 0.3) * (u - 0.3) + (v - 0.6) * (v - 0.6)) / 0.02);
      img.at(x, y, 0) = static_cast<float>(0.5 + 0.4 * std::sin(6.0 * u + 1.0) * (1 - blob));
      img.at(x, y, 1) = static_cast<float>(0.5 + 0.4 * std::cos(5.0 * v) - 0.3 * blob);
      img.at(x, y, 2) = static_cast<float>(0.5 + 0.35 * std::sin(4.0 * (u + v)));
    }
  const std::string path = dir.str("document.png");
  write_png(path, img, 8);
  return path;
}

std::string file_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

}  // namespace papersim::scenegen::test
