#pragma once
/// A sample from mesh to files: `prepare` writes a self-contained POV-Ray job folder, `run`
/// renders it with POV-Ray alone, `finish` decodes the raw renders into the final files;
/// `render_sample` = prepare + run + finish with no partial output on failure.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "scenegen/camera.hpp"
#include "scenegen/decode.hpp"
#include "scenegen/document.hpp"
#include "scenegen/passes.hpp"
#include "scenegen/pov_writer.hpp"
#include "scenegen/smooth_surface.hpp"

namespace papersim::scenegen {

/// Everything that defines a sample. Same options and seed: identical files.
struct SampleOptions {
  std::string mesh_path;        ///< sheet OBJ with vt
  std::string document;         ///< PNG / JPEG page; empty: documents_dir or built-in
  std::string documents_dir;    ///< draw the page from this folder's PNG / JPEG files
  std::string backgrounds_dir;  ///< add image backgrounds from this folder
  std::uint64_t seed = 0;
  int width = 1024;   ///< [pixels]
  int height = 1440;  ///< [pixels]
  std::vector<Pass> passes = all_passes();
  Quality quality = Quality::final;
  std::optional<QualitySettings>
      quality_override;  ///< replaces quality_settings(quality) (studies)
  GroundTruth ground_truth = GroundTruth::raycast;  ///< uv, coords, normal, mask: cast by
                                                    ///< scenegen or rendered by POV-Ray
  bool fine_passes = true;  ///< povray ground truth: float32-exact uv / coords (two
                            ///< renders each); ray casting is float32-exact anyway
  std::string rig;          ///< light rig; empty: drawn
  CameraParams camera;
  BackwardParams backward;
  double document_dpi = 100.0;  ///< built-in page raster [dpi]: ~1 texel per pixel at 1024 x 1440
  int threads = 1;              ///< threads per POV-Ray process (1: reproducible radiosity)
  std::string templates_dir;    ///< empty: the templates embedded in the binary
  SurfaceParams surface;        ///< smooth render surface through the mesh (PN triangles)
  double shadow_offset = 1e-4;  ///< shadow caster behind the printed side [m] (paper thickness)
  std::string layout = "scenegen";  ///< file names: scenegen | syntheticdoc (the reference's)
  bool flip = false;                ///< render the sheet from its other side (flip_sheet)
  std::vector<Light> lights;        ///< non-empty: these lights replace the drawn rig's (studies,
                                    ///< tests); colour and sky are still drawn
  bool contact_shadow = true;       ///< darken the table where the sheet hides its sky
                                    ///< (contact_shadow.hpp); the ground truth does not change
  bool edge_lift = true;            ///< curl the resting edges of the rendered surface by a drawn
                                    ///< amplitude (edge_lift.hpp; stream "edge_lift", the same
                                    ///< for every view of a sheet)
  int view = 0;                     ///< view index: views > 0 draw camera, lights, background
                                    ///< and paper from their own streams; the page is shared
};

/// What a pass render reports while a job runs.
struct PassProgress {
  std::string pass;
  int index = 0, total = 0;  ///< 1-based index of the render
  double seconds = 0.0;      ///< < 0 when the pass starts, its duration when it ends
};
using ProgressCallback = std::function<void(const PassProgress&)>;

/// Run-time settings (not part of the sample).
struct RunOptions {
  std::string povray = "povray";  ///< POV-Ray 3.7 executable
  ProgressCallback progress;      ///< may be empty
  int parallel = 0;               ///< POV-Ray processes at once (0: one per core)
  /// Polled every few milliseconds while POV-Ray runs; may throw (e.g. common::Interrupted) to
  /// stop: the POV-Ray processes are then killed and the exception passes on.
  std::function<void()> poll_stop;
};

/// Timings of a run [s], per render in order (wall time of each POV-Ray process).
struct RunReport {
  std::vector<std::pair<std::string, double>> seconds;
  double total() const;
};

/// Write a job folder (scene files, templates, fonts, document, one .ini per render, run.sh,
/// job.json). The folder is written under a temporary name and renamed into place.
/// @throw InputError / IoError for bad input, NoValidCameraError (with the failed meta.json
///        text in its what() context, see failed_meta) when no camera direction is valid.
void prepare_job(const SampleOptions& options, const std::string& job_dir);

/// Render every pass of a prepared job with POV-Ray (document page first). POV-Ray processes
/// die with the calling process (even on SIGKILL) and are killed when a render fails.
/// @throw RenderError when POV-Ray fails (with the tail of its log), IoError when the folder is
///        not a job, and whatever run.poll_stop throws.
RunReport run_job(const std::string& job_dir, const RunOptions& run);

/// Decode the raw renders of a job into the final files of `out_dir` (created if needed;
/// files are written under temporary names and renamed). @throw IoError
void finish_job(const std::string& job_dir, const std::string& out_dir);

/// prepare + run + finish. On failure nothing is left in `out_dir` except, when no camera is
/// valid, a meta.json with status "failed" and the evaluation of every candidate (the files of
/// an earlier sample in `out_dir` are then removed). On success `out_dir` holds this sample's
/// files only (see sample_output_names()).
/// @param keep_job  keep the job folder as out_dir/job
RunReport render_sample(const SampleOptions& options, const std::string& out_dir,
                        const RunOptions& run, bool keep_job = false);

/// File layouts of a sample.
std::vector<std::string> layout_names();

/// `views` samples of one mesh in out_dir/view_00, view_01, ... (views = 1: out_dir itself),
/// view k with SampleOptions::view = k: its own camera, lights, background and paper draws, the
/// same document page. @throw as render_sample; views < 1 is an InputError
RunReport render_views(const SampleOptions& options, int views, const std::string& out_dir,
                       const RunOptions& run, bool keep_job = false);
/// Every name render_sample / finish_job may publish in a sample folder. Publishing removes
/// those it did not write, so that a folder never mixes the files of two samples.
const std::vector<std::string>& sample_output_names();

/// The hidden folders render_sample and finish_job stage their work in, inside `out_dir`. A run
/// killed with SIGKILL may leave them; the next render or finish into `out_dir` removes them.
std::vector<std::string> render_staging_paths(const std::string& out_dir);

/// meta.json text of the last NoValidCameraError thrown by prepare_job in this thread.
const std::string& failed_meta();

/// Sorted PNG / JPEG files of a folder (--documents, --backgrounds; `what` names it).
/// @throw IoError when it cannot be listed, InputError when it has none
std::vector<std::filesystem::path> image_files(const std::string& dir, const std::string& what);

/// Parse WIDTHxHEIGHT with both sides in [min_side, MAX_IMAGE_SIDE] (or "full", giving 0 x 0,
/// when `allow_full`); nothing may follow the digits. `what` names the option in errors.
/// @throw InputError
void parse_image_size(const std::string& text, int& width, int& height, const std::string& what,
                      bool allow_full, int min_side);

}  // namespace papersim::scenegen
