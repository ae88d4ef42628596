#pragma once
/// Random draws of a sample's look: light rig and colour temperature, background material,
/// paper material and noise seeds. Every draw is recorded in meta.json (see meta.hpp).
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "scenegen/random.hpp"
#include "scenegen/resting_pose.hpp"

namespace papersim::scenegen {

/// One area light, aimed at the sheet (POV-Ray `area_light ... circular orient`).
struct Light {
  std::string name;                                    ///< key, fill, rim, top, sun, ...
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< world [m]
  double size = 1.0;                                   ///< side of the area light [m]
  double power = 25.0;                                 ///< reference power [W]
  double intensity = 1.0;      ///< POV-Ray colour multiplier at the sheet centre (fade_power 2)
  double fade_distance = 1.0;  ///< distance to the sheet centre [m]: attenuation 1 there
};

/// The lighting of a sample.
struct LightingDraw {
  std::string rig;            ///< three-point | rim | softbox | natural
  double rotation_deg = 0.0;  ///< rig rotated about the stage normal, U[0, 360)
  std::string temperature;    ///< warm | cool | neutral
  Eigen::Vector3d colour = Eigen::Vector3d::Ones();  ///< linear RGB of every light
  double exposure = 1.0;  ///< direct irradiance at the sheet centre, U[0.6, 0.85]
  double sky = 0.3;       ///< environment (background colour) brightness for radiosity
  std::vector<Light> lights;
};

/// The background plane's material (POV-Ray procedural patterns or a user image).
struct BackgroundDraw {
  std::string kind;  ///< wood | marble | granite | fabric | cork | concrete | image
  Eigen::Vector3d colour_a = Eigen::Vector3d::Constant(0.5);  ///< linear RGB
  Eigen::Vector3d colour_b = Eigen::Vector3d::Constant(0.3);  ///< linear RGB
  double scale = 1.0;                                         ///< U[0.5, 2] (reference)
  double rotation_deg = 0.0;                                  ///< about the plane normal, U[0, 360)
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();           ///< [m], U[-1, 1]
  double roughness = 0.6;                                     ///< U[0.5, 0.7] (reference)
  std::uint32_t noise_seed = 0;                               ///< pattern translation seed
  Eigen::Vector3d noise_offset = Eigen::Vector3d::Zero();     ///< pattern translation [m]
  std::string image;        ///< file name inside the job (kind == image)
  double image_size = 0.5;  ///< side of one image tile [m]
};

/// The paper: reflectance and relief (attached to the material: uv_mapping, metres).
struct PaperDraw {
  Eigen::Vector3d colour = Eigen::Vector3d::Constant(0.8);  ///< paper white, linear RGB
  double ink_floor = 0.025;        ///< colour = paper * (floor + (1 - floor) * document)
  double wave_amplitude = 0.1;     ///< low-frequency waviness, POV-Ray normal amplitude
  double wave_scale = 0.05;        ///< [m]
  double grain_amplitude = 0.1;    ///< high-frequency grain, POV-Ray normal amplitude
  double grain_scale = 5e-4;       ///< [m]
  double crease_strength = 0.002;  ///< micro-creases, U[0.001, 0.003] (reference)
  double crease_scale = 7.0;       ///< cells per sheet width, U[4, 10] (reference)
  double roughness_ink = 0.5;      ///< U[0.4, 0.6]
  double roughness_paper = 0.8;    ///< U[0.6, 1.0]
  std::uint32_t wave_seed = 0, grain_seed = 0, crease_seed = 0;  ///< noise seeds
  Eigen::Vector3d wave_offset = Eigen::Vector3d::Zero();         ///< pattern translations [m]
  Eigen::Vector3d grain_offset = Eigen::Vector3d::Zero();
  Eigen::Vector3d crease_offset = Eigen::Vector3d::Zero();
};

/// Light rigs of the reference (positions relative to the sheet, stage frame, [m]).
struct RigLight {
  const char* name;
  double x, y, z, power, size;
};
/// The named rig's lights. @throw InputError for an unknown rig name.
std::vector<RigLight> light_rig(const std::string& rig);
/// All rig names.
std::vector<std::string> light_rig_names();

/// Draw the lighting; lights are aimed at `target` (the sheet centre), rig placed on `stage`.
/// @param rig  a rig name, or empty to draw one
LightingDraw draw_lighting(Rng& rng, const Stage& stage, const Eigen::Vector3d& target,
                           const std::string& rig = "");
/// Draw the background. @param images  user background images (file names); may be empty
BackgroundDraw draw_background(Rng& rng, const std::vector<std::string>& images);
/// Draw the paper material and its noise seeds.
PaperDraw draw_paper(Rng& rng);

}  // namespace papersim::scenegen
