#pragma once
/// Builds obstacles from a plain description, for the scene loader (which parses JSON into a
/// ColliderSpec; this module never sees JSON).
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "collision/collider.hpp"
#include "collision/level_set_collider.hpp"
#include "collision/shapes.hpp"

namespace papersim::collision {

/// Obstacle kinds; local frames as in shapes.hpp (plane: z = 0, solid below).
enum class ColliderKind { plane, sphere, cylinder, capsule, box, gable, mesh, inverted_sphere };

/// How the field is evaluated.
enum class FieldKind {
  /// Exact analytic field for the plane and the primitives (exact and the cheapest), level set
  /// for meshes.
  automatic,
  /// Exact analytic field; not available for meshes.
  analytic,
  /// OpenVDB narrow-band level set; not available for the (unbounded) plane and inverted
  /// sphere.
  level_set,
};

/// A plain obstacle description; only the fields of its kind are read.
/// An obstacle that yields upwards, as a weighted roller resting on a stop does: while the sheet
/// pushes it up with more than `load` [N] (the barrier forces' world z component summed over its
/// contacts, measured after every accepted step) it rises, at up to `speed` [m/s]; with less it
/// sinks back to its keyframed path at up to `speed`, never below it. The rate is
/// speed x clamp((F - load) / load, -1, 1) over the next step, so it settles where F = load.
/// load = 0: the obstacle follows its keyframes exactly (the default).
/// coupled: instead of that rule the obstacle is a body of weight `load` (mass load / |g|) whose
/// height above its keyframed path is an unknown of every time step, solved with the sheet: its
/// inertia, its weight and a barrier that keeps it above the path are terms of the incremental
/// potential and the sheet's contact pushes it up within the step (simulation::LiftBodyEnergy).
/// `speed` is not used then.
struct LiftSpec {
  double load = 0.0;   ///< [N]
  double speed = 0.1;  ///< [m/s]
  bool coupled = false;
  bool enabled() const { return load > 0.0; }
};

struct ColliderSpec {
  ColliderKind kind = ColliderKind::plane;
  FieldKind field = FieldKind::automatic;
  double radius = 0.05;  ///< sphere, inverted sphere, cylinder, capsule [m]
  double length = 0.1;   ///< cylinder, capsule (tip to tip), gable: along local x [m]
  Eigen::Vector3d half_extents = Eigen::Vector3d::Constant(0.05);  ///< box [m]
  double half_width = 0.05;      ///< gable: half base width along local y [m]
  double height = 0.05;          ///< gable: ridge height along local z [m]
  double plane_half_size = 1e3;  ///< plane: half extent of its bounding box in x and y [m]
  std::string obj_path;          ///< mesh: closed triangle mesh, OBJ
  double obj_scale = 1.0;        ///< mesh: factor applied to the OBJ coordinates to get metres [-]
  LevelSetParams level_set;      ///< resolution of level-set fields (voxel size, band)
  double friction = 0.3;         ///< Coulomb coefficient sheet-obstacle [-]
  /// Placement over time (rotation, translation, uniform scale of the shape); empty = identity.
  std::vector<Keyframe> keyframes;
  LiftSpec lift;  ///< yield upwards under load (off by default)
};

/// A spherical cavity (inverted sphere) of `radius` [m] centred at `centre` [m] that holds its
/// size until `t_hold` [s] and shrinks linearly to `end_scale` times it at `t_end` [s] (held
/// after); friction `friction` [-]. Used by the crumple scenario and the stress suite.
ColliderSpec shrinking_cavity(const Eigen::Vector3d& centre, double radius, double t_hold,
                              double t_end, double end_scale, double friction = 0.3);

/// Builds the collider a spec describes.
/// @throw ColliderError naming the bad value (dimension, friction, keyframe time or scale,
/// kind/field
///        combination, grid too large); ColliderIoError naming the OBJ file when it cannot be
///        read or is not closed.
std::unique_ptr<Collider> make_collider(const ColliderSpec& spec);

/// The Shape of a primitive spec. @throw ColliderError for plane and mesh.
Shape shape_of(const ColliderSpec& spec);

/// Lower-case name of a kind ("plane", "sphere", "cylinder", "capsule", "box", "gable", "mesh",
/// "inverted_sphere").
const char* to_string(ColliderKind kind);
/// Inverse of to_string. @throw ColliderError naming the unknown name.
ColliderKind collider_kind_from_string(const std::string& name);
/// "automatic", "analytic" or "level_set" and back. @throw ColliderError for an unknown name.
const char* to_string(FieldKind field);
FieldKind field_kind_from_string(const std::string& name);

}  // namespace papersim::collision
