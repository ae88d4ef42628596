#pragma once
/// `scenegen batch DATASET`: render every finished mesh of a dataset K times, one child
/// `scenegen render` per view, resumable and failure-isolated like `papersim batch`
/// (batch/runner.hpp). Views go to renders/<scenario>/<seed/1000>/<seed>/view<k>/; renders.jsonl
/// has one row per finished view, renders_failures.jsonl one per failed attempt.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "batch/runner.hpp"
#include "scenegen/sheet_obj.hpp"

namespace papersim::scenegen {

/// What every view of a render batch shares.
struct RenderBatchOptions {
  int views = 4;      ///< renders per mesh (>= 1)
  bool flip = false;  ///< odd views show the flipped sheet (u -> 1 - u, seen from the back)
  std::string size = "1024x1440";  ///< WIDTHxHEIGHT [pixels]
  std::string quality = "final";   ///< draft | final | best
  std::string passes = "all";      ///< as scenegen render --passes
  std::string documents_dir;       ///< folder of pages to draw from (empty: built-in generator)
  std::string backgrounds_dir;     ///< folder of background images (empty: procedural only)
  int threads = 1;                 ///< POV-Ray threads per view (1 keeps radiosity reproducible)
  int dpi = 0;                     ///< built-in page resolution [dpi]; 0: scenegen render's default
};

/// The sheet seen from its other side: turned over about the material y axis (x -> -x,
/// z -> -z, a rotation, so nothing is mirrored in space) with u -> 1 - u, so the document is
/// printed, readable, on the side that now faces up.
SheetMesh flipped_sheet(const SheetMesh& mesh);

/// The render seed of view `view` of mesh (scenario, seed): a fixed hash, so shards agree.
std::uint64_t view_seed(const std::string& scenario, std::uint64_t seed, int view);

/// Progress of a walk over root/meshes/: called after each bucket folder
/// (meshes/<scenario>/<bucket>/) with the folders done, the folders in all, and the finished meshes
/// found so far.
using ListProgress = std::function<void(std::size_t done, std::size_t buckets, std::size_t meshes)>;

/// One task per (finished mesh, view) under root/meshes/<scenario>/<bucket>/<seed>/sheet.obj,
/// sorted by scenario, then seed, then view; of these, the positions `shard` holds. The meshes
/// are those of `mesh_list` (write_mesh_list) when it is given, without a look at their folders;
/// otherwise those found by walking root/meshes/ (one `stat` a mesh), telling `progress`.
/// @throw InputError when views < 1, when a seed is in two folders, or naming the line of
///        `mesh_list` that is malformed or out of order
batch::TaskList render_tasks(const std::filesystem::path& root, const RenderBatchOptions& options,
                             const batch::Shard& shard = {},
                             const std::filesystem::path& mesh_list = {},
                             const ListProgress& progress = {});

/// Walk root/meshes/ once and write its finished meshes to `file` (through a temporary and a
/// rename): a first line "# scenegen batch mesh list: N meshes", then one
/// "meshes/<scenario>/<bucket>/<seed>" a line, sorted by scenario, then seed. Every array task of
/// a Slurm batch reads this list instead of walking the dataset, so all shard the same list. The
/// walk tells `progress`.
/// @return the number of meshes
/// @throw InputError when a seed is in two folders or a folder's path has a line break;
///        common::OutputError when `file` cannot be written
std::size_t write_mesh_list(const std::filesystem::path& root, const std::filesystem::path& file,
                            const ListProgress& progress = {});

/// The number of meshes of a mesh list, checked as render_tasks checks it. @throw InputError
std::size_t mesh_list_size(const std::filesystem::path& file);

/// Hooks: prepare writes the flipped OBJ for flipped views, the command is
/// `scenegen render MESH --out ... --seed S --parallel 1 --threads T --quiet ...`.
/// @param scenegen the scenegen executable the children run
batch::BatchSpec render_batch_spec(const std::filesystem::path& root,
                                   const std::filesystem::path& scenegen,
                                   const RenderBatchOptions& options);

}  // namespace papersim::scenegen
