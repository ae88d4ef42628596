#include "simulation/scene.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "collision/errors.hpp"
#include "common/format.hpp"
#include "remesh/sheet_io.hpp"
#include "simulation/errors.hpp"

namespace papersim::simulation {

using nlohmann::json;

namespace {

/// Reads one JSON object, checking types and ranges, and refuses keys it was not asked for.
class Reader {
 public:
  Reader(const json& j, std::string path, const std::string& source)
      : m_j(j), m_path(std::move(path)), m_source(source) {
    if (!m_j.is_object()) fail("", "expected an object");
  }

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    const std::string full = m_path.empty() ? key : (key.empty() ? m_path : m_path + "." + key);
    throw SceneError(m_source + ": key '" + full + "': " + what);
  }

  bool has(const std::string& key) const { return m_j.contains(key); }

  double number(const std::string& key, double fallback, double lo = -INF, double hi = INF,
                bool lo_open = false) {
    const json* v = take(key);
    if (!v) return fallback;
    if (!v->is_number()) fail(key, "expected a number");
    const double x = v->get<double>();
    if (!std::isfinite(x) || x < lo || x > hi || (lo_open && x == lo))
      fail(key, "value " + common::format_number(x) + " out of range " + (lo_open ? "(" : "[") +
                    common::format_number(lo) + ", " + common::format_number(hi) + "]");
    return x;
  }

  int integer(const std::string& key, int fallback, int lo, int hi) {
    const json* v = take(key);
    if (!v) return fallback;
    if (!v->is_number_integer()) fail(key, "expected an integer");
    if (v->is_number_unsigned() &&
        v->get<unsigned long long>() > static_cast<unsigned long long>(hi))
      fail(key, "value " + std::to_string(v->get<unsigned long long>()) + " out of range [" +
                    std::to_string(lo) + ", " + std::to_string(hi) + "]");
    const long long x = v->get<long long>();
    if (x < lo || x > hi)
      fail(key, "value " + std::to_string(x) + " out of range [" + std::to_string(lo) + ", " +
                    std::to_string(hi) + "]");
    return static_cast<int>(x);
  }

  bool boolean(const std::string& key, bool fallback) {
    const json* v = take(key);
    if (!v) return fallback;
    if (!v->is_boolean()) fail(key, "expected true or false");
    return v->get<bool>();
  }

  std::string string(const std::string& key, const std::string& fallback) {
    const json* v = take(key);
    if (!v) return fallback;
    if (!v->is_string()) fail(key, "expected a string");
    return v->get<std::string>();
  }

  template <int N>
  Eigen::Matrix<double, N, 1> vector(const std::string& key,
                                     const Eigen::Matrix<double, N, 1>& fallback) {
    const json* v = take(key);
    if (!v) return fallback;
    if (!v->is_array() || v->size() != N)
      fail(key, "expected an array of " + std::to_string(N) + " numbers");
    Eigen::Matrix<double, N, 1> r;
    for (int i = 0; i < N; ++i) {
      if (!(*v)[i].is_number()) fail(key, "expected an array of " + std::to_string(N) + " numbers");
      r[i] = (*v)[i].get<double>();
      if (!std::isfinite(r[i])) fail(key, "not finite");
    }
    return r;
  }

  /// A nested object (an empty one when absent).
  Reader child(const std::string& key) {
    const json* v = take(key);
    static const json EMPTY = json::object();
    if (v && !v->is_object()) fail(key, "expected an object");
    return Reader(v ? *v : EMPTY, m_path.empty() ? key : m_path + "." + key, m_source);
  }

  /// Elements of an array of objects (none when absent).
  std::vector<Reader> children(const std::string& key) {
    std::vector<Reader> out;
    const json* v = take(key);
    if (!v) return out;
    if (!v->is_array()) fail(key, "expected an array");
    for (size_t i = 0; i < v->size(); ++i)
      out.emplace_back((*v)[i],
                       (m_path.empty() ? key : m_path + "." + key) + "[" + std::to_string(i) + "]",
                       m_source);
    return out;
  }

  const json* raw_array(const std::string& key) {
    const json* v = take(key);
    if (v && !v->is_array()) fail(key, "expected an array");
    return v;
  }

  /// Every key must have been read.
  void finish() const {
    for (auto it = m_j.begin(); it != m_j.end(); ++it)
      if (!m_used.count(it.key())) fail(it.key(), "unknown key");
  }

  const std::string& path() const { return m_path; }

 private:
  const json* take(const std::string& key) {
    m_used.insert(key);
    auto it = m_j.find(key);
    if (it == m_j.end()) return nullptr;
    if (it->is_null()) fail(key, "null is not a value (leave the key out for its default)");
    return &*it;
  }
  const json& m_j;
  std::string m_path;
  std::string m_source;
  std::set<std::string> m_used;
};

remesh::Triangulation triangulation_from(Reader& r, const std::string& key,
                                         remesh::Triangulation d) {
  const std::string name = r.string(key, "");
  if (name.empty()) return d;
  if (name == "alternating") return remesh::Triangulation::alternating;
  if (name == "random") return remesh::Triangulation::random;
  if (name == "regular") return remesh::Triangulation::regular;
  r.fail(key, "expected one of alternating, random, regular; got '" + name + "'");
}

const char* to_string(remesh::Triangulation t) {
  switch (t) {
    case remesh::Triangulation::alternating:
      return "alternating";
    case remesh::Triangulation::random:
      return "random";
    case remesh::Triangulation::regular:
      return "regular";
  }
  return "alternating";
}

BendingModel bending_model_from(Reader& r, const std::string& key, BendingModel d) {
  const std::string name = r.string(key, "");
  if (name.empty()) return d;
  if (name == "fit") return BendingModel::fit;
  if (name == "morley") return BendingModel::morley;
  r.fail(key, "expected one of fit, morley; got '" + name + "'");
}

const char* to_string(BendingModel m) { return m == BendingModel::morley ? "morley" : "fit"; }

MembraneModel membrane_model_from(Reader& r, const std::string& key, MembraneModel d) {
  const std::string name = r.string(key, "");
  if (name.empty()) return d;
  if (name == "chord") return MembraneModel::chord;
  if (name == "arc") return MembraneModel::arc;
  r.fail(key, "expected one of chord, arc; got '" + name + "'");
}

Material read_material(Reader r) {
  Material m;
  m.density = r.number("density", m.density, 0, 1e3, true);
  m.stretch_stiffness = r.number("stretch_stiffness", m.stretch_stiffness, 0, 1e12, true);
  m.poisson = r.number("poisson", m.poisson, 0, 0.49);
  m.bending_stiffness = r.number("bending_stiffness", m.bending_stiffness, 0, 1e3, true);
  m.damping = r.number("damping", m.damping, 0, 1e4);
  m.strain_limit = r.number("strain_limit", m.strain_limit, 0, 1);
  m.compression_limit = r.number("compression_limit", m.compression_limit, 0, 0.5);
  m.thickness = r.number("thickness", m.thickness, 0, 0.1, true);
  m.yield_curvature = r.number("yield_curvature", m.yield_curvature, 0, 1e6, true);
  m.weakening = r.number("weakening", m.weakening, 0, 1e3);
  m.bending_model = bending_model_from(r, "bending_model", m.bending_model);
  m.membrane_model = membrane_model_from(r, "membrane_model", m.membrane_model);
  r.finish();
  return m;
}

SheetSpec read_sheet(Reader r) {
  SheetSpec s;
  s.width = r.number("width", s.width, 0, 100, true);
  s.height = r.number("height", s.height, 0, 100, true);
  s.edge_length = r.number("edge_length", s.edge_length, 0, 100, true);
  if (s.edge_length > std::min(s.width, s.height)) r.fail("edge_length", "longer than the sheet");
  if (std::max(s.width, s.height) / s.edge_length > 4000)
    r.fail("edge_length", "too small for the sheet size (more than 4000 edges along a side)");
  if ((s.width / s.edge_length + 1) * (s.height / s.edge_length + 1) > remesh::MAX_SHEET_VERTICES)
    r.fail("edge_length", "too small for the sheet size (more than the limit of " +
                              std::to_string(remesh::MAX_SHEET_VERTICES) + " vertices)");
  s.triangulation = triangulation_from(r, "triangulation", s.triangulation);
  s.mesh_path = r.string("mesh", "");
  s.material = read_material(r.child("material"));
  s.position = r.vector<3>("position", s.position);
  if (s.position.cwiseAbs().maxCoeff() > MAX_SCENE_COORDINATE)
    r.fail("position", "a coordinate beyond the limit of " +
                           common::format_number(MAX_SCENE_COORDINATE) + " m");
  s.rotation_deg = r.vector<3>("rotation_deg", s.rotation_deg);
  r.finish();
  return s;
}

std::vector<HandleKeyframe> read_handle_keyframes(Reader& r, const std::string& key) {
  std::vector<HandleKeyframe> out;
  for (Reader k : r.children(key)) {
    HandleKeyframe f;
    f.time = k.number("time", 0.0, 0, 1e6);
    f.displacement = k.vector<3>("displacement", Eigen::Vector3d::Zero());
    if (!out.empty() && f.time <= out.back().time) k.fail("time", "keyframe times must increase");
    k.finish();
    out.push_back(f);
  }
  return out;
}

HandleSpec read_handle(Reader r, const SheetSpec& sheet) {
  HandleSpec h;
  h.material_point = r.vector<2>("point", Eigen::Vector2d(-1, -1));
  if (!r.has("point") && h.material_point.x() < 0) r.fail("point", "missing (material point [m])");
  if (h.material_point.x() < 0 || h.material_point.x() > sheet.width || h.material_point.y() < 0 ||
      h.material_point.y() > sheet.height)
    r.fail("point", "outside the sheet [0, width] x [0, height]");
  h.keyframes = read_handle_keyframes(r, "keyframes");
  h.release_time = r.number("release_time", INF, 0, INF);
  h.stiffness = r.number("stiffness", h.stiffness, 0, 1e12, true);
  h.axes = r.vector<3>("axes", h.axes);
  for (int k = 0; k < 3; ++k)
    if (h.axes[k] != 0 && h.axes[k] != 1) r.fail("axes", "expected three values, each 0 or 1");
  r.finish();
  return h;
}

ClampSpec read_clamp(Reader r) {
  ClampSpec c;
  c.region = r.vector<4>("region", Eigen::Vector4d(0, 0, -1, -1));
  if (c.region[2] < c.region[0] || c.region[3] < c.region[1])
    r.fail("region", "expected [x_min, y_min, x_max, y_max] with min <= max");
  c.release_time = r.number("release_time", INF, 0, INF);
  c.stiffness = r.number("stiffness", c.stiffness, 0, 1e12, true);
  r.finish();
  return c;
}

RemeshSpec read_remesh(Reader r) {
  RemeshSpec s;
  remesh::RemeshParams& p = s.params;
  s.enabled = r.boolean("enabled", s.enabled);
  s.every = r.integer("every", s.every, 1, 1 << 30);
  p.refine_angle = r.number("refine_angle", p.refine_angle, 0, M_PI, true);
  p.refine_compression = r.number("refine_compression", p.refine_compression, -1, 1);
  p.refine_velocity = r.number("refine_velocity", p.refine_velocity, -1, 1e3);
  p.obstacle_distance = r.number("obstacle_distance", p.obstacle_distance, -1, 10);
  s.rescue_distance = r.number("rescue_distance", s.rescue_distance, -1, 10);
  p.size_min = r.number("size_min", p.size_min, 0, 100, true);
  p.size_max = r.number("size_max", p.size_max, 0, 100, true);
  if (p.size_max < p.size_min) r.fail("size_max", "smaller than size_min");
  p.aspect_min = r.number("aspect_min", p.aspect_min, 0, 1, true);
  p.flip_angle_max = r.number("flip_angle_max", p.flip_angle_max, 0, M_PI, true);
  p.refuse_thin_splits = r.boolean("refuse_thin_splits", p.refuse_thin_splits);
  r.finish();
  return s;
}

/// An obstacle's `rotation_deg` (x, then y, then z, about fixed axes) as a quaternion.
Eigen::Quaterniond to_q(const Eigen::Vector3d& deg) {
  const Eigen::Vector3d a = deg * M_PI / 180;
  return Eigen::Quaterniond(Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()));
}

collision::ColliderSpec read_obstacle(Reader r) {
  collision::ColliderSpec c;
  try {
    c.kind = collision::collider_kind_from_string(r.string("kind", "plane"));
    c.field = collision::field_kind_from_string(r.string("field", "automatic"));
  } catch (const collision::ColliderError& e) {
    r.fail("kind", e.what());
  }
  c.radius = r.number("radius", c.radius, 0, 1e3, true);
  c.length = r.number("length", c.length, 0, 1e3, true);
  c.half_extents = r.vector<3>("half_extents", c.half_extents);
  c.half_width = r.number("half_width", c.half_width, 0, 1e3, true);
  c.height = r.number("height", c.height, 0, 1e3, true);
  c.obj_path = r.string("mesh", "");
  c.obj_scale = r.number("mesh_scale", c.obj_scale, 0, 1e6, true);
  c.level_set.voxel_size = r.number("voxel_size", c.level_set.voxel_size, 0, 1);
  c.friction = r.number("friction", c.friction, 0, 10);
  if (r.has("lift")) {
    Reader l = r.child("lift");
    c.lift.load = l.number("load", c.lift.load, 0, 1e6, true);
    c.lift.speed = l.number("speed", c.lift.speed, 0, 1e3, true);
    c.lift.coupled = l.boolean("coupled", c.lift.coupled);
    l.finish();
  }
  const Eigen::Vector3d t = r.vector<3>("position", Eigen::Vector3d::Zero());
  const Eigen::Vector3d rot = r.vector<3>("rotation_deg", Eigen::Vector3d::Zero());
  const double scale = r.number("scale", 1.0, 0, 1e6, true);
  for (Reader k : r.children("keyframes")) {
    collision::Keyframe f;
    f.time = k.number("time", 0.0, 0, 1e6);
    f.translation = k.vector<3>("position", t);
    f.rotation = to_q(k.vector<3>("rotation_deg", rot));
    if (k.has("rotation_quaternion")) {
      // The exact rotation, written where rotation_deg does not give it back to the bit.
      const Eigen::Vector4d w = k.vector<4>("rotation_quaternion", Eigen::Vector4d::Zero());
      const Eigen::Quaterniond q(w[0], w[1], w[2], w[3]);
      if (!(std::abs(q.norm() - 1) <= 1e-9))
        k.fail("rotation_quaternion", "expected a unit quaternion [w, x, y, z]; its norm is " +
                                          common::format_number(q.norm()));
      const double apart = q.angularDistance(f.rotation) * 180 / M_PI;
      if (k.has("rotation_deg") && !(apart <= 1e-6))
        k.fail("rotation_quaternion",
               "is " + common::format_number(apart) +
                   " degrees from rotation_deg; give one of the two, or both for one rotation");
      f.rotation = q;
    }
    f.scale = k.number("scale", scale, 0, 1e6, true);
    if (!c.keyframes.empty() && f.time <= c.keyframes.back().time)
      k.fail("time", "keyframe times must increase");
    k.finish();
    c.keyframes.push_back(f);
  }
  if (c.keyframes.empty()) {
    collision::Keyframe f;
    f.translation = t;
    f.rotation = to_q(rot);
    f.scale = scale;
    c.keyframes.push_back(f);
  }
  r.finish();
  return c;
}

}  // namespace

Scene scene_from_json(const json& j, const std::string& source) {
  Reader r(j, "", source);
  Scene s;
  s.name = r.string("name", s.name);
  s.sheet = read_sheet(r.child("sheet"));
  s.gravity = r.vector<3>("gravity", s.gravity);
  if (s.gravity.norm() > 1e5) r.fail("gravity", "magnitude above 1e5 m/s^2");
  s.duration = r.number("duration", s.duration, 0, 1e4, true);
  s.time_step = r.number("time_step", s.time_step, 1e-7, 1.0);
  if (s.time_step > s.duration) r.fail("time_step", "longer than the duration");
  s.ground = r.boolean("ground", s.ground);
  s.ground_friction = r.number("ground_friction", s.ground_friction, 0, 10);
  for (Reader o : r.children("obstacles")) s.obstacles.push_back(read_obstacle(std::move(o)));
  for (Reader h : r.children("handles")) s.handles.push_back(read_handle(std::move(h), s.sheet));
  for (Reader c : r.children("clamps")) s.clamps.push_back(read_clamp(std::move(c)));
  {
    Reader c = r.child("contact");
    s.contact.dhat = c.number("thickness", s.contact.dhat, 0, 0.1, true);
    s.contact.stiffness = c.number("stiffness", 0.0, 0, 1e12);
    s.contact.eps_velocity = c.number("static_velocity", s.contact.eps_velocity, 0, 10, true);
    s.contact.static_whole_step = c.boolean("static_whole_step", s.contact.static_whole_step);
    s.contact.faces = c.boolean("faces", s.contact.faces);
    s.contact.hold_load = c.boolean("hold_load", s.contact.hold_load);
    s.contact.load_raise = c.number("load_raise", s.contact.load_raise, 1, 1e3);
    s.contact.raise_limit = c.number("raise_limit", s.contact.raise_limit, 1, 1e12);
    c.finish();
  }
  {
    Reader c = r.child("self_contact");
    s.self_contact.enabled = c.boolean("enabled", s.self_contact.enabled);
    s.self_contact.dhat = c.number("thickness", s.self_contact.dhat, 0, 0.1);
    s.self_contact.stiffness = c.number("stiffness", s.self_contact.stiffness, 0, 1e12);
    s.self_contact.friction = c.number("friction", s.self_contact.friction, 0, 10);
    c.finish();
  }
  {
    Reader n = r.child("solver");
    s.newton.max_iterations = n.integer("max_iterations", s.newton.max_iterations, 1, 10000);
    s.newton.tolerance = n.number("tolerance", s.newton.tolerance, 0, 1e3, true);
    s.newton.max_halvings = n.integer("max_halvings", s.newton.max_halvings, 0, 30);
    s.newton.max_extrapolation =
        n.integer("max_extrapolation", s.newton.max_extrapolation, 1, 1024);
    s.newton.max_factor_reuse = n.integer("max_factor_reuse", s.newton.max_factor_reuse, 0, 1000);
    s.newton.follow_obstacles = n.boolean("follow_obstacles", s.newton.follow_obstacles);
    s.newton.exact_retry_skip_max =
        n.integer("exact_retry_skip_max", s.newton.exact_retry_skip_max, 0, 1000);
    s.newton.trust_region_cg = n.integer("trust_region_cg", s.newton.trust_region_cg, 0, 1000);
    n.finish();
  }
  s.remesh = read_remesh(r.child("remesh"));
  {
    Reader o = r.child("output");
    s.output.frames_every = o.integer("frames_every", s.output.frames_every, 0, 1 << 30);
    s.output.write_ply = o.boolean("ply", s.output.write_ply);
    o.finish();
  }
  s.scenario = r.string("scenario", "");
  if (r.has("seed")) s.seed = r.integer("seed", 0, 0, 2147483647);
  r.finish();
  return s;
}

json parse_scene_text(std::istream& in, const std::string& source) {
  // Keys seen in each open object, innermost last: a repeated key is an error, not "last wins".
  std::vector<std::set<std::string>> open;
  std::vector<std::string> where;
  const json::parser_callback_t check = [&](int, json::parse_event_t event, json& parsed) {
    if (event == json::parse_event_t::object_start) {
      open.emplace_back();
    } else if (event == json::parse_event_t::object_end) {
      if (!open.empty()) open.pop_back();
    } else if (event == json::parse_event_t::key && !open.empty()) {
      const std::string key = parsed.get<std::string>();
      if (!open.back().insert(key).second)
        throw SceneError(source + ": key '" + key + "' appears twice in the same object");
    }
    return true;
  };
  try {
    return json::parse(in, check);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for a number like 1e999
    throw SceneError(source + ": not valid JSON: " + e.what());
  }
}

Scene load_scene(const std::string& path) {
  if (!std::filesystem::exists(path)) throw SceneError(path + ": no such file");
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open");
  Scene scene = scene_from_json(parse_scene_text(in, path), path);
  scene.source = path;
  return scene;
}

namespace {

json vec(const Eigen::VectorXd& v) {
  json a = json::array();
  for (int i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}

json obstacle_json(const collision::ColliderSpec& c) {
  json o;
  o["kind"] = collision::to_string(c.kind);
  o["field"] = collision::to_string(c.field);
  o["radius"] = c.radius;
  o["length"] = c.length;
  o["half_extents"] = vec(c.half_extents);
  o["half_width"] = c.half_width;
  o["height"] = c.height;
  if (!c.obj_path.empty()) o["mesh"] = c.obj_path;
  o["mesh_scale"] = c.obj_scale;
  o["voxel_size"] = c.level_set.voxel_size;
  o["friction"] = c.friction;
  if (c.lift.enabled())
    o["lift"] = {{"load", c.lift.load}, {"speed", c.lift.speed}, {"coupled", c.lift.coupled}};
  json keys = json::array();
  for (const auto& k : c.keyframes) {
    const Eigen::Vector3d e = k.rotation.toRotationMatrix().eulerAngles(2, 1, 0) * 180 / M_PI;
    const Eigen::Vector3d deg(e[2], e[1], e[0]);
    json key = {{"time", k.time},
                {"position", vec(k.translation)},
                {"rotation_deg", vec(deg)},
                {"scale", k.scale}};
    // Degrees rarely give a quaternion back to the bit, and a run that differs by a bit in its
    // obstacle's pose can end elsewhere: the file then also carries the exact rotation.
    if (to_q(deg).coeffs() != k.rotation.coeffs())
      key["rotation_quaternion"] = {k.rotation.w(), k.rotation.x(), k.rotation.y(), k.rotation.z()};
    keys.push_back(key);
  }
  o["keyframes"] = keys;
  return o;
}

}  // namespace

json scene_to_json(const Scene& s, bool every_key) {
  json j;
  j["name"] = s.name;
  const Material& m = s.sheet.material;
  j["sheet"] = {{"width", s.sheet.width},
                {"height", s.sheet.height},
                {"edge_length", s.sheet.edge_length},
                {"triangulation", to_string(s.sheet.triangulation)},
                {"position", vec(s.sheet.position)},
                {"rotation_deg", vec(s.sheet.rotation_deg)},
                {"material",
                 {{"density", m.density},
                  {"stretch_stiffness", m.stretch_stiffness},
                  {"poisson", m.poisson},
                  {"bending_stiffness", m.bending_stiffness},
                  {"damping", m.damping},
                  {"strain_limit", m.strain_limit},
                  {"compression_limit", m.compression_limit},
                  {"thickness", m.thickness},
                  {"yield_curvature", m.yield_curvature},
                  {"weakening", m.weakening},
                  {"bending_model", to_string(m.bending_model)}}}};
  // Written only when not the default (or asked for), so that scenes of the default model keep
  // their bytes.
  if (m.membrane_model == MembraneModel::arc || every_key)
    j["sheet"]["material"]["membrane_model"] =
        m.membrane_model == MembraneModel::arc ? "arc" : "chord";
  if (!s.sheet.mesh_path.empty()) j["sheet"]["mesh"] = s.sheet.mesh_path;
  j["gravity"] = vec(s.gravity);
  j["duration"] = s.duration;
  j["time_step"] = s.time_step;
  j["ground"] = s.ground;
  j["ground_friction"] = s.ground_friction;
  j["obstacles"] = json::array();
  for (const auto& o : s.obstacles) j["obstacles"].push_back(obstacle_json(o));
  j["handles"] = json::array();
  for (const auto& h : s.handles) {
    json hj = {{"point", vec(h.material_point)}, {"stiffness", h.stiffness}, {"axes", vec(h.axes)}};
    if (std::isfinite(h.release_time)) hj["release_time"] = h.release_time;
    hj["keyframes"] = json::array();
    for (const auto& k : h.keyframes)
      hj["keyframes"].push_back({{"time", k.time}, {"displacement", vec(k.displacement)}});
    j["handles"].push_back(hj);
  }
  j["clamps"] = json::array();
  for (const auto& c : s.clamps) {
    json cj = {{"region", vec(c.region)}, {"stiffness", c.stiffness}};
    if (std::isfinite(c.release_time)) cj["release_time"] = c.release_time;
    j["clamps"].push_back(cj);
  }
  j["contact"] = {{"thickness", s.contact.dhat},
                  {"stiffness", s.contact.stiffness},
                  {"static_velocity", s.contact.eps_velocity},
                  {"static_whole_step", s.contact.static_whole_step},
                  {"faces", s.contact.faces},
                  {"hold_load", s.contact.hold_load},
                  {"load_raise", s.contact.load_raise},
                  {"raise_limit", s.contact.raise_limit}};
  j["self_contact"] = {{"enabled", s.self_contact.enabled},
                       {"thickness", s.self_contact.dhat},
                       {"stiffness", s.self_contact.stiffness},
                       {"friction", s.self_contact.friction}};
  j["solver"] = {{"max_iterations", s.newton.max_iterations},
                 {"tolerance", s.newton.tolerance},
                 {"max_halvings", s.newton.max_halvings},
                 {"max_extrapolation", s.newton.max_extrapolation},
                 {"max_factor_reuse", s.newton.max_factor_reuse},
                 {"follow_obstacles", s.newton.follow_obstacles},
                 {"exact_retry_skip_max", s.newton.exact_retry_skip_max},
                 {"trust_region_cg", s.newton.trust_region_cg}};
  const remesh::RemeshParams& rp = s.remesh.params;
  j["remesh"] = {{"enabled", s.remesh.enabled},
                 {"every", s.remesh.every},
                 {"refine_angle", rp.refine_angle},
                 {"refine_compression", rp.refine_compression},
                 {"refine_velocity", rp.refine_velocity},
                 {"obstacle_distance", rp.obstacle_distance},
                 {"rescue_distance", s.remesh.rescue_distance},
                 {"size_min", rp.size_min},
                 {"size_max", rp.size_max},
                 {"aspect_min", rp.aspect_min},
                 {"flip_angle_max", rp.flip_angle_max},
                 {"refuse_thin_splits", rp.refuse_thin_splits}};
  j["output"] = {{"frames_every", s.output.frames_every}, {"ply", s.output.write_ply}};
  if (!s.scenario.empty()) j["scenario"] = s.scenario;
  if (s.seed >= 0) j["seed"] = s.seed;
  return j;
}

}  // namespace papersim::simulation
