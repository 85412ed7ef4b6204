// Which of the ranked next views the arm can reach, safely, from where it is.
//
// The session ranks candidate views by how much they shrink X's covariance
// (estimation/next_best_pose.h). For each, best first, the planner asks, in this order:
//   workspace:          the effector inside the `workspace` box (base frame);
//   in view:            at the goal the camera sees the whole target face (predicted
//                       from the current X and Y) within the distance and tilt limits;
//   inverse kinematics: a joint solution (KDL, several seeds) nearest the current joints;
//   joint limits:       every joint within its URDF limits less `joint_margin`;
//   joint step:         no joint turns more than `max_joint_step` in the move;
//   collision at goal:  no contact (collision.h) at the goal;
//   collision on path:  none along the straight joint-space path, sampled so that no
//                       point of the arm moves more than 2 * padding between samples.
// The first candidate that passes every check is the plan; each refused one has
// its reason, counted per reason. Eye-in-hand and eye-to-hand alike: the
// candidate's T_base_effector is where the effector goes; its T_camera_pattern is
// what the camera should then see.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/core/camera.h"
#include "handeye_covariance/core/rig.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/motion/collision.h"
#include "handeye_covariance/motion/trajectory.h"

namespace handeye::motion {

/// In the order the planner checks them.
enum class Refusal {
  OutsideWorkspace,
  TargetNotInView,
  NoInverseKinematics,
  OutsideJointLimits,
  JointStepTooLarge,
  CollisionAtGoal,
  CollisionOnPath,
};
constexpr int kRefusals = 7;
/// "no_inverse_kinematics", "outside_joint_limits", ...: the spelling of messages and files.
const char* to_string(Refusal refusal);

struct PlannerOptions {
  double joint_margin = radians(5.0);     // rad, inside each URDF limit
  double max_joint_step = radians(90.0);  // rad, any joint, one move
  Eigen::AlignedBox3d workspace{Eigen::Vector3d(-1.0, -1.0, 0.05), Eigen::Vector3d(1.0, 1.0, 1.2)};  // m, base frame
  int ik_seeds = 6;    // random starts besides the current joints
  /// Check every candidate (a verdict for each, e.g. for a report), not only up
  /// to the first that passes; the plan is the same.
  bool check_all = false;
  unsigned seed = 1;
  /// The target in view at the goal.
  double min_distance = 0.2, max_distance = 1.5;  // m, camera to the face's centre
  double max_tilt = radians(60.0);          // rad, line of sight off the face's normal
  double image_margin = 0.05;                     // of the image's width and height, each side
  /// Without a camera model: the full field of view.
  double field_of_view_x = radians(60.0), field_of_view_y = radians(45.0);
};

struct ViewCandidate {
  Eigen::Isometry3d T_base_effector = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_camera_pattern = Eigen::Isometry3d::Identity();
  /// false: no calibration predicts the view yet (the first moves), so the
  /// in-view check is skipped; a view without a detection is then skipped.
  bool view_known = true;
};

struct CandidateVerdict {
  std::optional<Refusal> refusal;  // none: it passed (or was not needed: see ViewPlan::chosen)
  std::string reason;              // what failed, with its numbers
  bool checked = false;            // false: a better candidate passed first
};

struct ViewPlan {
  int chosen = -1;  // index into the candidates; -1: none passes
  Eigen::VectorXd start, goal;   // joints
  int path_samples = 0;          // configurations checked along the path
  std::array<int, kRefusals> refused{};
  std::vector<CandidateVerdict> verdicts;  // one per candidate
  bool found() const { return chosen >= 0; }
  /// "view 3 of 150: 2 no_inverse_kinematics, 1 collision_on_path (...)"
  std::string summary() const;
};

/// The planner's verdict on one straight joint-space move: the first contact
/// along it, if any, and how many configurations were checked.
struct PathCheck {
  std::optional<Contact> contact;
  double at = 0.0;   // fraction of the move where the contact is
  int samples = 0;
};
/// The arm is the collision model's (its reach sets the sampling).
PathCheck check_path(const CollisionModel& collision, const Eigen::VectorXd& from, const Eigen::VectorXd& to);

/// The first joint of q within `margin` of its URDF limits (or beyond), with the
/// numbers; none when every joint is inside them less the margin.
std::optional<std::string> limit_problem(const Arm& arm, const Eigen::VectorXd& q, double margin);

/// Whether the camera sees the target's face at T_camera_pattern, and if not why.
std::optional<std::string> view_problem(const Rig& rig, const std::optional<CameraModel>& camera,
                                        const Eigen::Isometry3d& T_camera_pattern, const PlannerOptions& options);

/// The arm is the collision model's.
ViewPlan plan_view(const CollisionModel& collision, const Rig& rig,
                   const std::optional<CameraModel>& camera, const Eigen::VectorXd& current,
                   const std::vector<ViewCandidate>& candidates, const PlannerOptions& options);

}  // namespace handeye::motion
