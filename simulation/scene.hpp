#pragma once
/// A scene: everything one simulation needs, as plain structs with defaults and units. JSON is
/// parsed only here (load_scene / scene_from_json) and written back by scene_to_json.
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "collision/collider_factory.hpp"
#include "remesh/remesh.hpp"
#include "remesh/sheet_generator.hpp"
#include "simulation/energies/contact_energy.hpp"
#include "simulation/energies/handle_energy.hpp"
#include "simulation/energies/self_contact_energy.hpp"
#include "simulation/integrator.hpp"
#include "simulation/material.hpp"

namespace papersim::simulation {

/// Largest |coordinate| of a sheet's initial position (and of a sheet read from sheet.mesh) [m].
constexpr double MAX_SCENE_COORDINATE = 1e3;

struct SheetSpec {
  double width = 0.210;       ///< [m] along material x
  double height = 0.297;      ///< [m] along material y
  double edge_length = 6e-3;  ///< target edge length of the initial mesh [m]
  remesh::Triangulation triangulation = remesh::Triangulation::alternating;
  std::string mesh_path;  ///< optional OBJ/PLY to start from instead of a rectangle
  Material material;
  /// Initial pose: the sheet's centre goes to `position` [m], then it is rotated by
  /// `rotation_deg` (x, y, z Euler angles applied in that order) about its centre [deg].
  Eigen::Vector3d position = Eigen::Vector3d(0, 0, 1e-3);
  Eigen::Vector3d rotation_deg = Eigen::Vector3d::Zero();
};

/// A clamp: every vertex whose material point lies in the box is held in place.
struct ClampSpec {
  Eigen::Vector4d region = Eigen::Vector4d::Zero();  ///< (x_min, y_min, x_max, y_max) [m]
  double release_time = INF;                         ///< [s]
  double stiffness = 1e6;                            ///< [N/m]
};

struct OutputSpec {
  int frames_every = 0;   ///< write every K-th step to frames/ (0: none)
  bool write_ply = true;  ///< sheet.ply beside sheet.obj
};

/// Adaptive remeshing during a run (remesh/remesh.hpp; keys under `remesh` in docs/scene.md).
struct RemeshSpec {
  bool enabled = false;
  /// Remesh before the first step, after it, and then after every `every` steps.
  int every = 1;
  remesh::RemeshParams params;
  /// [m] when a step fails at h / 64 while the obstacle criterion is off
  /// (params.obstacle_distance <= 0), the run turns it on with this distance, remeshes and takes
  /// the step again (Run::step); <= 0 off.
  double rescue_distance = 0.05;
};

/// ContactParams with the stiffness left to the scene (0: automatic).
inline ContactParams automatic_contact() {
  ContactParams c;
  c.stiffness = 0.0;
  return c;
}

struct Scene {
  std::string name = "scene";
  std::string source;  ///< the file the scene was read from, for messages (not written back)
  SheetSpec sheet;
  Eigen::Vector3d gravity = Eigen::Vector3d(0, 0, -9.8);  ///< [m/s^2]
  double duration = 1.0;                                  ///< [s]
  double time_step = 2e-3;                                ///< [s]
  bool ground = true;                                     ///< the plane z = 0
  double ground_friction = 0.3;                           ///< [-]
  std::vector<collision::ColliderSpec> obstacles;
  std::vector<HandleSpec> handles;
  std::vector<ClampSpec> clamps;
  /// Contact thickness, pressure scale and slip speed; stiffness <= 0 (the default, as in
  /// scene files) means automatic: rho_A max(|g|, 1).
  ContactParams contact = automatic_contact();
  /// Sheet against itself; thickness and stiffness 0 mean: as `contact` (eps_velocity and
  /// static_whole_step are always contact's).
  SelfContactParams self_contact;
  NewtonParams newton;
  RemeshSpec remesh;
  OutputSpec output;
  /// Provenance when a scenario drew the scene.
  std::string scenario;
  long long seed = -1;
};

/// Parse a scene. `source` names the file in error messages.
/// @throw SceneError naming the file and the key (unknown key, wrong type, out-of-range value).
Scene scene_from_json(const nlohmann::json& j, const std::string& source);
/// Parse the JSON text of a scene file; a key repeated in one object is an error.
/// @throw SceneError naming `source` when the text is not valid JSON or repeats a key
nlohmann::json parse_scene_text(std::istream& in, const std::string& source);
/// @throw SceneError when the file is missing, not valid JSON or repeats a key, or as
///        scene_from_json.
Scene load_scene(const std::string& path);
/// Every field of the scene, so that scene_from_json(scene_to_json(s)) == s to the bit (an
/// obstacle keyframe whose rotation_deg does not give its quaternion back exactly also carries
/// rotation_quaternion, so a run of the written file is the run of s). A key that is
/// written only when not at its default (sheet.material.membrane_model) is written at its
/// default too with `every_key` (so that an override can name it).
nlohmann::json scene_to_json(const Scene& scene, bool every_key = false);

}  // namespace papersim::simulation
