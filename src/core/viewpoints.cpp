#include "handeye_covariance/core/viewpoints.h"

namespace handeye {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

Isometry3d random_view(Rng& rng, const ViewpointOptions& options) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double azimuth = 2.0 * M_PI * unit(rng);
  // Uniform over the cap's area: cos(tilt) uniform in [cos(max_tilt), 1].
  const double tilt = std::acos(1.0 - unit(rng) * (1.0 - std::cos(options.max_tilt)));
  const double roll = options.max_roll * (2.0 * unit(rng) - 1.0);
  const double distance =
      options.min_distance + (options.max_distance - options.min_distance) * unit(rng);
  const Vector3d tilt_axis(std::cos(azimuth), std::sin(azimuth), 0.0);
  // Camera z looks down the pattern's -z, from `distance` along the tilted normal.
  const Matrix3d R_pattern_camera = so3::exp(tilt * tilt_axis) *
                                    Eigen::AngleAxisd(M_PI, Vector3d::UnitX()).toRotationMatrix() *
                                    Eigen::AngleAxisd(roll, Vector3d::UnitZ()).toRotationMatrix();
  std::uniform_real_distribution<double> offset(-options.max_offset, options.max_offset);
  const Vector3d camera_position =
      so3::exp(tilt * tilt_axis) * Vector3d(0.0, 0.0, distance) +
      R_pattern_camera * [&] {
        const double y = offset(rng), x = offset(rng);  // a fixed order; see sample_gaussian
        return Vector3d(x, y, 0.0);
      }();
  return se3::make_pose(R_pattern_camera, camera_position).inverse();
}

}  // namespace handeye
