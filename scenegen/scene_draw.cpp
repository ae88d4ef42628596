#include "scenegen/scene_draw.hpp"

#include <algorithm>
#include <cmath>

#include "scenegen/errors.hpp"
#include "scenegen/geometry.hpp"

namespace papersim::scenegen {
namespace {

Eigen::Vector3d noise_offset(std::uint32_t seed) {
  // A noise seed is a far translation of POV-Ray's (position-hashed) noise patterns.
  Rng r(seed, "noise-offset");
  return {r.uniform(-1000.0, 1000.0), r.uniform(-1000.0, 1000.0), r.uniform(-1000.0, 1000.0)};
}

Eigen::Vector3d temperature_colour(Rng& rng, const std::string& t) {
  if (t == "warm") return {1.0, rng.uniform(0.90, 0.95), rng.uniform(0.70, 0.85)};
  if (t == "cool") return {rng.uniform(0.75, 0.90), rng.uniform(0.85, 0.95), 1.0};
  return {rng.uniform(0.98, 1.0), rng.uniform(0.98, 1.0), rng.uniform(0.98, 1.0)};
}

Eigen::Vector3d hsv_to_rgb(double h, double s, double v) {
  const double c = v * s, hp = std::fmod(h, 360.0) / 60.0;
  const double x = c * (1 - std::abs(std::fmod(hp, 2.0) - 1));
  Eigen::Vector3d rgb = hp < 1   ? Eigen::Vector3d(c, x, 0)
                        : hp < 2 ? Eigen::Vector3d(x, c, 0)
                        : hp < 3 ? Eigen::Vector3d(0, c, x)
                        : hp < 4 ? Eigen::Vector3d(0, x, c)
                        : hp < 5 ? Eigen::Vector3d(x, 0, c)
                                 : Eigen::Vector3d(c, 0, x);
  return rgb + Eigen::Vector3d::Constant(v - c);
}

/// Colour pairs per material family: (hue range, saturation range, value range).
void draw_colours(Rng& rng, BackgroundDraw& bg) {
  double h0 = 0, h1 = 360, s0 = 0, s1 = 0.2, v0 = 0.2, v1 = 0.6;
  if (bg.kind == "wood") {
    h0 = 18;
    h1 = 38;
    s0 = 0.45;
    s1 = 0.8;
    v0 = 0.25;
    v1 = 0.7;
  }
  if (bg.kind == "cork") {
    h0 = 25;
    h1 = 40;
    s0 = 0.4;
    s1 = 0.6;
    v0 = 0.35;
    v1 = 0.6;
  }
  if (bg.kind == "marble") {
    s0 = 0.0;
    s1 = 0.15;
    v0 = 0.55;
    v1 = 0.9;
  }
  if (bg.kind == "granite" || bg.kind == "concrete") {
    s0 = 0.0;
    s1 = 0.12;
    v0 = 0.25;
    v1 = 0.6;
  }
  if (bg.kind == "fabric") {
    s0 = 0.2;
    s1 = 0.7;
    v0 = 0.15;
    v1 = 0.6;
  }
  const double h = rng.uniform(h0, h1), s = rng.uniform(s0, s1), v = rng.uniform(v0, v1);
  // Colours are drawn in display space and stored linear (sRGB-ish gamma 2.2).
  bg.colour_a = hsv_to_rgb(h, s, v).array().pow(2.2);
  bg.colour_b = hsv_to_rgb(h + rng.uniform(-8, 8), std::min(1.0, s * rng.uniform(0.8, 1.3)),
                           v * rng.uniform(0.45, 0.8))
                    .array()
                    .pow(2.2);
}

}  // namespace

std::vector<std::string> light_rig_names() { return {"three-point", "rim", "softbox", "natural"}; }

std::vector<RigLight> light_rig(const std::string& rig) {
  // Reference rigs (SCENARIOS.md): position [m], power [W], size [m].
  if (rig == "three-point")
    return {{"key", -1.3, 1.1, 2.2, 25, 1.0},
            {"fill", 1.3, -0.17, 2.4, 25, 1.5},
            {"rim", 0, 2.5, 0.25, 30, 0.8}};
  if (rig == "rim")
    return {{"rim-left", -2, 1.5, 0.8, 40, 1.0},
            {"rim-right", 2, 1.5, 0.8, 40, 1.0},
            {"fill", 0, -2, 1.5, 10, 1.5}};
  if (rig == "softbox")
    return {{"top", 0, 0, 3, 30, 2.0},
            {"left", -2.5, 0, 1.5, 25, 2.0},
            {"right", 2.5, 0, 1.5, 25, 2.0}};
  if (rig == "natural")
    return {
        {"sun", 2, -2, 3, 50, 1.5}, {"sky", 0, 0, 4, 15, 3.0}, {"bounce", -1.5, 1.5, 0.5, 8, 1.8}};
  throw InputError("unknown light rig '" + rig + "' (three-point, rim, softbox, natural)");
}

LightingDraw draw_lighting(Rng& rng, const Stage& stage, const Eigen::Vector3d& target,
                           const std::string& rig) {
  LightingDraw d;
  const auto names = light_rig_names();
  const std::string drawn = names[static_cast<std::size_t>(rng.randint(0, 3))];
  d.rig = rig.empty() ? drawn : rig;
  d.rotation_deg = rng.uniform(0.0, 360.0);
  const char* temps[] = {"warm", "cool", "neutral"};
  d.temperature = temps[rng.randint(0, 2)];
  d.colour = temperature_colour(rng, d.temperature);
  // An auto-exposed photo of a page shows the paper light grey-white with headroom for the
  // parts turned towards a light: U[1.0, 1.3] clipped 93% of the unprinted paper of pull seed
  // 1 to white, U[0.6, 0.85] puts its median at sRGB 0.86 (docs/scenegen.md, "Realism").
  d.exposure = rng.uniform(0.6, 0.85);
  d.sky = rng.uniform(0.25, 0.4);
  const double c = std::cos(d.rotation_deg * DEG), s = std::sin(d.rotation_deg * DEG);
  double norm = 0.0;
  for (const RigLight& r : light_rig(d.rig)) {
    Light l;
    l.name = r.name;
    const Eigen::Vector3d p_stage(c * r.x - s * r.y, s * r.x + c * r.y, r.z);
    l.position = stage.to_world(p_stage);
    l.size = r.size;
    l.power = r.power;
    const Eigen::Vector3d to_light = l.position - target;
    l.fade_distance = to_light.norm();
    const double cosine = std::max(0.2, stage.up.dot(to_light.normalized()));
    l.intensity = r.power / (l.fade_distance * l.fade_distance);
    norm += l.intensity * cosine;
    d.lights.push_back(l);
  }
  // Normalise so the irradiance of a flat sheet at the centre equals the drawn exposure.
  for (Light& l : d.lights) l.intensity *= d.exposure / norm;
  return d;
}

BackgroundDraw draw_background(Rng& rng, const std::vector<std::string>& images) {
  static const char* kinds[] = {"wood", "marble", "granite", "fabric", "cork", "concrete"};
  BackgroundDraw bg;
  const int n_kinds = 6 + (images.empty() ? 0 : 1);
  const int k = rng.randint(0, n_kinds - 1);
  bg.kind = k < 6 ? kinds[k] : "image";
  if (bg.kind == "image")
    bg.image =
        images[static_cast<std::size_t>(rng.randint(0, static_cast<int>(images.size()) - 1))];
  draw_colours(rng, bg);
  bg.scale = rng.uniform(0.5, 2.0);
  bg.rotation_deg = rng.uniform(0.0, 360.0);
  bg.offset = {rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)};
  bg.roughness = rng.uniform(0.5, 0.7);
  bg.noise_seed = rng.seed32();
  bg.noise_offset = noise_offset(bg.noise_seed);
  bg.image_size = rng.uniform(0.3, 0.8);
  return bg;
}

PaperDraw draw_paper(Rng& rng) {
  PaperDraw p;
  const double white = rng.uniform(0.76, 0.84);
  p.colour = {white * rng.uniform(0.98, 1.0), white * rng.uniform(0.98, 1.0),
              white * rng.uniform(0.96, 1.0)};
  p.wave_amplitude = rng.uniform(0.05, 0.2);
  p.wave_scale = rng.uniform(0.03, 0.08);
  p.grain_amplitude = rng.uniform(0.05, 0.15);
  p.grain_scale = rng.uniform(3e-4, 8e-4);
  p.crease_strength = rng.uniform(0.001, 0.003);
  p.crease_scale = rng.uniform(4.0, 10.0);
  p.roughness_ink = rng.uniform(0.4, 0.6);
  p.roughness_paper = rng.uniform(0.6, 1.0);
  p.wave_seed = rng.seed32();
  p.grain_seed = rng.seed32();
  p.crease_seed = rng.seed32();
  p.wave_offset = noise_offset(p.wave_seed);
  p.grain_offset = noise_offset(p.grain_seed);
  p.crease_offset = noise_offset(p.crease_seed);
  return p;
}

}  // namespace papersim::scenegen
