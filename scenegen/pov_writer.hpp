#pragma once
/// Writers of the generated POV-Ray text: the sheet as a mesh2, the per-sample scene.inc and
/// one .ini per pass. All take std::ostream& so the text is golden-file tested.
#include <Eigen/Core>
#include <iosfwd>
#include <string>

#include "scenegen/camera.hpp"
#include "scenegen/passes.hpp"
#include "scenegen/resting_pose.hpp"
#include "scenegen/scene_draw.hpp"
#include "scenegen/sheet_obj.hpp"

namespace papersim::scenegen {

/// Render quality of the lit passes (image, shading). Ground-truth passes ignore it.
/// best: final with smooth penumbrae (3 x 3 jittered area-light samples at adaptive depth 0
/// instead of 2 x 2, whose four hard shadow copies show as steps where a raised part shadows
/// the table; docs/scenegen.md, "Penumbrae").
enum class Quality { draft, final, best };

/// Settings of the lit passes per quality.
struct QualitySettings {
  bool radiosity = false;        ///< final: radiosity (1 bounce)
  int radiosity_count = 35;      ///< rays per radiosity sample
  double radiosity_error = 1.8;  ///< error_bound
  int radiosity_nearest = 5;     ///< nearest_count: samples averaged per lookup
  /// pretrace_end (pretrace_start 0.08; each pass halves it)
  double radiosity_pretrace_end = 0.02;
  int area_samples = 1;   ///< area light samples per side (1: point lights)
  int area_adaptive = 1;  ///< adaptive depth of area lights
  /// Jittered area-light samples (POV-Ray `jitter`, over the drawn light: lights.inc shortens
  /// the axes by (n - 1) / n): a smooth, slightly grainy penumbra instead of area_samples^2
  /// overlapping hard shadows; reproducible for a single-threaded render.
  bool area_jitter = false;
  /// Lights whose intensity is below this share of the rig's summed intensity get
  /// `dim_area_samples` per side instead of `area_samples` (1: point light; 0: point light
  /// that casts no shadow, POV-Ray `shadowless`). 0: every light gets `area_samples`.
  double dim_light_share = 0.0;
  int dim_area_samples = 1;
  bool antialias = false;    ///< image pass only (non-jittered adaptive supersampling)
  int antialias_method = 2;  ///< POV-Ray Sampling_Method: 1 (non-adaptive) or 2 (adaptive)
  double antialias_threshold = 0.1;
  int antialias_depth = 1;  ///< 1: corner samples shared by neighbouring pixels (cheap)
  double ambient = 0.12;    ///< ambient fill when radiosity is off
  /// Row bands of each lit render (photo, shading): one POV-Ray process per band, so one
  /// single-threaded (reproducible) render uses several cores. Radiosity is sampled per band
  /// (the pretrace covers the band's rows), so the count is part of the sample.
  int bands = 2;
};
/// Settings used for a quality level.
QualitySettings quality_settings(Quality q);
/// "draft" / "final" / "best". @throw InputError for other names.
Quality parse_quality(const std::string& name);
std::string quality_name(Quality q);

/// The contact shadow on the table (contact_shadow.hpp): a map of the sheet's occlusion of the
/// sky over the stage plane, multiplied into the table's lit colour as 1 - strength x occlusion.
struct ContactShadowDecl {
  bool enabled = false;
  std::string file = "contact.png";  ///< in the job folder
  double x0 = 0.0, y0 = 0.0;         ///< stage coordinates of the map's lower-left corner [m]
  double width = 0.0, height = 0.0;  ///< extent of the map [m]
  double strength = 0.0;             ///< share of the table's light the occlusion removes
};

/// Everything scene.inc declares for one sample.
struct SceneDescription {
  Camera camera;
  Stage stage;
  LightingDraw lighting;
  BackgroundDraw background;
  PaperDraw paper;
  QualitySettings quality;
  double sheet_width = 0.21, sheet_height = 0.297;       ///< [m]
  std::string document_file = "document.png";            ///< in the job folder
  Eigen::Vector3d coords_min = Eigen::Vector3d::Zero();  ///< coords pass offset [m]
  double coords_span = 1.0;                              ///< coords pass scale [m]
  double background_gap = 3e-4;  ///< background slab below the support plane [m]
  ContactShadowDecl contact;
};

/// Coords pass encoding: offset and span such that (p - min) / span is in [0.01, 0.99).
void set_coords_encoding(SceneDescription& scene, const SheetMesh& mesh);

/// `#declare SG_Sheet_Mesh = mesh2 {...}` with vertex, normal and uv vectors (17 digits).
void write_sheet_inc(std::ostream& out, const SheetMesh& mesh, const Eigen::MatrixX3d& normals);

/// `#declare SG_Sheet_Shadow_Mesh = mesh2 {...}`: the sheet moved by `offset` [m] along -normal
/// (behind the printed side: the paper's back face). The lit passes render the sheet without
/// shadows of its own and let this copy, unseen, cast them, so a faceted surface does not
/// shadow itself where light grazes it (the shadow-terminator artefact; Cycles' "shadow
/// terminator geometry offset" does the same). offset 0: no copy (SG_Shadow_Caster = 0), the
/// sheet casts its own shadows.
void write_shadow_inc(std::ostream& out, const SheetMesh& mesh, const Eigen::MatrixX3d& normals,
                      double offset);

/// scene.inc: every per-sample declaration used by render_templates/main.pov.
void write_scene_inc(std::ostream& out, const SceneDescription& scene);

/// Rows of a render: band `index` of `count` covers rows [index * H / count,
/// (index + 1) * H / count) (integer division); count 1 is the whole image.
struct RowBand {
  int index = 0;
  int count = 1;
  int first_row(int height) const {
    return static_cast<int>(static_cast<long>(index) * height / count);
  }
  int end_row(int height) const {
    return static_cast<int>(static_cast<long>(index + 1) * height / count);
  }
};
/// Name of a render in the job folder: "image" for a whole image, "image_b0", ... for bands.
/// Its .ini is NAME.ini, its output raw_NAME.png.
std::string raw_render_name(RawPass pass, RowBand band);

/// One render's .ini: size, rows, output file, antialiasing, gamma, bit depth, threads.
/// @param threads  POV-Ray worker threads (0: POV-Ray's default)
void write_pass_ini(std::ostream& out, RawPass pass, int width, int height,
                    const QualitySettings& quality, int threads, RowBand band = {});

/// The built-in document's .ini (antialiased, 8-bit sRGB PNG).
void write_document_ini(std::ostream& out, int width_px, int height_px, int threads);

}  // namespace papersim::scenegen
