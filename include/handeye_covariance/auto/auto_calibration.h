// The robot moving itself, without ROS: which move comes next. The node (confirm
// and auto modes), the simulated arm and handeye_auto_study all ask this class,
// so the decision is made once:
//   - until the session can calibrate, the first moves keep the target in view
//     without knowing X: two or more translations of the start pose by
//     +-bootstrap_translation (base x, y, z), whose camera-side displacements give
//     X's rotation (R_X b_i = a_i, an SVD); then turns by +-bootstrap_angle (and
//     half) about the lines of sight's perpendiculars through the target (its
//     position in the effector frame R_X t_P, X's few-cm translation neglected).
//     Eye-to-hand turns the effector in place (the target is on it). The planner
//     checks them all but the view (unknown without X);
//   - then the session ranks candidate views by the covariance they leave
//     (CalibrationSession::suggest, next_best_pose.h) and the planner takes the
//     most informative one the arm reaches safely (motion/view_planner.h).
// The move is a timed straight joint-space path within `timing`'s speed and
// acceleration bounds (motion::timed_move).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/motion/view_planner.h"
#include "handeye_covariance/session/calibration_session.h"

namespace handeye {

struct AutoCalibrationOptions {
  motion::PlannerOptions planner;
  motion::MoveTiming timing;                     // speed fraction of the URDF's limits, acceleration bound
  double bootstrap_translation = 0.05;           // m, the first moves' shifts
  double bootstrap_angle = radians(20.0);  // rad, the first turns
};

struct NextMove {
  bool found = false;
  bool bootstrap = false;           // one of the first moves (no estimate yet)
  motion::ViewPlan plan;            // with the refusals per reason
  motion::ViewCandidate view;       // the chosen one
  std::vector<motion::TrajectoryPoint> trajectory;
  double object_sigma = 0.0;            // m, now; 0 before there is an estimate
  double predicted_object_sigma = 0.0;  // m, after the view; 0 for a first move
  std::optional<Eigen::Isometry3d> X;   // the estimate the view was predicted with (none for a first move)
  std::string reason;               // when not found: why, with the planner's counts
};

class AutoCalibration {
 public:
  /// `collision` holds the arm (its base and tip are the session's base and
  /// effector frames) and the obstacles; it must outlive this object.
  AutoCalibration(const motion::CollisionModel& collision, std::optional<CameraModel> camera,
                  AutoCalibrationOptions options = {});

  /// The next move from `current` joints. Effector poses within the sampler's
  /// minimum step of one in `failed` (moves that gave no detection) are not
  /// proposed again. With `analysis` of the snapshot's generation (the node's
  /// worker's), its estimate and ranking are used, not computed again: what the
  /// node shows and where the arm goes come from one ranking. Never throws for the
  /// session's state: what stops it is in NextMove::reason.
  NextMove next(const CalibrationSession& session, const SessionSnapshot& snapshot, const Eigen::VectorXd& current,
                const std::vector<Eigen::Isometry3d>& failed = {}, const Analysis* analysis = nullptr) const;

  /// The first moves' candidates for these samples, in order (see above).
  std::vector<motion::ViewCandidate> bootstrap_views(const Rig& rig, const std::vector<PoseSample>& samples) const;

  const AutoCalibrationOptions& options() const { return options_; }

 private:
  const motion::CollisionModel& collision_;
  std::optional<CameraModel> camera_;
  AutoCalibrationOptions options_;
};

}  // namespace handeye
