#pragma once
/// meta.json: every draw of a sample (camera, lights, colour temperature, background, paper,
/// noise seeds, document), so a sample can be reproduced or filtered without opening images.
#include <nlohmann/json.hpp>

#include "scenegen/camera.hpp"
#include "scenegen/document.hpp"
#include "scenegen/edge_lift.hpp"
#include "scenegen/resting_pose.hpp"
#include "scenegen/scene_draw.hpp"

namespace papersim::scenegen {

nlohmann::json to_json(const Eigen::Vector3d& v);
nlohmann::json to_json(const Stage& stage);
nlohmann::json to_json(const CameraChoice& choice, const CameraParams& params);
nlohmann::json to_json(const LightingDraw& lighting);
nlohmann::json to_json(const BackgroundDraw& background);
nlohmann::json to_json(const PaperDraw& paper);
nlohmann::json to_json(const DocumentLayout& document);
/// meta.json's surface.edge_lift: enabled, amplitude_m, width_m, rest_low_m, rest_high_m (the
/// drawn values are recorded also when `enabled` is false).
nlohmann::json to_json(const EdgeLift& lift, bool enabled);
/// The curl a sample's surface was rendered with, from meta.json's surface entry (amplitude 0
/// when disabled or absent, as in samples made before the curl).
EdgeLift edge_lift_from_json(const nlohmann::json& surface);
/// Camera from its meta.json entry (position, forward, right, up, focal_px, width, height).
Camera camera_from_json(const nlohmann::json& j);

}  // namespace papersim::scenegen
