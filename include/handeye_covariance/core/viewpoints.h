// Plausible views of the pattern: where a camera can stand to see it well. Used
// to draw the next-best-pose candidates and by the simulator.
#pragma once

#include <random>

#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/core/units.h"

namespace handeye {

using Rng = std::mt19937_64;  // every random draw in the package is seeded

/// Geometry of a calibration session: the camera looks at the pattern from
/// viewpoints on a cap of a sphere, as an integrator would move the robot.
struct ViewpointOptions {
  double min_distance = 0.4;        // m, camera to pattern
  double max_distance = 0.8;        // m
  double max_tilt = radians(35.0);  // viewing angle off the pattern normal
  double max_roll = radians(60.0);  // about the optical axis
  double max_offset = 0.05;         // m, pattern centre off the optical axis
};

/// A T_camera_pattern seen from a random viewpoint.
Eigen::Isometry3d random_view(Rng& rng, const ViewpointOptions& options);

}  // namespace handeye
