#include "scenegen/pov_writer.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <ostream>

#include "scenegen/errors.hpp"

namespace papersim::scenegen {
namespace {

/// Shortest text that reads back as the same double: "%.*g" at the lowest precision from 6 that
/// does. The search starts at the significant digits of the shortest round-trip form
/// (std::to_chars): no lower precision reads back, and trying each from 6 cost a quarter of
/// `prepare` (the mesh2 of the refined surface). The text is the same as trying each.
std::string num(double v) {
  if (v == 0.0) v = 0.0;  // no "-0"
  char buf[40];
  int start = 6;
  if (v != 0.0 && std::isfinite(v)) {
    char shortest[40];
    const auto res =
        std::to_chars(shortest, shortest + sizeof shortest, v, std::chars_format::scientific);
    int first = -1, last = -1, digits = 0;  // significant digits: first to last nonzero digit
    for (const char* c = shortest; c != res.ptr && *c != 'e'; ++c) {
      if (*c < '0' || *c > '9') continue;
      if (*c != '0') {
        if (first < 0) first = digits;
        last = digits;
      }
      ++digits;
    }
    if (first >= 0) start = std::clamp(last - first + 1, start, 17);
  }
  for (int prec = start; prec <= 17; ++prec) {
    std::snprintf(buf, sizeof buf, "%.*g", prec, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

std::string vec(const Eigen::Vector3d& v) {
  return "<" + num(v.x()) + ", " + num(v.y()) + ", " + num(v.z()) + ">";
}

int background_kind_id(const std::string& kind) {
  const char* kinds[] = {"wood", "marble", "granite", "fabric", "cork", "concrete", "image"};
  for (int i = 0; i < 7; ++i)
    if (kind == kinds[i]) return i + 1;
  throw InputError("unknown background kind '" + kind + "'");
}

std::string image_type(const std::string& file) {
  const auto dot = file.rfind('.');
  const std::string ext = dot == std::string::npos ? "" : file.substr(dot + 1);
  return (ext == "jpg" || ext == "jpeg" || ext == "JPG" || ext == "JPEG") ? "jpeg" : "png";
}

void write_camera(std::ostream& out, const Camera& cam) {
  // POV-Ray traces direction + x0 right + y0 up with x0 = (i + 0.5) / W - 0.5 and
  // y0 = 0.5 - (j + 0.5) / H at pixel (i, j): the pinhole of Camera::project.
  out << "#declare SG_Cam_Location = " << vec(cam.position) << ";\n"
      << "#declare SG_Cam_Direction = " << vec(cam.forward) << ";\n"
      << "#declare SG_Cam_Right = " << vec(cam.right * (cam.width / cam.focal_px)) << ";\n"
      << "#declare SG_Cam_Up = " << vec(cam.up * (cam.height / cam.focal_px)) << ";\n";
}

void write_lighting(std::ostream& out, const SceneDescription& s) {
  const LightingDraw& l = s.lighting;
  out << "// lighting: rig " << l.rig << ", rotated " << num(l.rotation_deg) << " deg, "
      << l.temperature << "\n"
      << "#declare SG_Light_Colour = " << vec(l.colour) << ";\n"
      << "#declare SG_Sky = " << num(l.sky) << ";\n"
      << "#declare SG_Area_Samples = " << s.quality.area_samples << ";\n"
      << "#declare SG_Area_Adaptive = " << s.quality.area_adaptive << ";\n"
      << "#declare SG_Area_Jitter = " << (s.quality.area_jitter ? 1 : 0) << ";\n"
      << "#macro SG_Lights()\n";
  double total = 0;
  for (const Light& light : l.lights) total += light.intensity;
  for (const Light& light : l.lights) {
    const bool dim = light.intensity < s.quality.dim_light_share * total;
    out << (dim ? "  SG_Light_Samples(" : "  SG_Light(") << vec(light.position) << ", "
        << num(light.size) << ", " << num(light.intensity) << ", " << num(light.fade_distance);
    if (dim) out << ", " << s.quality.dim_area_samples;
    out << ")  // " << light.name << ", " << num(light.power) << " W\n";
  }
  out << "#end\n";
}

void write_background(std::ostream& out, const SceneDescription& s) {
  const BackgroundDraw& b = s.background;
  const Stage& st = s.stage;
  out << "// background: " << b.kind << "\n"
      << "#declare SG_Bg_Kind = " << background_kind_id(b.kind) << ";\n"
      << "#declare SG_Bg_Colour_A = " << vec(b.colour_a) << ";\n"
      << "#declare SG_Bg_Colour_B = " << vec(b.colour_b) << ";\n"
      << "#declare SG_Bg_Scale = " << num(b.scale) << ";\n"
      << "#declare SG_Bg_Rotation = " << num(b.rotation_deg) << ";\n"
      << "#declare SG_Bg_Offset = <" << num(b.offset.x()) << ", " << num(b.offset.y()) << ">;\n"
      << "#declare SG_Bg_Roughness = " << num(b.roughness) << ";\n"
      << "#declare SG_Bg_Noise_Offset = " << vec(b.noise_offset) << ";\n"
      << "#declare SG_Bg_Gap = " << num(s.background_gap) << ";\n";
  if (b.kind == "image")
    out << "#declare SG_Bg_Image_File = \"" << b.image << "\";\n"
        << "#declare SG_Bg_Image_Size = " << num(b.image_size) << ";\n"
        << "#macro SG_Bg_Image_Type() " << image_type(b.image) << " #end\n";
  out << "#declare SG_Stage_Transform = transform { matrix <" << num(st.ex.x()) << ", "
      << num(st.ex.y()) << ", " << num(st.ex.z()) << ", " << num(st.ey.x()) << ", "
      << num(st.ey.y()) << ", " << num(st.ey.z()) << ", " << num(st.up.x()) << ", "
      << num(st.up.y()) << ", " << num(st.up.z()) << ", " << num(st.origin.x()) << ", "
      << num(st.origin.y()) << ", " << num(st.origin.z()) << "> }\n";
}

void write_paper(std::ostream& out, const SceneDescription& s) {
  const PaperDraw& p = s.paper;
  out << "#declare SG_Sheet_Width = " << num(s.sheet_width) << ";\n"
      << "#declare SG_Sheet_Height = " << num(s.sheet_height) << ";\n"
      << "#declare SG_Document_File = \"" << s.document_file << "\";\n"
      << "#macro SG_Document_Type() " << image_type(s.document_file) << " #end\n"
      << "#declare SG_Paper_Colour = " << vec(p.colour) << ";\n"
      << "#declare SG_Ink_Floor = " << num(p.ink_floor) << ";\n"
      << "#declare SG_Wave_Amplitude = " << num(p.wave_amplitude) << ";\n"
      << "#declare SG_Wave_Scale = " << num(p.wave_scale) << ";\n"
      << "#declare SG_Wave_Offset = " << vec(p.wave_offset) << ";\n"
      << "#declare SG_Grain_Amplitude = " << num(p.grain_amplitude) << ";\n"
      << "#declare SG_Grain_Scale = " << num(p.grain_scale) << ";\n"
      << "#declare SG_Grain_Offset = " << vec(p.grain_offset) << ";\n"
      << "#declare SG_Crease_Strength = " << num(p.crease_strength) << ";\n"
      << "#declare SG_Crease_Scale = " << num(p.crease_scale) << ";\n"
      << "#declare SG_Crease_Offset = " << vec(p.crease_offset) << ";\n"
      << "#declare SG_Roughness_Ink = " << num(p.roughness_ink) << ";\n"
      << "#declare SG_Roughness_Paper = " << num(p.roughness_paper) << ";\n";
}

void write_contact(std::ostream& out, const ContactShadowDecl& c) {
  out << "#declare SG_Contact = " << (c.enabled ? 1 : 0) << ";\n";
  if (!c.enabled) return;
  out << "#declare SG_Contact_File = \"" << c.file << "\";\n"
      << "#declare SG_Contact_Origin = <" << num(c.x0) << ", " << num(c.y0) << ">;\n"
      << "#declare SG_Contact_Size = <" << num(c.width) << ", " << num(c.height) << ">;\n"
      << "#declare SG_Contact_Strength = " << num(c.strength) << ";\n";
}

}  // namespace

QualitySettings quality_settings(Quality q) {
  QualitySettings s;
  if (q == Quality::final || q == Quality::best) {
    // Chosen on scenegen_quality_study's front (docs/scenegen.md, "Render time against image
    // error"): the photo's error is mostly antialiasing, so a second antialiasing level where
    // neighbours differ by more than 0.8 buys more than 3 x 3 area-light samples cost.
    // Radiosity lookups were ~40% of the photo's trace (each lookup examined nearly every
    // sample): nearest_count 2 and a pretrace to 0.04 took about a quarter off the photo's CPU;
    // nearest_count 1 examines a quarter fewer radiosity blocks than 2 (27.9 M against 36.5 M,
    // photo of scenegen example fold at 512 x 720), and with antialiasing threshold 0.8 the
    // photo is as close to the converged reference (34.79 against 34.73 dB).
    s.radiosity = true;
    s.radiosity_nearest = 1;
    s.radiosity_pretrace_end = 0.04;
    // 2 x 2 jittered area-light samples: without jitter they give four overlapping hard
    // shadows (a raised part's penumbra in three bands); jittered over the drawn light (the
    // axes shortened in lights.inc) the penumbra is a smooth, slightly grainy ramp at the
    // same number of shadow rays (docs/scenegen.md, "Penumbrae").
    s.area_samples = 2;
    s.area_adaptive = 1;
    s.area_jitter = true;
    s.antialias = true;
    s.antialias_threshold = 0.8;
    s.antialias_depth = 2;
    s.ambient = 0.0;
    if (q == Quality::best) {
      // Adaptive depth 0 starts from the grid's four corners, so lit and fully shadowed
      // pixels cost what 2 x 2 cost; penumbrae get up to 9 jittered samples per light (less
      // grain than final's 4).
      s.area_samples = 3;
      s.area_adaptive = 0;
    }
  } else {
    s.area_samples = 2;
  }
  return s;
}

Quality parse_quality(const std::string& name) {
  if (name == "draft") return Quality::draft;
  if (name == "final") return Quality::final;
  if (name == "best") return Quality::best;
  throw InputError("unknown quality '" + name + "' (draft, final, best)");
}

std::string quality_name(Quality q) {
  return q == Quality::best ? "best" : q == Quality::final ? "final" : "draft";
}

void set_coords_encoding(SceneDescription& scene, const SheetMesh& mesh) {
  const Eigen::Vector3d lo = mesh.positions.colwise().minCoeff().transpose();
  const Eigen::Vector3d hi = mesh.positions.colwise().maxCoeff().transpose();
  const double extent = std::max((hi - lo).maxCoeff(), 1e-3);
  scene.coords_span = extent / 0.98;
  scene.coords_min = lo - Eigen::Vector3d::Constant(0.01 * scene.coords_span);
}

void write_sheet_inc(std::ostream& out, const SheetMesh& mesh, const Eigen::MatrixX3d& normals) {
  const int nv = mesh.num_vertices();
  out << "// papersim scenegen: the sheet, world positions [m], unit normals, exact material UV\n"
      << "#declare SG_Sheet_Mesh = mesh2 {\n  vertex_vectors { " << nv;
  for (int i = 0; i < nv; ++i) out << ",\n    " << vec(mesh.positions.row(i).transpose());
  out << " }\n  normal_vectors { " << nv;
  for (int i = 0; i < nv; ++i) out << ",\n    " << vec(normals.row(i).transpose());
  out << " }\n  uv_vectors { " << nv;
  for (int i = 0; i < nv; ++i)
    out << ",\n    <" << num(mesh.uv(i, 0)) << ", " << num(mesh.uv(i, 1)) << ">";
  out << " }\n  face_indices { " << mesh.num_faces();
  for (int f = 0; f < mesh.num_faces(); ++f)
    out << ",\n    <" << mesh.faces(f, 0) << ", " << mesh.faces(f, 1) << ", " << mesh.faces(f, 2)
        << ">";
  out << " }\n}\n";
}

void write_shadow_inc(std::ostream& out, const SheetMesh& mesh, const Eigen::MatrixX3d& normals,
                      double offset) {
  if (offset <= 0.0) {
    out << "// papersim scenegen: no shadow caster, the sheet casts its own shadows\n"
        << "#declare SG_Shadow_Caster = 0;\n";
    return;
  }
  const int nv = mesh.num_vertices();
  out << "#declare SG_Shadow_Caster = 1;\n// papersim scenegen: shadow caster, the sheet moved "
      << num(offset)
      << " m behind its printed side\n#declare SG_Sheet_Shadow_Mesh = mesh2 {\n  vertex_vectors { "
      << nv;
  for (int i = 0; i < nv; ++i)
    out << ",\n    " << vec((mesh.positions.row(i) - offset * normals.row(i)).transpose());
  out << " }\n  face_indices { " << mesh.num_faces();
  for (int f = 0; f < mesh.num_faces(); ++f)
    out << ",\n    <" << mesh.faces(f, 0) << ", " << mesh.faces(f, 1) << ", " << mesh.faces(f, 2)
        << ">";
  out << " }\n}\n";
}

void write_scene_inc(std::ostream& out, const SceneDescription& s) {
  out << "// papersim scenegen: per-sample declarations (generated; see meta.json)\n";
  write_camera(out, s.camera);
  out << "#declare SG_Radiosity = " << (s.quality.radiosity ? 1 : 0) << ";\n"
      << "#declare SG_Radiosity_Count = " << s.quality.radiosity_count << ";\n"
      << "#declare SG_Radiosity_Error = " << num(s.quality.radiosity_error) << ";\n"
      << "#declare SG_Radiosity_Nearest = " << s.quality.radiosity_nearest << ";\n"
      << "#declare SG_Radiosity_Pretrace_End = " << num(s.quality.radiosity_pretrace_end) << ";\n"
      << "#declare SG_Ambient = " << num(s.quality.ambient) << ";\n"
      << "#declare SG_Coords_Min = " << vec(s.coords_min) << ";\n"
      << "#declare SG_Coords_Span = " << num(s.coords_span) << ";\n";
  write_lighting(out, s);
  write_background(out, s);
  write_paper(out, s);
  write_contact(out, s.contact);
}

std::string raw_render_name(RawPass pass, RowBand band) {
  return band.count <= 1 ? raw_pass_name(pass)
                         : raw_pass_name(pass) + "_b" + std::to_string(band.index);
}

void write_pass_ini(std::ostream& out, RawPass pass, int width, int height,
                    const QualitySettings& quality, int threads, RowBand band) {
  const bool photo = pass == RawPass::image;
  const std::string name = raw_render_name(pass, band);
  out << "; papersim scenegen: " << raw_pass_name(pass) << " pass";
  if (band.count > 1) out << ", rows band " << band.index + 1 << " of " << band.count;
  out << "\nInput_File_Name=main.pov\n"
      << "Output_File_Name=raw_" << name << ".png\n"
      << "Output_File_Type=N\n"
      << "Width=" << width << "\nHeight=" << height << "\n";
  // POV-Ray rows are 1-based and inclusive; rows outside the band are written black.
  if (band.count > 1)
    out << "Start_Row=" << band.first_row(height) + 1 << "\nEnd_Row=" << band.end_row(height)
        << "\n";
  out << "Declare=SG_PASS=" << static_cast<int>(pass)
      << "\n"
      // Ground truth: linear 16-bit. Photo: 16-bit sRGB (quantised to 8 bits after vignetting).
      << "Bits_Per_Color=16\n"
      << "File_Gamma=" << (photo ? "sRGB" : "1.0") << "\n"
      << "Output_Alpha=Off\n"
      << "Jitter=Off\n";
  if (photo && quality.antialias)
    out << "Antialias=On\nSampling_Method=" << quality.antialias_method
        << "\nAntialias_Threshold=" << num(quality.antialias_threshold)
        << "\nAntialias_Depth=" << quality.antialias_depth << "\n";
  else
    out << "Antialias=Off\n";
  out << "Display=Off\nVerbose=Off\nPause_When_Done=Off\nWarning_Level=0\n";
  if (threads > 0) out << "Work_Threads=" << threads << "\n";
}

void write_document_ini(std::ostream& out, int width_px, int height_px, int threads) {
  out << "; papersim scenegen: built-in document page\n"
      << "Input_File_Name=document.pov\nOutput_File_Name=document.png\nOutput_File_Type=N\n"
      << "Width=" << width_px << "\nHeight=" << height_px << "\n"
      << "Bits_Per_Color=8\nFile_Gamma=sRGB\nOutput_Alpha=Off\n"
      << "Antialias=On\nSampling_Method=2\nAntialias_Threshold=0.05\nAntialias_Depth=3\nJitter="
         "Off\n"
      << "Display=Off\nVerbose=Off\nPause_When_Done=Off\nWarning_Level=0\n";
  // No radiosity: multi-threaded rendering of the page is reproducible.
  if (threads > 0) out << "Work_Threads=" << threads << "\n";
}

}  // namespace papersim::scenegen
