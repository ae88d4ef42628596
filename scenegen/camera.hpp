#pragma once
/// The camera: a pinhole matching POV-Ray's perspective camera pixel for pixel, the candidate
/// directions of the reference setup, and the validity test (in frame, facing, not occluded).
#include <Eigen/Core>
#include <vector>

#include "scenegen/random.hpp"
#include "scenegen/resting_pose.hpp"
#include "scenegen/sheet_obj.hpp"

namespace papersim::scenegen {

/// Camera parameters (reference: 50 mm lens on a 36 mm sensor, 0.6 m away).
struct CameraParams {
  double focal_length = 0.050;            ///< [m]
  double sensor_size = 0.036;             ///< [m] along the longer image side
  double distance = 0.6;                  ///< camera to sheet centre of mass [m]
  double margin = 0.02;                   ///< frame margin, fraction of the image width / height
  double max_roll_deg = 8.0;              ///< roll drawn in U[-max, max] [deg]
  double backfacing_angle_deg = 60.0;     ///< a normal turned further away counts as backfacing
  double max_backfacing_fraction = 0.04;  ///< of the vertices
  bool check_occlusion = true;            ///< ray-cast every vertex and face centre
};

/// A pinhole camera. Pixel coordinates: x right, y down, pixel (i, j) covers [i, i+1) x [j, j+1)
/// and its centre is (i + 0.5, j + 0.5), the point POV-Ray traces with antialiasing off.
struct Camera {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< [m] world
  Eigen::Vector3d forward = Eigen::Vector3d::UnitZ();  ///< unit viewing direction
  Eigen::Vector3d right = Eigen::Vector3d::UnitX();    ///< unit, image +x
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();       ///< unit, image -y
  double focal_px = 1000.0;                            ///< focal length [pixels]
  int width = 1024;                                    ///< [pixels]
  int height = 1440;                                   ///< [pixels]

  /// Depth of a world point along `forward` [m] (positive in front of the camera).
  double depth(const Eigen::Vector3d& p) const { return (p - position).dot(forward); }
  /// Pixel coordinates of a world point in front of the camera.
  Eigen::Vector2d project(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = p - position;
    const double z = d.dot(forward);
    return {0.5 * width + focal_px * d.dot(right) / z, 0.5 * height - focal_px * d.dot(up) / z};
  }
  /// Unnormalised world direction of the ray through pixel coordinates (x, y).
  Eigen::Vector3d ray(double x, double y) const {
    return forward + ((x - 0.5 * width) / focal_px) * right - ((y - 0.5 * height) / focal_px) * up;
  }
  /// Vertical field of view [deg].
  double vertical_fov_deg() const;
};

/// One of the 26 candidate directions and how it fared.
struct CameraCandidate {
  double inclination_deg = 0.0;  ///< from the support-plane normal
  double azimuth_deg = 0.0;      ///< 0: camera on the page's bottom side (-y), positive towards +x
  bool in_frame = false;         ///< every vertex inside the frame minus the margin
  double backfacing_fraction = 0.0;
  int occluded_points = 0;  ///< vertices / face centres hidden by another part of the sheet
  bool valid = false;
};

/// The drawn camera (or the failure) and the evaluation of every candidate.
struct CameraChoice {
  bool valid = false;
  int index = -1;  ///< chosen candidate
  double roll_deg = 0.0;
  Camera camera;
  std::vector<CameraCandidate> candidates;
};

/// The 26 candidate (inclination, azimuth) pairs [deg] of the reference: 5 (1 azimuth),
/// 12 (5), 20 (9), 28 (11), azimuths spread evenly over [-120, 120].
std::vector<Eigen::Vector2d> candidate_directions();

/// Camera looking at `target` from direction (inclination, azimuth) of the stage, with roll.
Camera make_camera(const Stage& stage, const Eigen::Vector3d& target, double inclination_deg,
                   double azimuth_deg, double roll_deg, int width, int height,
                   const CameraParams& params);

/// Draw the roll, evaluate all candidates and draw one valid direction uniformly.
/// No valid direction is an expected outcome: returned with valid = false.
CameraChoice choose_camera(const SheetMesh& mesh, const Stage& stage, int width, int height,
                           const CameraParams& params, Rng& rng);

}  // namespace papersim::scenegen
