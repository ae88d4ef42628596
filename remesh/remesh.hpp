#pragma once
/// Adaptive anisotropic remeshing of the sheet (Narain, Samii, O'Brien 2012, "Adaptive
/// anisotropic remeshing for cloth simulation", the method of ArcSim).
///
/// A sizing metric M (2 x 2, symmetric positive definite, material space [1/m^2]) is computed per
/// face from the world state; an edge with material vector u has the size l^2 = u^T M u under it
/// (M the mean of its end vertices' metrics) and wants splitting when l^2 > 1. One pass of
/// remesh() splits every edge that is too long (longest first), flips edges to the anisotropic
/// Delaunay condition, collapses edges wherever the result has no edge longer than 0.9 under the
/// metric, flips again, and repairs slivers (faces thinner than half of aspect_min, which midpoint
/// splits next to the boundary leave: no flip can reach them there) by a collapse that makes the
/// neighbourhood less thin. Every edit goes through one MeshEditor (mesh_editor.hpp), which
/// carries every attribute across it and hands each proposed edit to a caller's veto first.
#include <Eigen/Core>
#include <array>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "remesh/sheet_mesh.hpp"

namespace papersim::remesh {

/// Parameters of the sizing metric and of the remeshing pass. Defaults are the reference values
/// of the published pipeline (refine_angle 0.2 rad, refine_compression 1e-4, edges 3-100 mm,
/// minimum aspect 0.2, velocity criterion off).
struct RemeshParams {
  /// [rad] dihedral angle an edge may span (curvature criterion): across a bend of radius R the
  /// wanted edge length is refine_angle * R. Must be > 0.
  double refine_angle = 0.2;
  /// [m] compression criterion of ArcSim, <= 0 off: an edge of length l under compressive
  /// Green strain e is split when l^2 |e| > refine_compression^2, i.e. when a buckle of
  /// amplitude about refine_compression could hide inside it. Curvature lowers the demand. On a
  /// face coarser than 2 pi refine_compression / refine_angle the demand is relative to the
  /// face (compression_metric_at_resolution, sizing.hpp): a face is refined only when it holds
  /// more compression than a buckle on its own edges could take up (|e| > (refine_angle /
  /// 2 pi)^2, 1.0e-3 at 0.2 rad), and only to the edges that buckle needs.
  double refine_compression = 1e-4;
  /// [m/s] velocity difference an edge may span (velocity-gradient criterion), <= 0 off.
  double refine_velocity = 0.0;
  /// [m] only vertices closer than this to an obstacle (RemeshState::obstacle_distance) ask for
  /// refinement: edges no longer than d / |grad d| along the direction in which the distance d
  /// changes (ArcSim's obstacle metric from a per-vertex distance), <= 0 off.
  double obstacle_distance = 0.0;
  double size_min = 3e-3;   ///< [m] shortest edge the metric asks for (> 0)
  double size_max = 0.1;    ///< [m] longest edge the metric allows (>= size_min)
  double aspect_min = 0.2;  ///< [-] smallest aspect ratio of the metric, and of a face a
                            ///< collapse may create (12 sqrt(3) area / perimeter^2), in (0, 1]
  /// [rad] no flip across a hinge whose world dihedral angle (or the one the flip would create)
  /// exceeds this: a flip there would cut a crease (ArcSim 0.2 uses 40 degrees). In (0, pi].
  double flip_angle_max = 0.7;
  /// Refuse a split that would make a face thinner than half of aspect_min (the sliver phase's
  /// threshold) unless a face it replaces is thinner already ("thin split"). A midpoint split of
  /// an edge that is not its face's longest halves the face across its length; where the flips
  /// that would repair the halves are refused (across a sharp hinge, or by the caller's veto on a
  /// bent or stretched sheet) repeated splits leave slivers down to the editor's floor, which the
  /// sliver phase cannot collapse there either.
  bool refuse_thin_splits = false;
};

/// The per-vertex state carried through the edits, indexed by vertex (#V rows).
struct RemeshState {
  Eigen::MatrixX3d positions;   ///< world positions [m], #V by 3
  Eigen::MatrixX3d velocities;  ///< [m/s], #V by 3
  /// Distance to the nearest obstacle [m], #V (input of the sizing; may be empty). When given it
  /// is carried like the positions (linear on split), so it keeps #V rows: recompute it before
  /// relying on it again.
  Eigen::VectorXd obstacle_distance;
  /// Membrane Green strain per face (e_xx, e_yy, e_xy) [-], #F (input of the compression
  /// criterion; may be empty: then the chords' strain from the positions). For a membrane that
  /// does not measure its strain on the chords (the simulation's arc model, which counts a face
  /// bent smoothly as unstrained). Read once at the start of a pass; the edits change the faces,
  /// so remesh() empties it.
  Eigen::MatrixX3d membrane_strain;
};

enum class EditKind { split, flip, collapse };

class MeshEditor;

/// What an edit would create, handed to the caller's veto before it is applied.
struct EditProposal {
  EditKind kind = EditKind::split;
  /// The faces the edit creates (counter-clockwise in material space): corner vertex indices in
  /// the mesh as it is before the edit (the editor's working mesh, see MeshEditor), -1 for the
  /// vertex a split inserts.
  std::vector<std::array<int, 3>> vertices;
  std::vector<Eigen::Matrix3d> world;                 ///< per new face, rows = corners [m]
  std::vector<Eigen::Matrix<double, 3, 2>> material;  ///< per new face, rows = corners [m]
  /// Face indices the edit removes or rewrites (working mesh).
  std::vector<int> removed_faces;
  /// The editor proposing the edit: its working mesh and world positions, for checks against
  /// the rest of the sheet. Never null inside a veto.
  const MeshEditor* editor = nullptr;
};

/// Returns an empty string to allow the edit, or the reason it is refused (counted per reason as
/// "veto: <reason>"). It is asked only about edits that passed every other check, once per
/// attempt (a pass of a 1,300-vertex sheet asks it about 2,000 times). It may throw: remesh()
/// then leaves its inputs untouched.
using EditVeto = std::function<std::string(const EditProposal&)>;

/// Edits applied and refused in one pass. Refusal reasons of the editor: "topology" (OpenMesh link
/// condition), "boundary" (would move a boundary vertex off the boundary or remove a corner of the
/// sheet), "inverted" (a new face with non-positive area in material space), "degenerate" (a new
/// face with aspect ratio below EDIT_ASPECT_MIN = 0.01, mesh_editor.hpp); of the remesh loop:
/// "crease" (a flip across, or making, a hinge sharper than flip_angle_max), "thin split"
/// (RemeshParams::refuse_thin_splits), "too long" (a collapse
/// would make an edge longer than 0.9 under the metric), "too thin" (a collapse would make a face
/// with aspect below aspect_min), "no better" (a sliver repair whose thinnest new face is no
/// thicker than the thinnest face it removes); of the caller: "veto: <reason>". Counts are per
/// attempt: the loop tries to collapse every short edge both ways, so "too long" and "boundary" run
/// into the thousands on a 1,300-vertex sheet.
struct RemeshStats {
  int splits = 0, flips = 0, collapses = 0;
  std::map<std::string, int> refusals;
};

/// One remeshing pass (split, flip, collapse, flip, sliver repair) of `mesh` and `state`. Vertices
/// and faces are renumbered (garbage collected); material coordinates are exact (new vertices at
/// edge midpoints, boundary vertices stay on the boundary, corners stay); positions, velocities and
/// obstacle distances are linear on split, kept on collapse; plastic curvature and damage are
/// transferred by material area so their area integrals are conserved.
/// @throw ParameterError when a parameter is out of range (the message names it).
/// @throw MeshError when the state does not have one row per vertex or holds NaN or inf.
RemeshStats remesh(SheetMesh& mesh, RemeshState& state, const RemeshParams& params,
                   const EditVeto& veto = {});

/// The sizing metric per face (#F, each 2 x 2 symmetric positive definite, material space
/// [1/m^2]): the anisotropic maximum of the curvature (of the world shape, and the plastic
/// curvature the face carries, as ArcSim's plastic-space curvature, so a crease stays refined
/// when it is pressed flat or unfolded), compression, velocity and obstacle metrics, its
/// eigenvalues clamped to [1/size_max^2, 1/size_min^2] and to an aspect of at least aspect_min.
/// Exposed for tests.
/// @throw ParameterError, MeshError as remesh().
std::vector<Eigen::Matrix2d> sizing(const SheetMesh& mesh, const RemeshState& state,
                                    const RemeshParams& params);

/// The criteria of one face's sizing before they are combined and clamped, each a 2 x 2
/// symmetric positive semi-definite metric in material space [1/m^2] (zero when off): an edge u
/// is as long as a criterion allows when u^T M u = 1.
struct SizingTerms {
  Eigen::Matrix2d curvature = Eigen::Matrix2d::Zero();  ///< world shape: S^T S / refine_angle^2
  /// plastic curvature: Kp^T Kp / refine_angle^2
  Eigen::Matrix2d plastic = Eigen::Matrix2d::Zero();
  Eigen::Matrix2d compression = Eigen::Matrix2d::Zero();  ///< membrane compression (ArcSim)
  Eigen::Matrix2d velocity = Eigen::Matrix2d::Zero();     ///< velocity gradient
  Eigen::Matrix2d obstacle = Eigen::Matrix2d::Zero();     ///< obstacle proximity
};

/// The criteria per face (#F), unclamped: sizing() is clamp_metric(tensor_max of these). Exposed
/// for tests and for diagnostics that ask which criterion refines a mesh.
/// @throw ParameterError, MeshError as remesh().
std::vector<SizingTerms> sizing_terms(const SheetMesh& mesh, const RemeshState& state,
                                      const RemeshParams& params);

/// Checks the parameters. @throw ParameterError naming the first one out of range.
void check_params(const RemeshParams& params);

/// Checks that the state has one finite row per vertex of `mesh`.
/// @throw MeshError naming the array and the vertex.
void check_state(const SheetMesh& mesh, const RemeshState& state);

}  // namespace papersim::remesh
