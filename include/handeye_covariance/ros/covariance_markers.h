// A MarkerArray with the same ellipsoids as the RViz display, for users without
// the plugin. Geometry from core/ellipsoid.h.
#pragma once

#include <visualization_msgs/MarkerArray.h>

#include "handeye_covariance/core/ellipsoid.h"

namespace handeye {

struct CovarianceMarkerOptions {
  double sigmas = 3.0;        // ellipsoid size in sigma
  double axis_length = 0.1;   // m: where the orientation discs sit on each axis
  std::string ns = "handeye_covariance";
};

/// Position ellipsoid (id 0), one disc per local axis for the orientation
/// uncertainty (ids 1-3, red/green/blue for x/y/z) and a 1-sigma label (id 4),
/// all in `frame`. Throws HandEyeError for an invalid covariance.
visualization_msgs::MarkerArray covariance_markers(const PoseWithCovariance& X, const std::string& frame,
                                                   const ros::Time& stamp, const CovarianceMarkerOptions& options = {});

/// "1σ 0.42 mm, 0.031°": worst-axis translation and rotation sigma.
std::string sigma_label(const PoseWithCovariance& X);

}  // namespace handeye
