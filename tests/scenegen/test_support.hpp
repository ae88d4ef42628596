#pragma once
// Helpers shared by the scenegen tests: temporary folders, meshes and documents on disk.
#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "scenegen/example_sheets.hpp"
#include "scenegen/image_io.hpp"

namespace papersim::scenegen::test {

/// A fresh empty folder under the system temp dir, removed by the destructor.
class TempDir {
 public:
  explicit TempDir(const std::string& tag);
  ~TempDir();
  const std::filesystem::path& path() const { return m_path; }
  std::string str(const std::string& child = "") const;

 private:
  std::filesystem::path m_path;
};

/// Write an example sheet OBJ and return its path.
std::string write_example(const TempDir& dir, const std::string& kind, const std::string& name,
                          const ExampleSheetParams& params = {});
/// A smooth synthetic document (low-frequency colour waves and soft blobs), sRGB 8-bit PNG.
std::string write_smooth_document(const TempDir& dir, int width, int height);
/// Whole file as bytes.
std::string file_bytes(const std::filesystem::path& path);

/// The JSON document in `path` (throws nlohmann::json::parse_error on a broken one).
nlohmann::json read_json(const std::filesystem::path& path);

}  // namespace papersim::scenegen::test
