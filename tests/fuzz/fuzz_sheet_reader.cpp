// libFuzzer target: the sheet readers of remesh (OBJ when FUZZ_PLY is 0, PLY when 1). Bad input
// must end in remesh::IoError or remesh::MeshError; anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "remesh/errors.hpp"
#include "remesh/sheet_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace rm = papersim::remesh;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size), std::ios::binary);
  try {
    rm::parse_sheet(in, "fuzz", FUZZ_PLY ? rm::SheetFormat::ply : rm::SheetFormat::obj);
  } catch (const rm::IoError&) {
  } catch (const rm::MeshError&) {
  }
  return 0;
}
