#include "scenegen/passes.hpp"

#include <algorithm>
#include <sstream>

#include "scenegen/errors.hpp"

namespace papersim::scenegen {

std::vector<Pass> all_passes() {
  return {Pass::image,  Pass::shading, Pass::albedo, Pass::uv,
          Pass::coords, Pass::normal,  Pass::mask,   Pass::backward};
}

std::string pass_name(Pass p) {
  switch (p) {
    case Pass::image:
      return "image";
    case Pass::shading:
      return "shading";
    case Pass::albedo:
      return "albedo";
    case Pass::uv:
      return "uv";
    case Pass::coords:
      return "coords";
    case Pass::normal:
      return "normal";
    case Pass::mask:
      return "mask";
    case Pass::backward:
      return "backward";
  }
  return "?";
}

std::string raw_pass_name(RawPass p) {
  switch (p) {
    case RawPass::image:
      return "image";
    case RawPass::shading:
      return "shading";
    case RawPass::albedo:
      return "albedo";
    case RawPass::uv:
      return "uv";
    case RawPass::uv_fine:
      return "uv_fine";
    case RawPass::coords:
      return "coords";
    case RawPass::coords_fine:
      return "coords_fine";
    case RawPass::normal:
      return "normal";
  }
  return "?";
}

std::vector<Pass> parse_passes(const std::string& list) {
  if (list == "all") return all_passes();
  std::vector<Pass> out;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    bool found = false;
    for (Pass p : all_passes())
      if (pass_name(p) == item) {
        if (std::find(out.begin(), out.end(), p) == out.end()) out.push_back(p);
        found = true;
      }
    if (!found)
      throw InputError("unknown pass '" + item +
                       "' (image, shading, albedo, uv, coords, normal, mask, backward)");
  }
  if (out.empty()) throw InputError("no pass requested");
  return out;
}

std::string ground_truth_name(GroundTruth g) {
  return g == GroundTruth::povray ? "povray" : "raycast";
}

GroundTruth parse_ground_truth(const std::string& name) {
  if (name == "raycast") return GroundTruth::raycast;
  if (name == "povray") return GroundTruth::povray;
  throw InputError("unknown --ground-truth '" + name + "' (raycast, povray)");
}

std::vector<RawPass> raw_passes_for(const std::vector<Pass>& passes, bool fine,
                                    GroundTruth ground_truth) {
  const auto has = [&](Pass p) {
    const bool cast = p == Pass::uv || p == Pass::mask || p == Pass::backward ||
                      p == Pass::coords || p == Pass::normal;
    if (cast && ground_truth == GroundTruth::raycast) return false;
    return std::find(passes.begin(), passes.end(), p) != passes.end();
  };
  std::vector<RawPass> raw;
  // The UV render gives the mask (also of the coords and normal passes) and the occlusion test
  // of the backward map.
  if (has(Pass::uv) || has(Pass::mask) || has(Pass::backward) || has(Pass::coords) ||
      has(Pass::normal)) {
    raw.push_back(RawPass::uv);
    if (fine && has(Pass::uv)) raw.push_back(RawPass::uv_fine);
  }
  if (has(Pass::coords)) {
    raw.push_back(RawPass::coords);
    if (fine) raw.push_back(RawPass::coords_fine);
  }
  if (has(Pass::normal)) raw.push_back(RawPass::normal);
  if (has(Pass::albedo)) raw.push_back(RawPass::albedo);
  if (has(Pass::shading)) raw.push_back(RawPass::shading);
  if (has(Pass::image)) raw.push_back(RawPass::image);
  return raw;
}

}  // namespace papersim::scenegen
