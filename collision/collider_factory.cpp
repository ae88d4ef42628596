#include "collision/collider_factory.hpp"

#include <cmath>
#include <stdexcept>

#include "collision/errors.hpp"
#include "common/format.hpp"

namespace papersim::collision {

namespace {

const ColliderKind ALL_KINDS[] = {ColliderKind::plane,    ColliderKind::sphere,
                                  ColliderKind::cylinder, ColliderKind::capsule,
                                  ColliderKind::box,      ColliderKind::gable,
                                  ColliderKind::mesh,     ColliderKind::inverted_sphere};
const FieldKind ALL_FIELDS[] = {FieldKind::automatic, FieldKind::analytic, FieldKind::level_set};

RigidMotion motion_of(const std::vector<Keyframe>& keyframes) {
  for (size_t i = 0; i < keyframes.size(); ++i)
    if (!keyframes[i].translation.allFinite() || !keyframes[i].rotation.coeffs().allFinite() ||
        !std::isfinite(keyframes[i].time))
      throw ColliderError("collider keyframe " + std::to_string(i) + " is not finite");
  for (size_t i = 0; i < keyframes.size(); ++i)
    if (!(std::isfinite(keyframes[i].scale) && keyframes[i].scale > 0.0))
      throw ColliderError("collider keyframe " + std::to_string(i) +
                          ": scale must be finite and > 0, got " +
                          common::format_number(keyframes[i].scale));
  try {
    return RigidMotion(keyframes);
  } catch (const std::invalid_argument& e) {
    throw ColliderError(e.what());
  }
}

std::unique_ptr<Collider> make_plane(const ColliderSpec& spec) {
  if (spec.field == FieldKind::level_set)
    throw ColliderError("collider plane: field 'level_set' is not available (unbounded)");
  if (!(std::isfinite(spec.plane_half_size) && spec.plane_half_size > 0.0))
    throw ColliderError("collider plane: plane_half_size must be > 0, got " +
                        common::format_number(spec.plane_half_size));
  auto plane = std::make_unique<PlaneCollider>();
  plane->half_size = spec.plane_half_size;
  return plane;
}

std::unique_ptr<Collider> make_mesh(const ColliderSpec& spec) {
  if (spec.field == FieldKind::analytic)
    throw ColliderError("collider mesh '" + spec.obj_path + "': field 'analytic' is not available");
  if (spec.obj_path.empty()) throw ColliderError("collider mesh: obj_path is empty");
  return LevelSetCollider::from_obj(spec.obj_path, spec.level_set, spec.obj_scale);
}

std::unique_ptr<Collider> make_primitive(const ColliderSpec& spec) {
  const Shape shape = shape_of(spec);
  if (shape.kind == ShapeKind::inverted_sphere && spec.field == FieldKind::level_set)
    throw ColliderError(
        "collider inverted_sphere: field 'level_set' is not available (unbounded solid)");
  if (spec.field == FieldKind::level_set)
    return LevelSetCollider::from_shape(shape, spec.level_set);
  return std::make_unique<AnalyticCollider>(shape);
}

}  // namespace

Shape shape_of(const ColliderSpec& spec) {
  Shape s;
  switch (spec.kind) {
    case ColliderKind::sphere:
      s.kind = ShapeKind::sphere;
      break;
    case ColliderKind::cylinder:
      s.kind = ShapeKind::cylinder;
      break;
    case ColliderKind::capsule:
      s.kind = ShapeKind::capsule;
      break;
    case ColliderKind::box:
      s.kind = ShapeKind::box;
      break;
    case ColliderKind::gable:
      s.kind = ShapeKind::gable;
      break;
    case ColliderKind::inverted_sphere:
      s.kind = ShapeKind::inverted_sphere;
      break;
    default:
      throw ColliderError(std::string("collider ") + to_string(spec.kind) +
                          " is not an analytic primitive");
  }
  s.radius = spec.radius;
  s.length = spec.length;
  s.half_extents = spec.half_extents;
  s.half_width = spec.half_width;
  s.height = spec.height;
  return s;
}

ColliderSpec shrinking_cavity(const Eigen::Vector3d& centre, double radius, double t_hold,
                              double t_end, double end_scale, double friction) {
  ColliderSpec cavity;
  cavity.kind = ColliderKind::inverted_sphere;
  cavity.radius = radius;
  cavity.friction = friction;
  Keyframe k;
  k.translation = centre;
  k.time = t_hold;
  cavity.keyframes.push_back(k);
  k.time = t_end;
  k.scale = end_scale;
  cavity.keyframes.push_back(k);
  return cavity;
}

std::unique_ptr<Collider> make_collider(const ColliderSpec& spec) {
  if (!(std::isfinite(spec.friction) && spec.friction >= 0.0))
    throw ColliderError(std::string("collider ") + to_string(spec.kind) +
                        ": friction must be >= 0, got " + common::format_number(spec.friction));
  RigidMotion motion = motion_of(spec.keyframes);
  std::unique_ptr<Collider> collider;
  if (spec.kind == ColliderKind::plane)
    collider = make_plane(spec);
  else if (spec.kind == ColliderKind::mesh)
    collider = make_mesh(spec);
  else
    collider = make_primitive(spec);
  collider->friction = spec.friction;
  collider->motion = std::move(motion);
  return collider;
}

const char* to_string(ColliderKind kind) {
  switch (kind) {
    case ColliderKind::plane:
      return "plane";
    case ColliderKind::sphere:
      return "sphere";
    case ColliderKind::cylinder:
      return "cylinder";
    case ColliderKind::capsule:
      return "capsule";
    case ColliderKind::box:
      return "box";
    case ColliderKind::gable:
      return "gable";
    case ColliderKind::mesh:
      return "mesh";
    case ColliderKind::inverted_sphere:
      return "inverted_sphere";
  }
  return "unknown";
}

ColliderKind collider_kind_from_string(const std::string& name) {
  for (ColliderKind k : ALL_KINDS)
    if (name == to_string(k)) return k;
  throw ColliderError(
      "unknown collider kind '" + name +
      "' (expected plane, sphere, cylinder, capsule, box, gable, mesh or inverted_sphere)");
}

const char* to_string(FieldKind field) {
  switch (field) {
    case FieldKind::automatic:
      return "automatic";
    case FieldKind::analytic:
      return "analytic";
    case FieldKind::level_set:
      return "level_set";
  }
  return "unknown";
}

FieldKind field_kind_from_string(const std::string& name) {
  for (FieldKind f : ALL_FIELDS)
    if (name == to_string(f)) return f;
  throw ColliderError("unknown collider field '" + name +
                      "' (expected automatic, analytic or level_set)");
}

}  // namespace papersim::collision
