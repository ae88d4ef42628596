#include "scenegen/job.hpp"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "common/atomic_file.hpp"
#include "common/interrupt.hpp"
#include "scenegen/contact_shadow.hpp"
#include "scenegen/edge_lift.hpp"
#include "scenegen/errors.hpp"
#include "scenegen/geometry.hpp"
#include "scenegen/image_io.hpp"
#include "scenegen/limits.hpp"
#include "scenegen/meta.hpp"
#include "scenegen/raycast.hpp"
#include "scenegen/resting_pose.hpp"
#include "scenegen/scene_draw.hpp"
#include "scenegen/sheet_obj.hpp"
#include "scenegen/templates.hpp"

#ifndef PAPERSIM_VERSION
#define PAPERSIM_VERSION "unknown"
#endif

namespace papersim::scenegen {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

thread_local std::string g_failed_meta;

/// `j` as indented text and a line break. Names from outside (the mesh's, a document's or a
/// background's file name) are any bytes: those that are not UTF-8 become U+FFFD.
std::string json_text(const json& j) {
  return j.dump(2, ' ', false, json::error_handler_t::replace) + "\n";
}

/// POV-Ray 3.7's message when its worker threads do not start in time (vfeInitializeTimedOut):
/// on a loaded machine it fails a render before it begins (seen once in the test suite beside
/// two simulations on two cores). Such a render is started again, up to POVRAY_STARTS times in all.
const std::string POVRAY_STARTUP_TIMEOUT = "Timed out waiting for worker thread startup";
constexpr int POVRAY_STARTS = 5;

void write_text(const fs::path& path, const std::string& text) {
  common::write_text_atomically(path, text);
}

template <class Writer>
void write_with(const fs::path& path, Writer&& writer) {
  common::write_file_atomically(path, [&](std::ostream& out) { writer(out); });
}

/// Copy a file, as an output. @throw common::OutputError
void copy_output(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  fs::copy_file(from, to, fs::copy_options::overwrite_existing, ec);
  if (ec)
    throw common::OutputError("cannot copy '" + from.string() + "' to '" + to.string() +
                              "': " + ec.message());
}

std::string lower_ext(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e;
}

/// Check that an image is a readable PNG or JPEG. @throw IoError / InputError
void check_image(const fs::path& p, const std::string& what) {
  if (!fs::is_regular_file(p)) throw IoError(what + " '" + p.string() + "' does not exist");
  if (is_png_file(p.string())) {
    read_png(p.string());  // throws when truncated or corrupt
    return;
  }
  if (!is_jpeg_file(p.string()))
    throw InputError(what + " '" + p.string() + "' is not a readable PNG or JPEG image");
}

std::uint64_t fnv1a_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::uint64_t h = 1469598103934665603ULL;
  char buf[65536];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i)
      h = (h ^ static_cast<unsigned char>(buf[i])) * 1099511628211ULL;
    if (!in) break;
  }
  return h;
}

std::string hex(std::uint64_t v) {
  std::ostringstream s;
  s << std::hex << v;
  return s.str();
}

json options_json(const SampleOptions& o, const std::vector<std::string>& renders, int doc_w,
                  int doc_h) {
  json passes = json::array();
  for (Pass p : o.passes) passes.push_back(pass_name(p));
  const int gw = o.backward.grid_width > 0 ? o.backward.grid_width : o.width;
  const int gh = o.backward.grid_height > 0 ? o.backward.grid_height : o.height;
  return {
      {"passes", passes},
      {"raw_renders", renders},
      {"width", o.width},
      {"height", o.height},
      {"quality", quality_name(o.quality)},
      {"fine_passes", o.fine_passes},
      {"ground_truth", ground_truth_name(o.ground_truth)},
      {"backward",
       {{"grid_width", gw},
        {"grid_height", gh},
        {"tolerance_pixels", o.backward.tolerance_pixels}}},
      {"document_render", doc_w > 0 ? json{{"width_px", doc_w}, {"height_px", doc_h}} : json()}};
}

/// Copy the document into the job; returns its file name there and its meta.json entry.
std::pair<std::string, json> place_document(const SampleOptions& o, const SheetMesh& mesh,
                                            const fs::path& job, int threads,
                                            const std::string& tpl_dir) {
  fs::path src;
  if (!o.document.empty())
    src = o.document;
  else if (!o.documents_dir.empty()) {
    const auto files = image_files(o.documents_dir, "documents");
    Rng rng(o.seed, "document-choice");
    src = files[static_cast<std::size_t>(rng.randint(0, static_cast<int>(files.size()) - 1))];
  }
  if (!src.empty()) {
    check_image(src, "document");
    const std::string name = "document" + std::string(is_png_file(src.string()) ? ".png" : ".jpg");
    copy_output(src, job / name);
    return {name,
            {{"source", "file"},
             {"file", src.filename().string()},
             {"fnv1a64", hex(fnv1a_file(src.string()))}}};
  }
  DocumentParams dp;
  dp.page_width_mm = mesh.width * 1000.0;
  dp.page_height_mm = mesh.height * 1000.0;
  dp.dpi = o.document_dpi;
  const double side_px = std::max(dp.page_width_mm, dp.page_height_mm) / 25.4 * dp.dpi;
  if (!(side_px <= MAX_DOCUMENT_SIDE))
    throw InputError("the built-in page would be " + std::to_string(std::lround(side_px)) +
                     " pixels long, beyond the limit of " + std::to_string(MAX_DOCUMENT_SIDE) +
                     " (lower --dpi or give --document)");
  const DocumentLayout doc = generate_document(o.seed, dp);
  for (const auto& [name, path] : document_font_files()) copy_output(path, job / name);
  write_text(job / "document.inc", template_text("document.inc", tpl_dir));
  write_with(job / "document.pov", [&](std::ostream& out) { write_document_pov(out, doc); });
  write_with(job / "document.ini", [&](std::ostream& out) {
    write_document_ini(out, doc.width_px(), doc.height_px(), 0);
  });
  (void)threads;
  json j = to_json(doc);
  j["source"] = "built-in";
  return {"document.png", j};
}

/// Row bands of a raw render: the lit renders (photo, shading) are split into quality.bands
/// bands (at most one per row), the exact passes are rendered whole.
int band_count(RawPass r, const QualitySettings& q, int height) {
  const bool lit = r == RawPass::image || r == RawPass::shading;
  return lit ? std::clamp(q.bands, 1, height) : 1;
}

/// Random stream of a component for a view: view 0 uses the sample's own streams.
std::string view_stream(const std::string& component, int view) {
  return view == 0 ? component : component + "/view" + std::to_string(view);
}

/// The contact shadow's map (contact.png in the job) and its declaration. Its strength is the
/// share of the light on an open table that comes from the sky (radiosity) or the ambient fill
/// (draft), the part of the light the sheet's occlusion of the sky removes.
ContactShadowDecl place_contact_shadow(const SheetMesh& surface, const Stage& stage,
                                       const SceneDescription& scene, const fs::path& job,
                                       json& meta) {
  const Eigen::Vector3d span =
      surface.positions.colwise().maxCoeff() - surface.positions.colwise().minCoeff();
  ContactParams params = contact_params_for(span.maxCoeff());
  params.gap = scene.background_gap;
  const SheetHeightField field = sheet_height_field(surface, stage, params);
  write_contact_png((job / "contact.png").string(), field, contact_occlusion(field, params));
  ContactShadowDecl c;
  c.enabled = true;
  c.x0 = field.x0;
  c.y0 = field.y0;
  c.width = field.width * field.cell;
  c.height = field.height * field.cell;
  const double fill = scene.quality.radiosity ? scene.lighting.sky : scene.quality.ambient;
  c.strength = fill / (fill + scene.lighting.exposure);
  meta = {{"enabled", true},
          {"file", c.file},
          {"origin_stage_m", {c.x0, c.y0}},
          {"size_m", {c.width, c.height}},
          {"cell_m", params.cell},
          {"reach_m", params.reach},
          {"azimuths", params.azimuths},
          {"strength", c.strength}};
  return c;
}

void remove_quietly(const fs::path& p) {
  std::error_code ec;
  fs::remove_all(p, ec);
}

}  // namespace

std::vector<fs::path> image_files(const std::string& dir, const std::string& what) {
  std::error_code ec;
  std::vector<fs::path> files;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string e = lower_ext(it->path());
    if (it->is_regular_file() && (e == ".png" || e == ".jpg" || e == ".jpeg"))
      files.push_back(it->path());
  }
  if (ec) throw IoError("cannot list " + what + " folder '" + dir + "': " + ec.message());
  if (files.empty()) throw InputError(what + " folder '" + dir + "' has no PNG or JPEG file");
  std::sort(files.begin(), files.end());
  return files;
}

void parse_image_size(const std::string& s, int& w, int& h, const std::string& what,
                      bool allow_full, int min_side) {
  if (allow_full && s == "full") {
    w = h = 0;
    return;
  }
  const auto x = s.find('x');
  const auto digits = [](const std::string& t) {
    return !t.empty() && t.size() <= 9 && t.find_first_not_of("0123456789") == std::string::npos;
  };
  if (x == std::string::npos || !digits(s.substr(0, x)) || !digits(s.substr(x + 1)))
    throw InputError(what + " '" + s + "' is not WIDTHxHEIGHT (two whole numbers)");
  w = std::stoi(s.substr(0, x));
  h = std::stoi(s.substr(x + 1));
  if (w < min_side || h < min_side)
    throw InputError(what + " '" + s + "' is too small (at least " + std::to_string(min_side) +
                     " per side)");
  if (w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE)
    throw InputError(what + " '" + s + "' exceeds the limit of " + std::to_string(MAX_IMAGE_SIDE) +
                     " per side");
}

double RunReport::total() const {
  double t = 0;
  for (const auto& s : seconds) t += s.second;
  return t;
}

const std::string& failed_meta() { return g_failed_meta; }

void prepare_job(const SampleOptions& o, const std::string& job_dir) {
  if (o.width < 8 || o.height < 8) throw InputError("image size must be at least 8 x 8");
  if (!(o.shadow_offset >= 0.0 && o.shadow_offset < 3e-4))
    throw InputError("shadow offset must be in [0, 0.3 mm) (the gap to the table), got " +
                     std::to_string(o.shadow_offset) + " m");
  const std::vector<std::string> layouts = layout_names();
  if (std::find(layouts.begin(), layouts.end(), o.layout) == layouts.end())
    throw InputError("unknown layout '" + o.layout + "' (scenegen, syntheticdoc)");
  const int bands = (o.quality_override ? *o.quality_override : quality_settings(o.quality)).bands;
  if (bands < 1 || bands > 64)
    throw InputError("quality bands must be in [1, 64], got " + std::to_string(bands));
  if (o.view < 0) throw InputError("view index " + std::to_string(o.view) + " is negative");
  const SheetMesh read_mesh = read_sheet_obj(o.mesh_path);
  const SheetMesh mesh = o.flip ? flip_sheet(read_mesh) : read_mesh;
  // Draws (resting pose, camera) use the simulated vertices, so they do not depend on the
  // refinement level; every pass is rendered and decoded on the refined surface.
  const Stage stage = find_resting_pose(mesh);
  // The curl is the sheet's, not the view's: one stream for every view of it.
  Rng lift_rng(o.seed, "edge_lift");
  const EdgeLift lift = draw_edge_lift(lift_rng);
  const RenderedSurface rendered =
      rendered_surface(mesh, stage.origin, stage.up, o.surface, o.edge_lift ? lift : EdgeLift{});
  const SheetMesh& surface = rendered.surface;
  Rng cam_rng(o.seed, view_stream("camera", o.view));
  const CameraChoice choice = choose_camera(mesh, stage, o.width, o.height, o.camera, cam_rng);

  json meta;
  meta["scenegen_version"] = PAPERSIM_VERSION;
  meta["seed"] = o.seed;
  meta["mesh"] = {{"file", fs::path(o.mesh_path).filename().string()},
                  {"fnv1a64", hex(fnv1a_file(o.mesh_path))},
                  {"vertices", mesh.num_vertices()},
                  {"faces", mesh.num_faces()},
                  {"width_m", mesh.width},
                  {"height_m", mesh.height},
                  {"size_from_header", mesh.size_from_header}};
  meta["flip"] = o.flip;
  meta["shadow_offset_m"] = o.shadow_offset;
  meta["view"] = o.view;
  meta["surface"] = {{"kind", "modified_butterfly"},
                     {"level", o.surface.level},
                     {"vertices", surface.num_vertices()},
                     {"faces", surface.num_faces()},
                     {"edge_lift", to_json(lift, o.edge_lift)}};
  meta["stage"] = to_json(stage);
  meta["camera"] = to_json(choice, o.camera);
  if (!choice.valid) {
    meta["status"] = "failed";
    meta["failure"] =
        "no valid camera direction: none of the 26 candidates sees the whole sheet "
        "in frame (2% margin) without self-occlusion and backfacing";
    g_failed_meta = json_text(meta);
    throw NoValidCameraError("mesh '" + o.mesh_path + "': " + meta["failure"].get<std::string>());
  }

  const fs::path final_dir(job_dir), tmp = final_dir.string() + ".partial";
  remove_quietly(tmp);
  std::error_code ec;
  fs::create_directories(tmp, ec);
  if (ec)
    throw common::OutputError("cannot create job folder '" + tmp.string() + "': " + ec.message());
  try {
    SceneDescription scene;
    scene.camera = choice.camera;
    scene.stage = stage;
    scene.quality = o.quality_override ? *o.quality_override : quality_settings(o.quality);
    scene.sheet_width = mesh.width;
    scene.sheet_height = mesh.height;
    Rng light_rng(o.seed, view_stream("lighting", o.view));
    Rng bg_rng(o.seed, view_stream("background", o.view));
    Rng paper_rng(o.seed, view_stream("paper", o.view));
    scene.lighting = draw_lighting(light_rng, stage, stage.centre_of_mass, o.rig);
    if (!o.lights.empty()) {
      scene.lighting.rig = "custom";
      scene.lighting.lights = o.lights;
    }
    std::vector<std::string> bg_images;
    std::vector<fs::path> bg_files;
    if (!o.backgrounds_dir.empty()) {
      bg_files = image_files(o.backgrounds_dir, "backgrounds");
      for (const auto& f : bg_files) bg_images.push_back(f.string());
    }
    scene.background = draw_background(bg_rng, bg_images);
    if (scene.background.kind == "image") {
      const fs::path src = scene.background.image;
      check_image(src, "background image");
      scene.background.image =
          "background" + std::string(is_png_file(src.string()) ? ".png" : ".jpg");
      copy_output(src, tmp / scene.background.image);
    }
    scene.paper = draw_paper(paper_rng);
    set_coords_encoding(scene, surface);
    // Only the lit renders (photo, shading) see the table.
    const bool lit = std::any_of(o.passes.begin(), o.passes.end(),
                                 [](Pass p) { return p == Pass::image || p == Pass::shading; });
    json contact_meta = {{"enabled", false}};
    if (o.contact_shadow && lit)
      scene.contact = place_contact_shadow(surface, stage, scene, tmp, contact_meta);
    const auto [doc_file, doc_meta] = place_document(o, mesh, tmp, o.threads, o.templates_dir);
    scene.document_file = doc_file;

    for (const char* name :
         {"main.pov", "passes.inc", "paper.inc", "backgrounds.inc", "lights.inc"})
      write_text(tmp / name, template_text(name, o.templates_dir));
    const Eigen::MatrixX3d& normals = rendered.normals;
    write_with(tmp / "sheet.inc",
               [&](std::ostream& out) { write_sheet_inc(out, surface, normals); });
    write_with(tmp / "shadow.inc", [&](std::ostream& out) {
      write_shadow_inc(out, surface, normals, o.shadow_offset);
    });
    write_with(tmp / "scene.inc", [&](std::ostream& out) { write_scene_inc(out, scene); });
    write_with(tmp / "sheet.obj", [&](std::ostream& out) { write_sheet_obj(out, surface); });
    if (o.ground_truth == GroundTruth::raycast)
      write_vertex_normals((tmp / "sheet_normals.txt").string(), normals);
    const auto raw = raw_passes_for(o.passes, o.fine_passes, o.ground_truth);
    std::vector<std::string> renders;
    std::string run_sh =
        "#!/bin/sh\n# Renders this job with POV-Ray 3.7 alone; then: scenegen finish THIS_DIR "
        "--out DIR\nset -e\n"
        "cd \"$(dirname \"$0\")\"\n"
        "# One render, its messages in NAME.log. POV-Ray can fail to start its worker threads on "
        "a\n"
        "# loaded machine; such a render is started again (" +
        std::to_string(POVRAY_STARTS) +
        " starts at most).\n"
        "render() {\n"
        "  for start in $(seq " +
        std::to_string(POVRAY_STARTS) +
        "); do\n"
        "    povray \"$1\" > \"${1%.ini}.log\" 2>&1 && return 0\n"
        "    grep -q '" +
        POVRAY_STARTUP_TIMEOUT +
        "' \"${1%.ini}.log\" || break\n"
        "  done\n"
        "  echo \"POV-Ray failed on $1; the end of ${1%.ini}.log:\" >&2\n"
        "  tail -n 8 \"${1%.ini}.log\" >&2\n"
        "  return 1\n"
        "}\n";
    if (fs::exists(tmp / "document.ini")) run_sh += "render document.ini\n";
    for (RawPass r : raw) {
      const int count = band_count(r, scene.quality, o.height);
      for (int b = 0; b < count; ++b) {
        const RowBand band{b, count};
        const std::string name = raw_render_name(r, band);
        write_with(tmp / (name + ".ini"), [&](std::ostream& out) {
          write_pass_ini(out, r, o.width, o.height, scene.quality, o.threads, band);
        });
        run_sh += "render " + name + ".ini\n";
        renders.push_back(name);
      }
    }
    write_text(tmp / "run.sh", run_sh);
    fs::permissions(tmp / "run.sh",
                    fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                    fs::perm_options::add, ec);
    if (ec)
      throw common::OutputError("cannot make '" + (tmp / "run.sh").string() +
                                "' executable: " + ec.message());

    meta["status"] = "ok";
    meta["image"] = {{"width", o.width}, {"height", o.height}};
    meta["quality"] = quality_name(o.quality);
    meta["quality_settings"] = {{"radiosity", scene.quality.radiosity},
                                {"area_samples", scene.quality.area_samples},
                                {"antialias", scene.quality.antialias},
                                {"ambient", scene.quality.ambient},
                                {"radiosity_count", scene.quality.radiosity_count},
                                {"radiosity_error", scene.quality.radiosity_error},
                                {"radiosity_nearest", scene.quality.radiosity_nearest},
                                {"radiosity_pretrace_end", scene.quality.radiosity_pretrace_end},
                                {"dim_light_share", scene.quality.dim_light_share},
                                {"dim_area_samples", scene.quality.dim_area_samples},
                                {"antialias_method", scene.quality.antialias_method},
                                {"area_adaptive", scene.quality.area_adaptive},
                                {"area_jitter", scene.quality.area_jitter},
                                {"antialias_threshold", scene.quality.antialias_threshold},
                                {"antialias_depth", scene.quality.antialias_depth},
                                {"bands", scene.quality.bands},
                                {"custom", o.quality_override.has_value()}};
    meta["lighting"] = to_json(scene.lighting);
    meta["background"] = to_json(scene.background);
    meta["background"]["gap_m"] = scene.background_gap;
    meta["contact_shadow"] = contact_meta;
    meta["paper"] = to_json(scene.paper);
    meta["document"] = doc_meta;
    meta["encoding"] = {{"coords_min", to_json(scene.coords_min)},
                        {"coords_span", scene.coords_span},
                        {"uv_encoding", UV_ENCODING},
                        {"fine_factor", FINE_FACTOR}};
    json job =
        options_json(o, renders, doc_meta.value("width_px", 0), doc_meta.value("height_px", 0));
    job["meta"] = meta;
    job["document_file"] = doc_file;
    job["layout"] = o.layout;
    job["lit_bands"] = std::clamp(scene.quality.bands, 1, o.height);
    write_text(tmp / "job.json", json_text(job));
    remove_quietly(final_dir);
    fs::rename(tmp, final_dir, ec);
    if (ec)
      throw common::OutputError("cannot rename job folder into '" + final_dir.string() +
                                "': " + ec.message());
  } catch (...) {
    remove_quietly(tmp);
    throw;
  }
}

namespace {

/// Start POV-Ray on one .ini in the job folder, output to <name>.log. @throw RenderError
pid_t start_povray(const fs::path& job_rel, const std::string& povray, const std::string& ini) {
  const fs::path job = fs::absolute(job_rel);
  const std::string log = (job / (fs::path(ini).stem().string() + ".log")).string();
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) throw RenderError("cannot start POV-Ray (fork failed)");
  if (pid == 0) {
    // POV-Ray dies with scenegen, even when scenegen is killed with SIGKILL.
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(125);  // scenegen died before prctl
    common::reset_signals_in_child();
    if (chdir(job.c_str()) != 0) _exit(126);
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
      close(fd);
    }
    execlp(povray.c_str(), povray.c_str(), ini.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

/// Whether a failed POV-Ray's log says its worker threads did not start in time (POV-Ray's
/// vfeInitializeTimedOut, seen on a loaded machine): nothing was rendered, and the render is
/// started again.
bool povray_startup_timed_out(const fs::path& job, const std::string& ini) {
  std::ifstream in(fs::absolute(job) / (fs::path(ini).stem().string() + ".log"));
  std::string line;
  while (std::getline(in, line))
    if (line.find(POVRAY_STARTUP_TIMEOUT) != std::string::npos) return true;
  return false;
}

/// Turn a finished POV-Ray's exit status into success or a RenderError with its log's tail.
void check_povray(const fs::path& job, const std::string& povray, const std::string& ini,
                  int status) {
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
    throw RenderError("cannot run POV-Ray '" + povray + "' (is povray 3.7 installed?)");
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  const std::string log_name = fs::path(ini).stem().string() + ".log";
  std::ifstream in(fs::absolute(job) / log_name);
  std::string line, tail;
  std::vector<std::string> lines;
  while (std::getline(in, line)) lines.push_back(line);
  for (std::size_t i = lines.size() > 8 ? lines.size() - 8 : 0; i < lines.size(); ++i)
    tail += "\n  " + lines[i];
  const std::string how = WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                            : "signal " + std::to_string(WTERMSIG(status));
  throw RenderError("POV-Ray failed on " + ini + " (" + how + "); the end of " + log_name + ":" +
                    tail);
}

json read_job(const fs::path& job) {
  std::ifstream in(job / "job.json");
  if (!in) throw IoError("'" + job.string() + "' is not a scenegen job folder (no job.json)");
  try {
    return json::parse(in);
  } catch (const json::exception& e) {
    throw IoError("cannot parse '" + (job / "job.json").string() + "': " + e.what());
  }
}

}  // namespace

RunReport run_job(const std::string& job_dir, const RunOptions& run) {
  const fs::path job(job_dir);
  const json j = read_job(job);
  std::vector<std::string> inis;
  if (fs::exists(job / "document.ini")) inis.push_back("document.ini");
  for (const auto& r : j.at("raw_renders")) inis.push_back(r.get<std::string>() + ".ini");
  // Renders are single-threaded POV-Ray processes run side by side: multi-threaded radiosity
  // is not reproducible, one thread is. The document page comes first; the renders that read it
  // (photo, albedo: render_templates/paper.inc) wait for it while the others run beside it; the
  // longest renders (photo, shading) start first.
  std::vector<std::size_t> order;
  for (std::size_t i = inis.size(); i-- > 0;) order.push_back(i);
  const bool has_document = !inis.empty() && inis[0] == "document.ini";
  if (has_document) std::rotate(order.begin(), order.end() - 1, order.end());
  const auto reads_document = [&](std::size_t i) {
    for (const char* p : {"image", "albedo"})
      if (inis[i].rfind(p, 0) == 0) return true;
    return false;
  };
  const int slots = std::max(
      1, run.parallel > 0 ? run.parallel : static_cast<int>(std::thread::hardware_concurrency()));
  RunReport report;
  report.seconds.resize(inis.size());
  struct Running {
    pid_t pid;
    std::size_t index;
    std::chrono::steady_clock::time_point t0;
  };
  std::vector<Running> running;
  std::vector<bool> started(inis.size(), false);
  std::vector<int> starts(inis.size(), 0);  // failed starts so far, per render
  std::size_t next = 0;
  int done = 0;
  bool document_done = !has_document;
  const auto name_of = [&](std::size_t i) { return fs::path(inis[i]).stem().string(); };
  // The first render in `order` not started that may start now; inis.size() when none.
  const auto pick = [&]() -> std::size_t {
    for (std::size_t i : order)
      if (!started[i] && (document_done || !reads_document(i))) return i;
    return inis.size();
  };
  // SIGKILL: POV-Ray may ignore SIGTERM while it renders.
  const auto kill_all = [&] {
    for (auto& r : running) {
      kill(r.pid, SIGKILL);
      waitpid(r.pid, nullptr, 0);
    }
  };
  try {
    while (next < order.size() || !running.empty()) {
      while (next < order.size() && static_cast<int>(running.size()) < slots) {
        const std::size_t i = pick();
        if (i == inis.size()) break;
        started[i] = true;
        ++next;
        if (run.progress)
          run.progress({name_of(i), static_cast<int>(next), static_cast<int>(inis.size()), -1.0});
        running.push_back(
            {start_povray(job, run.povray, inis[i]), i, std::chrono::steady_clock::now()});
      }
      bool reaped = false;
      for (std::size_t k = 0; k < running.size(); ++k) {
        int status = 0;
        if (waitpid(running[k].pid, &status, WNOHANG) != running[k].pid) continue;
        const Running r = running[k];
        running.erase(running.begin() + static_cast<long>(k));
        if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0) && ++starts[r.index] < POVRAY_STARTS &&
            povray_startup_timed_out(job, inis[r.index])) {
          running.push_back({start_povray(job, run.povray, inis[r.index]), r.index,
                             std::chrono::steady_clock::now()});
          reaped = true;
          break;
        }
        check_povray(job, run.povray, inis[r.index], status);
        const double sec =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - r.t0).count();
        report.seconds[r.index] = {name_of(r.index), sec};
        if (inis[r.index] == "document.ini") document_done = true;
        ++done;
        if (run.progress)
          run.progress({name_of(r.index), done, static_cast<int>(inis.size()), sec});
        reaped = true;
        break;
      }
      if (run.poll_stop) run.poll_stop();
      if (!reaped) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  } catch (...) {
    kill_all();
    throw;
  }
  return report;
}

namespace {

ImageF to_srgb(const ImageF& linear) {
  ImageF out = linear;
  for (float& v : out.data) v = static_cast<float>(linear_to_srgb(v));
  return out;
}

ImageF channel(const ImageF& img, int c) {
  ImageF out(img.width, img.height, 1);
  for (std::size_t p = 0; p < std::size_t(img.width) * img.height; ++p)
    out.data[p] = img.data[p * img.channels + c];
  return out;
}

/// Rename a staged file (when present) and move its meta.json description along.
void rename_staged(const fs::path& stage, json& files, const std::string& from,
                   const std::string& to) {
  if (!fs::exists(stage / from)) return;
  fs::rename(stage / from, stage / to);
  files[to] = files[from];
  files.erase(from);
}

/// The reference dataset's names and conventions (docs/scenegen.md, "Layouts"): photo
/// render.png, shading shadow.png, UV uv_inverse.exr, coords 3d.exr, backward_map.npy of shape
/// (grid_height, grid_width, 2) float32 = pixel coordinates normalised to [-1, 1]
/// (grid_sample with align_corners=False), metadata.json.
void apply_syntheticdoc_layout(const fs::path& stage, json& meta) {
  json& files = meta["files"];
  rename_staged(stage, files, "image.png", "render.png");
  rename_staged(stage, files, "shading.png", "shadow.png");
  rename_staged(stage, files, "uv.exr", "uv_inverse.exr");
  rename_staged(stage, files, "coords.exr", "3d.exr");
  if (fs::exists(stage / "backward.exr")) {
    const ImageF back = read_exr((stage / "backward.exr").string(), {"R", "G", "B"});
    const int w = meta["image"]["width"], h = meta["image"]["height"];
    ImageF grid(back.width, back.height, 2);
    for (int r = 0; r < back.height; ++r)
      for (int c = 0; c < back.width; ++c) {
        grid.at(c, r, 0) =
            static_cast<float>(std::clamp(2.0 * back.at(c, r, 0) / w - 1.0, -1.0, 1.0));
        grid.at(c, r, 1) =
            static_cast<float>(std::clamp(2.0 * back.at(c, r, 1) / h - 1.0, -1.0, 1.0));
      }
    write_npy((stage / "backward_map.npy").string(), grid);
    files["backward_map.npy"] =
        "float32 (grid_height, grid_width, 2): 2 x / width - 1, 2 y / height - 1 "
        "(clamped to [-1, 1]); row 0 = top of the page";
    // backward.exr keeps the visibility flag the reference's map does not have.
    fs::remove(stage / "backward.npy");
    files.erase("backward.npy");
  }
  meta["layout"] = "syntheticdoc";
  files.erase("meta.json");
  files["metadata.json"] = "this file";
}

/// The exact passes by ray casting (raycast ground truth): the pixel rays of `camera` on the
/// job's sheet.obj with its sheet_normals.txt, at the precision POV-Ray holds them for the
/// photo. `uv` gets u, v, mask; `xyz` and `normal` are filled when asked for. @throw IoError
void cast_ground_truth(const fs::path& job, const Camera& camera, bool want_coords,
                       bool want_normal, ImageF& uv, ImageF& xyz, ImageF& normal) {
  const SheetMesh surface = read_sheet_obj((job / "sheet.obj").string());
  Eigen::MatrixX3d normals =
      read_vertex_normals((job / "sheet_normals.txt").string(), surface.num_vertices());
  const SheetMesh rendered = povray_precision(surface, normals);
  const PixelHits hits = cast_pixel_rays(rendered, camera);
  uv = uv_from_hits(hits, rendered);
  if (want_coords) xyz = coords_from_hits(hits, rendered);
  if (want_normal) normal = normals_from_hits(hits, rendered, normals, camera);
}

/// Path of a raw render in a job folder. @throw IoError when it is missing
std::string raw_path(const fs::path& job, const std::string& render) {
  const fs::path p = job / ("raw_" + render + ".png");
  if (!fs::exists(p)) throw IoError("raw render '" + p.string() + "' missing: run the job first");
  return p.string();
}

void finish_into(const fs::path& job, const fs::path& stage) {
  const json j = read_job(job);
  json meta = j.at("meta");
  std::vector<std::string> passes;
  for (const auto& p : j.at("passes")) passes.push_back(p.get<std::string>());
  const auto has = [&](const std::string& p) {
    return std::find(passes.begin(), passes.end(), p) != passes.end();
  };
  const bool fine = j.at("fine_passes").get<bool>();
  const auto raw = [&](RawPass r) { return raw_path(job, raw_pass_name(r)); };
  const int bands = j.value("lit_bands", 1);
  const int height = j.at("height").get<int>();
  // A lit render from its row bands: band b's rows are taken from its own file.
  const auto lit = [&](RawPass r, ImageF (*reader)(const std::string&)) {
    if (bands <= 1) return reader(raw_path(job, raw_render_name(r, {})));
    ImageF out;
    for (int b = 0; b < bands; ++b) {
      const RowBand band{b, bands};
      const ImageF part = reader(raw_path(job, raw_render_name(r, band)));
      if (b == 0) out = ImageF(part.width, part.height, part.channels);
      if (part.width != out.width || part.height != height || part.channels != out.channels)
        throw IoError("raw render '" + raw_render_name(r, band) +
                      "' does not match its other bands");
      const std::size_t row = std::size_t(part.width) * part.channels;
      std::copy(part.data.begin() + static_cast<long>(row * band.first_row(height)),
                part.data.begin() + static_cast<long>(row * band.end_row(height)),
                out.data.begin() + static_cast<long>(row * band.first_row(height)));
    }
    return out;
  };
  const Camera camera = camera_from_json(meta.at("camera"));
  meta["camera"]["vignetting"] = "cos^4 (natural, applied to the photo and the shading pass)";
  json files = json::object();
  // Independent outputs are decoded and written side by side (each task writes its own files;
  // meta.json is filled here), in two waves: the UV render first gives the mask the others use.
  std::vector<std::future<void>> tasks;
  const auto spawn = [&](std::function<void()> task) {
    tasks.push_back(std::async(std::launch::async, std::move(task)));
  };
  const auto wait_all = [&] {
    for (auto& t : tasks) t.wait();
    for (auto& t : tasks) t.get();  // rethrows the first failure, once every task has ended
    tasks.clear();
  };
  const bool cast = j.value("ground_truth", "povray") == "raycast";
  meta["ground_truth"] = cast ? "raycast" : "povray";
  ImageF uv, mask, xyz, normal;
  if (has("uv") || has("mask") || has("backward") || has("coords") || has("normal"))
    spawn([&] {
      if (cast) {
        cast_ground_truth(job, camera, has("coords"), has("normal"), uv, xyz, normal);
      } else {
        uv = decode_uv(raw(RawPass::uv), fine && has("uv") ? raw(RawPass::uv_fine) : "");
      }
      mask = channel(uv, 2);
    });
  if (has("albedo")) {
    spawn([&] {
      write_png((stage / "albedo.png").string(), to_srgb(decode_linear(raw(RawPass::albedo))), 16);
    });
    files["albedo.png"] = "16-bit sRGB document colour times paper colour, unlit, background 0";
  }
  if (has("shading")) {
    spawn([&] {
      ImageF shading = lit(RawPass::shading, decode_linear);
      apply_vignetting(shading, camera);
      write_png((stage / "shading.png").string(), to_srgb(shading), 16);
    });
    files["shading.png"] = "16-bit sRGB photo lighting on white paper (relief kept), background 0";
  }
  if (has("image")) {
    spawn([&] {
      // The photo is rendered as 16-bit sRGB so that the camera's vignetting is applied before
      // the one quantisation to 8 bits.
      ImageF photo = lit(RawPass::image, read_png);
      for (float& v : photo.data) v = static_cast<float>(srgb_to_linear(v));
      apply_vignetting(photo, camera);
      write_png((stage / "image.png").string(), to_srgb(photo), 8);
    });
    files["image.png"] = "8-bit sRGB photo";
  }
  wait_all();
  if (has("uv")) {
    spawn([&] { write_exr((stage / "uv.exr").string(), uv, {"R", "G", "B"}); });
    files["uv.exr"] = "float32 R = u, G = v (material x / width, y / height), B = mask";
  }
  if (has("mask")) {
    spawn([&] { write_png((stage / "mask.png").string(), mask, 8); });
    files["mask.png"] = "8-bit grey, 255 where the sheet is seen";
  }
  if (has("coords")) {
    const json& e = meta.at("encoding");
    const Eigen::Vector3d lo(e["coords_min"][0], e["coords_min"][1], e["coords_min"][2]);
    const double span = e.at("coords_span").get<double>();
    spawn([&, lo, span] {
      if (!cast)
        xyz = decode_coords(raw(RawPass::coords), fine ? raw(RawPass::coords_fine) : "", lo, span,
                            mask);
      write_exr((stage / "coords.exr").string(), xyz, {"R", "G", "B"});
    });
    files["coords.exr"] = "float32 R, G, B = world x, y, z [m], 0 outside the sheet";
  }
  if (has("normal")) {
    spawn([&] {
      if (!cast) normal = decode_normal(raw(RawPass::normal), mask);
      write_exr((stage / "normal.exr").string(), normal, {"R", "G", "B"});
    });
    files["normal.exr"] =
        "float32 unit world normal turned towards the camera, 0 outside the sheet";
  }
  if (has("backward")) {
    BackwardParams bp;
    bp.grid_width = j["backward"]["grid_width"];
    bp.grid_height = j["backward"]["grid_height"];
    bp.tolerance_pixels = j["backward"]["tolerance_pixels"];
    spawn([&, bp] {
      const SheetMesh mesh = read_sheet_obj((job / "sheet.obj").string());
      const ImageF map = backward_map(mesh, camera, uv, bp);
      write_exr((stage / "backward.exr").string(), map, {"R", "G", "B"});
      write_npy((stage / "backward.npy").string(), map);
    });
    files["backward.exr"] =
        "float32 grid over the flat page (row 0 = top): R, G = pixel x, y, B = visible";
    files["backward.npy"] = "float32 (grid_height, grid_width, 3): pixel x, y, visible";
    meta["backward"] = j["backward"];
  }
  wait_all();
  const std::string doc = j.at("document_file").get<std::string>();
  if (fs::exists(job / doc)) {
    // Re-encoded: POV-Ray's PNG carries a creation time, which would break reproducibility.
    if (is_png_file((job / doc).string()))
      write_png((stage / doc).string(), read_png((job / doc).string()), 8);
    else
      fs::copy_file(job / doc, stage / doc, fs::copy_options::overwrite_existing);
    files[doc] = "the flat document page (sRGB)";
  }
  meta["passes"] = j.at("passes");
  meta["fine_passes"] = fine;
  files["meta.json"] = "this file";
  meta["files"] = files;
  meta["layout"] = "scenegen";
  if (j.value("layout", "scenegen") == "syntheticdoc") {
    apply_syntheticdoc_layout(stage, meta);
    write_text(stage / "metadata.json", json_text(meta));
  } else {
    write_text(stage / "meta.json", json_text(meta));
  }
}

/// Remove the sample_output_names() of `out` that are not in `keep`. @throw common::OutputError
void remove_stale_outputs(const fs::path& out, const std::vector<std::string>& keep) {
  for (const std::string& name : sample_output_names()) {
    if (std::find(keep.begin(), keep.end(), name) != keep.end()) continue;
    std::error_code ec;
    fs::remove_all(out / name, ec);
    if (ec)
      throw common::OutputError("cannot remove '" + (out / name).string() + "': " + ec.message());
  }
}

/// Move every file of `stage` into `out` (rename; meta.json last, after the outputs of an
/// earlier sample that this one does not replace are gone), then remove `stage`.
void publish(const fs::path& stage, const fs::path& out) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(stage)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) {
    return (a == "meta.json") < (b == "meta.json") ||
           ((a == "meta.json") == (b == "meta.json") && a < b);
  });
  std::vector<std::string> keep = names;
  keep.erase(std::remove(keep.begin(), keep.end(), "meta.json"), keep.end());
  remove_stale_outputs(out, keep);  // the old meta.json first of all
  for (const auto& name : names) {
    std::error_code ec;
    fs::rename(stage / name, out / name, ec);
    if (ec)
      throw common::OutputError("cannot move '" + (stage / name).string() + "' into '" +
                                out.string() + "': " + ec.message());
  }
  remove_quietly(stage);
}

constexpr const char* JOB_NAME = ".scenegen-job";
constexpr const char* STAGE_NAME = ".scenegen-stage";

}  // namespace

const std::vector<std::string>& sample_output_names() {
  static const std::vector<std::string> NAMES = {
      "image.png",    "shading.png", "albedo.png",   "uv.exr",       "coords.exr",
      "normal.exr",   "mask.png",    "backward.exr", "backward.npy", "document.png",
      "document.jpg", "job",         "meta.json"};
  return NAMES;
}

std::vector<std::string> render_staging_paths(const std::string& out_dir) {
  const fs::path out(out_dir);
  return {(out / JOB_NAME).string(), (out / JOB_NAME).string() + ".partial",
          (out / STAGE_NAME).string()};
}

void finish_job(const std::string& job_dir, const std::string& out_dir) {
  const fs::path out(out_dir);
  std::error_code ec;
  const bool created = !fs::exists(out);
  fs::create_directories(out, ec);
  if (ec) throw common::OutputError("cannot create '" + out_dir + "': " + ec.message());
  const fs::path stage = out / STAGE_NAME;
  remove_quietly(stage);
  fs::create_directories(stage, ec);
  if (ec) throw common::OutputError("cannot create '" + stage.string() + "': " + ec.message());
  try {
    finish_into(job_dir, stage);
    publish(stage, out);
  } catch (...) {
    remove_quietly(stage);
    if (created) remove_quietly(out);
    throw;
  }
}

RunReport render_sample(const SampleOptions& options, const std::string& out_dir,
                        const RunOptions& run, bool keep_job) {
  const fs::path out(out_dir);
  const bool created = !fs::exists(out);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw common::OutputError("cannot create '" + out_dir + "': " + ec.message());
  for (const std::string& p : render_staging_paths(out_dir)) remove_quietly(p);  // left by SIGKILL
  const fs::path job = out / JOB_NAME;
  try {
    try {
      prepare_job(options, job.string());
    } catch (const NoValidCameraError&) {
      remove_stale_outputs(out, {});
      write_text(out / "meta.json", failed_meta());
      throw;
    }
    RunReport report = run_job(job.string(), run);
    finish_job(job.string(), out_dir);
    if (keep_job) {
      remove_quietly(out / "job");
      fs::rename(job, out / "job", ec);
      if (ec)
        throw common::OutputError("cannot move the job folder to '" + (out / "job").string() +
                                  "': " + ec.message());
    } else {
      remove_quietly(job);
    }
    return report;
  } catch (const NoValidCameraError&) {
    remove_quietly(job);
    throw;
  } catch (...) {
    remove_quietly(job);
    if (created) remove_quietly(out);
    throw;
  }
}

std::vector<std::string> layout_names() { return {"scenegen", "syntheticdoc"}; }

RunReport render_views(const SampleOptions& options, int views, const std::string& out_dir,
                       const RunOptions& run, bool keep_job) {
  if (views < 1) throw InputError("--views must be at least 1 (got " + std::to_string(views) + ")");
  if (views == 1) return render_sample(options, out_dir, run, keep_job);
  RunReport total;
  for (int k = 0; k < views; ++k) {
    SampleOptions o = options;
    o.view = k;
    char name[32];
    std::snprintf(name, sizeof name, "view_%02d", k);
    const RunReport r = render_sample(o, (fs::path(out_dir) / name).string(), run, keep_job);
    for (const auto& [pass, sec] : r.seconds)
      total.seconds.emplace_back(std::string(name) + "/" + pass, sec);
  }
  return total;
}

}  // namespace papersim::scenegen
