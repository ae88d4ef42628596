// libFuzzer target: scenegen's sheet OBJ reader, then the resting pose and camera search that
// crashed on a coordinate of 1e200 (issue 17). Bad input must end in scenegen::InputError or
// IoError (or NoValidCameraError's "no camera" outcome); anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "scenegen/camera.hpp"
#include "scenegen/errors.hpp"
#include "scenegen/random.hpp"
#include "scenegen/resting_pose.hpp"
#include "scenegen/sheet_obj.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace sg = papersim::scenegen;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const sg::SheetMesh mesh = sg::parse_sheet_obj(in, "fuzz.obj");
    if (mesh.num_faces() > 2000) return 0;  // the camera search is the slow part; keep runs fast
    const sg::Stage stage = sg::find_resting_pose(mesh);
    sg::Rng rng(1, "camera");
    sg::choose_camera(mesh, stage, 64, 90, sg::CameraParams{}, rng);
  } catch (const sg::InputError&) {
  } catch (const sg::IoError&) {
  }
  return 0;
}
