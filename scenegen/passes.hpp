#pragma once
/// The passes a sample can have and the POV-Ray renders ("raw passes") each one needs.
#include <string>
#include <vector>

namespace papersim::scenegen {

/// User-visible outputs.
enum class Pass { image, shading, albedo, uv, coords, normal, mask, backward };

/// POV-Ray renders. The number is SG_PASS in render_templates/passes.inc.
enum class RawPass {
  image = 1,
  shading = 2,
  albedo = 3,
  uv = 4,
  uv_fine = 5,
  coords = 6,
  coords_fine = 7,
  normal = 8
};

/// Where the exact ground-truth passes (uv, coords, normal, mask) come from.
enum class GroundTruth {
  raycast,  ///< scenegen casts the pixel-centre rays on the triangles POV-Ray renders (default)
  povray    ///< emissive POV-Ray renders of encoded values (the uv, coords, normal raw passes)
};
std::string ground_truth_name(GroundTruth g);
/// "raycast" / "povray". @throw InputError naming the value otherwise
GroundTruth parse_ground_truth(const std::string& name);

std::string pass_name(Pass p);
std::string raw_pass_name(RawPass p);
/// All passes in output order.
std::vector<Pass> all_passes();
/// Parse "image,uv,..." (or "all"). @throw InputError naming an unknown pass.
std::vector<Pass> parse_passes(const std::string& list);
/// The raw renders the passes need, in render order (exact passes first, photo last).
/// @param fine  add the fine uv / coords renders (float32 precision instead of 16 bits)
/// @param ground_truth  raycast: no uv, coords or normal render (scenegen casts those rays)
std::vector<RawPass> raw_passes_for(const std::vector<Pass>& passes, bool fine,
                                    GroundTruth ground_truth = GroundTruth::raycast);

}  // namespace papersim::scenegen
