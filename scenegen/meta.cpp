#include "scenegen/meta.hpp"

namespace papersim::scenegen {

using nlohmann::json;

json to_json(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

namespace {
Eigen::Vector3d vec3(const json& j) {
  return {j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()};
}
}  // namespace

json to_json(const Stage& s) {
  return {{"origin", to_json(s.origin)},
          {"ex", to_json(s.ex)},
          {"ey", to_json(s.ey)},
          {"up", to_json(s.up)},
          {"centre_of_mass", to_json(s.centre_of_mass)},
          {"flat_sheet", s.flat_sheet},
          {"stable", s.stable},
          {"stable_faces", s.stable_faces}};
}

json to_json(const CameraChoice& c, const CameraParams& p) {
  json cands = json::array();
  for (const auto& k : c.candidates)
    cands.push_back({{"inclination_deg", k.inclination_deg},
                     {"azimuth_deg", k.azimuth_deg},
                     {"in_frame", k.in_frame},
                     {"backfacing_fraction", k.backfacing_fraction},
                     {"occluded_points", k.occluded_points},
                     {"valid", k.valid}});
  json j = {{"valid", c.valid},
            {"candidate_index", c.index},
            {"roll_deg", c.roll_deg},
            {"focal_length_m", p.focal_length},
            {"sensor_size_m", p.sensor_size},
            {"distance_m", p.distance},
            {"margin", p.margin},
            {"backfacing_angle_deg", p.backfacing_angle_deg},
            {"max_backfacing_fraction", p.max_backfacing_fraction},
            {"check_occlusion", p.check_occlusion},
            {"candidates", cands}};
  if (c.valid) {
    const auto& k = c.candidates[static_cast<std::size_t>(c.index)];
    const Camera& cam = c.camera;
    j["inclination_deg"] = k.inclination_deg;
    j["azimuth_deg"] = k.azimuth_deg;
    j["position"] = to_json(cam.position);
    j["forward"] = to_json(cam.forward);
    j["right"] = to_json(cam.right);
    j["up"] = to_json(cam.up);
    j["focal_px"] = cam.focal_px;
    j["width"] = cam.width;
    j["height"] = cam.height;
    j["vertical_fov_deg"] = cam.vertical_fov_deg();
  }
  return j;
}

Camera camera_from_json(const json& j) {
  Camera c;
  c.position = vec3(j.at("position"));
  c.forward = vec3(j.at("forward"));
  c.right = vec3(j.at("right"));
  c.up = vec3(j.at("up"));
  c.focal_px = j.at("focal_px").get<double>();
  c.width = j.at("width").get<int>();
  c.height = j.at("height").get<int>();
  return c;
}

json to_json(const LightingDraw& l) {
  json lights = json::array();
  for (const auto& x : l.lights)
    lights.push_back({{"name", x.name},
                      {"position", to_json(x.position)},
                      {"size_m", x.size},
                      {"power_w", x.power},
                      {"intensity", x.intensity},
                      {"fade_distance_m", x.fade_distance}});
  return {{"rig", l.rig},
          {"rotation_deg", l.rotation_deg},
          {"temperature", l.temperature},
          {"colour", to_json(l.colour)},
          {"exposure", l.exposure},
          {"sky", l.sky},
          {"lights", lights}};
}

json to_json(const BackgroundDraw& b) {
  json j = {{"kind", b.kind},
            {"colour_a", to_json(b.colour_a)},
            {"colour_b", to_json(b.colour_b)},
            {"scale", b.scale},
            {"rotation_deg", b.rotation_deg},
            {"offset_m", {b.offset.x(), b.offset.y()}},
            {"roughness", b.roughness},
            {"noise_seed", b.noise_seed},
            {"noise_offset", to_json(b.noise_offset)}};
  if (b.kind == "image") {
    j["image"] = b.image;
    j["image_size_m"] = b.image_size;
  }
  return j;
}

json to_json(const EdgeLift& lift, bool enabled) {
  return {{"enabled", enabled},    {"stream", "edge_lift"},       {"amplitude_m", lift.amplitude},
          {"width_m", lift.width}, {"rest_low_m", lift.rest_low}, {"rest_high_m", lift.rest_high}};
}

EdgeLift edge_lift_from_json(const json& surface) {
  EdgeLift lift;
  if (!surface.contains("edge_lift") || !surface["edge_lift"]["enabled"].get<bool>()) return lift;
  const json& j = surface["edge_lift"];
  lift.amplitude = j["amplitude_m"];
  lift.width = j["width_m"];
  lift.rest_low = j["rest_low_m"];
  lift.rest_high = j["rest_high_m"];
  return lift;
}

json to_json(const PaperDraw& p) {
  return {{"colour", to_json(p.colour)},
          {"ink_floor", p.ink_floor},
          {"wave_amplitude", p.wave_amplitude},
          {"wave_scale_m", p.wave_scale},
          {"grain_amplitude", p.grain_amplitude},
          {"grain_scale_m", p.grain_scale},
          {"crease_strength", p.crease_strength},
          {"crease_scale", p.crease_scale},
          {"roughness_ink", p.roughness_ink},
          {"roughness_paper", p.roughness_paper},
          {"wave_seed", p.wave_seed},
          {"grain_seed", p.grain_seed},
          {"crease_seed", p.crease_seed},
          {"wave_offset", to_json(p.wave_offset)},
          {"grain_offset", to_json(p.grain_offset)},
          {"crease_offset", to_json(p.crease_offset)}};
}

json to_json(const DocumentLayout& d) {
  return {{"seed", d.seed},
          {"page_width_mm", d.params.page_width_mm},
          {"page_height_mm", d.params.page_height_mm},
          {"dpi", d.params.dpi},
          {"width_px", d.width_px()},
          {"height_px", d.height_px()},
          {"columns", d.columns},
          {"fonts", d.fonts},
          {"figure", d.figure_kind},
          {"table_rows", d.table_rows},
          {"table_cols", d.table_cols},
          {"paragraphs", d.paragraphs},
          {"headings", d.headings},
          {"text_lines", d.lines.size()}};
}

}  // namespace papersim::scenegen
