// What a calibration report holds (session/report.h makes it, io writes it):
// plain data of the estimation layer, so the io layer can write it without the
// session.
#pragma once

#include <string>
#include <vector>

#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/estimation/outliers.h"
#include "handeye_covariance/estimation/split_check.h"

namespace handeye {

/// One motion's rotation between two kept samples, in the camera frame.
struct MotionAxis {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit
  double angle = 0.0;            // rad
};

struct CalibrationReport {
  Calibration calibration;       // as the session calibrates it
  std::vector<SampleFit> fits;   // every sample's, the rejected ones too (sample_fits)
  /// A sample beyond this is called out: the options' advice_sigma, scaled up as the
  /// outlier gate scales (by the kept samples' median squared sigmas over 5.348, when above 1).
  double advice_sigma = 0.0;

  Vector6d predicted_sigma = Vector6d::Zero();  // ROS order (m, rad)

  /// Leave-one-out over the kept samples.
  int leave_one_out_solved = 0, leave_one_out_failed = 0;
  Vector6d leave_one_out_sigma = Vector6d::Zero();

  /// The split-half check against its reference at this session's poses and noise
  /// (split_check.h; honesty.observed is the session's own splits);
  /// split_half_sigma is zero when it was left out or could not run (split_problem says why).
  HonestyCheck honesty;
  Vector6d split_half_sigma = Vector6d::Zero();
  std::string split_problem;

  std::vector<MotionAxis> rotation_axes;  // at most ReportOptions::max_rotation_axes, evenly spread over the pairs
  Eigen::Vector3d turning = Eigen::Vector3d::Zero();   // eigenvalues of M (rad^2), ascending
  Eigen::Matrix3d turning_axes = Eigen::Matrix3d::Identity();  // their eigenvectors (columns, camera frame)

  /// The object's worst-axis 1 sigma at the working distance, and the target.
  double working_distance = 0.0, object_sigma = 0.0, target_object_sigma = 0.0;
  bool target_reached = false;      // target_progress: within the target, with enough samples for its noise model
  std::string target_not_reached;  // within the target but not reached: why

  /// Plain-language advice, the most urgent first; never empty.
  std::vector<std::string> advice;
};

}  // namespace handeye
