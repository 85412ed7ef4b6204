#include "handeye_covariance/auto/auto_calibration.h"

#include "handeye_covariance/core/errors.h"

namespace handeye {

AutoCalibration::AutoCalibration(const motion::CollisionModel& collision, std::optional<CameraModel> camera,
                                 AutoCalibrationOptions options)
    : collision_(collision), camera_(std::move(camera)), options_(options) {}

namespace {

// X's rotation from pure translations of the effector (the same rotation as the
// first sample): eye-in-hand, the target's displacement in the camera frame is
// -R_X^T R_E^T dp; eye-to-hand, R_X^T dp. Needs two non-parallel shifts.
std::optional<Eigen::Matrix3d> rotation_from_shifts(const Rig& rig, const std::vector<PoseSample>& shifts) {
  if (shifts.size() < 3) return std::nullopt;
  const PoseSample& first = shifts.front();
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  std::vector<Eigen::Vector3d> moved;
  for (std::size_t i = 1; i < shifts.size(); ++i) {
    const Eigen::Vector3d dp = shifts[i].T_base_effector.translation() - first.T_base_effector.translation();
    const Eigen::Vector3d a = rig.eye_in_hand() ? Eigen::Vector3d(first.T_base_effector.linear().transpose() * dp) : dp;
    const Eigen::Vector3d db = shifts[i].T_camera_pattern.translation() - first.T_camera_pattern.translation();
    const Eigen::Vector3d b = rig.eye_in_hand() ? Eigen::Vector3d(-db) : db;
    M += a * b.transpose();  // R b = a
    moved.push_back(a.normalized());
  }
  bool spread = false;
  for (std::size_t i = 0; i < moved.size(); ++i)
    for (std::size_t j = i + 1; j < moved.size(); ++j) spread = spread || moved[i].cross(moved[j]).norm() > 0.5;
  if (!spread) return std::nullopt;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  S(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return Eigen::Matrix3d(svd.matrixU() * S * svd.matrixV().transpose());
}

bool near_any(const Eigen::Isometry3d& pose, const std::vector<Eigen::Isometry3d>& others, const SamplerOptions& step) {
  for (const Eigen::Isometry3d& other : others) {
    const Eigen::Isometry3d d = other.inverse() * pose;
    if (d.translation().norm() < step.min_translation && Eigen::AngleAxisd(d.linear()).angle() < step.min_rotation)
      return true;
  }
  return false;
}

}  // namespace

std::vector<motion::ViewCandidate> AutoCalibration::bootstrap_views(const Rig& rig,
                                                                    const std::vector<PoseSample>& samples) const {
  std::vector<motion::ViewCandidate> views;
  if (samples.empty()) return views;
  const Eigen::Isometry3d E = samples.front().T_base_effector;
  std::vector<PoseSample> shifts;
  for (const PoseSample& s : samples)
    if (Eigen::AngleAxisd(s.T_base_effector.linear().transpose() * E.linear()).angle() < 1e-3) shifts.push_back(s);
  auto add = [&](const Eigen::Isometry3d& pose) { views.push_back({pose, Eigen::Isometry3d::Identity(), false}); };
  const std::optional<Eigen::Matrix3d> R_X = rotation_from_shifts(rig, shifts);
  if (R_X) {
    // Turns about the perpendiculars of the line of sight, through the target.
    const Eigen::Vector3d target = *R_X * samples.front().T_camera_pattern.translation();
    // Across the line of sight first, alternating axes (two axes make an estimate), then about it.
    for (const double scale : {1.0, 0.5}) {
      for (const auto& [axis, sign] : {std::pair{0, 1.0}, {1, 1.0}, {0, -1.0}, {1, -1.0}, {2, 1.0}, {2, -1.0}}) {
        Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
        const Eigen::Vector3d direction = *R_X * Eigen::Vector3d::Unit(axis);  // the camera's x, y, z
        turn.rotate(Eigen::AngleAxisd(sign * scale * options_.bootstrap_angle, direction));
        if (rig.eye_in_hand()) {
          turn.pretranslate(target);
          turn.translate(-target);
        }
        add(E * turn);
      }
    }
  }
  // Shifts of the start pose in the base frame (more of them when X's rotation is not known yet).
  // +x, +y first: two shifts that are not parallel give X's rotation.
  for (const auto& [axis, sign] : {std::pair{0, 1.0}, {1, 1.0}, {0, -1.0}, {1, -1.0}, {2, 1.0}, {2, -1.0}}) {
    Eigen::Isometry3d shifted = E;
    shifted.translation() += sign * options_.bootstrap_translation * Eigen::Vector3d::Unit(axis);
    add(shifted);
  }
  return views;
}

NextMove AutoCalibration::next(const CalibrationSession& session, const SessionSnapshot& snapshot,
                               const Eigen::VectorXd& current, const std::vector<Eigen::Isometry3d>& failed,
                               const Analysis* analysis) const {
  NextMove move;
  const Rig& rig = session.settings().rig;
  std::vector<motion::ViewCandidate> candidates;
  std::vector<double> predicted;
  auto rank = [&](const Calibration& estimate, const std::vector<ScoredPose>& ranked) {
    move.object_sigma = object_sigma({estimate.T_parent_camera, estimate.pose_covariance},
                                     session.settings().suggest.working_distance);
    move.X = estimate.T_parent_camera;
    for (const ScoredPose& pose : ranked) {
      if (near_any(pose.T_base_effector, failed, session.settings().sampler)) continue;
      candidates.push_back({pose.T_base_effector, pose.T_camera_pattern, true});
      predicted.push_back(pose.object_sigma);
    }
  };
  try {
    if (analysis && analysis->generation == snapshot.generation && analysis->estimate && !analysis->ranked.empty()) {
      rank(*analysis->estimate, analysis->ranked);
    } else {
      SuggestRequest request;
      request.count = session.settings().suggest.candidates;
      const SuggestResult suggestion = session.suggest(snapshot, request);
      rank(suggestion.estimate, suggestion.suggestion.ranked);
    }
  } catch (const HandEyeError&) {
    // No estimate yet: the first moves, skipping poses the session has or that gave no detection.
    move.bootstrap = true;
    if (snapshot.samples.samples.empty()) {
      move.reason = "no sample yet: take the first one where the camera sees the target";
      return move;
    }
    std::vector<Eigen::Isometry3d> known = failed;
    for (const PoseSample& s : snapshot.samples.samples) known.push_back(s.T_base_effector);
    for (const motion::ViewCandidate& view : bootstrap_views(rig, snapshot.samples.samples)) {
      if (near_any(view.T_base_effector, known, session.settings().sampler)) continue;
      candidates.push_back(view);
      predicted.push_back(0.0);
    }
  }
  move.plan = motion::plan_view(collision_, rig, camera_, current, candidates, options_.planner);
  if (!move.plan.found()) {
    move.reason = (move.bootstrap ? "no first move passes the planner (" : "no ranked view passes the planner (") +
                  move.plan.summary() + ")";
    return move;
  }
  move.found = true;
  move.view = candidates[move.plan.chosen];
  move.predicted_object_sigma = predicted[move.plan.chosen];
  move.trajectory = motion::timed_move(collision_.arm(), current, move.plan.goal, options_.timing);
  return move;
}

}  // namespace handeye
