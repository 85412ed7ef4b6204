#include "handeye_covariance/motion/view_planner.h"

#include <cmath>
#include <sstream>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/units.h"

namespace handeye::motion {
namespace {

std::string degrees_text(double rad) { return number_text(degrees(rad), 3) + " deg"; }

}  // namespace

const char* to_string(Refusal refusal) {
  switch (refusal) {
    case Refusal::NoInverseKinematics: return "no_inverse_kinematics";
    case Refusal::OutsideJointLimits: return "outside_joint_limits";
    case Refusal::JointStepTooLarge: return "joint_step_too_large";
    case Refusal::OutsideWorkspace: return "outside_workspace";
    case Refusal::TargetNotInView: return "target_not_in_view";
    case Refusal::CollisionAtGoal: return "collision_at_goal";
    case Refusal::CollisionOnPath: return "collision_on_path";
  }
  return "unknown";
}

std::string ViewPlan::summary() const {
  std::ostringstream out;
  if (found())
    out << "view " << chosen + 1 << " of " << verdicts.size();
  else
    out << "no view of " << verdicts.size() << " passes";
  std::string refusals;
  for (int r = 0; r < kRefusals; ++r) {
    if (refused[r] == 0) continue;
    refusals += (refusals.empty() ? "" : ", ") + std::to_string(refused[r]) + " " + to_string(static_cast<Refusal>(r));
  }
  if (!refusals.empty()) out << "; refused: " << refusals;
  return out.str();
}

PathCheck check_path(const CollisionModel& collision, const Eigen::VectorXd& from, const Eigen::VectorXd& to) {
  const Arm& arm = collision.arm();
  // No point of the arm moves more than sum_j reach_j |dq_j| over the move (arm.h);
  // split it so that each step moves none more than 2 * padding (collision.h).
  const std::vector<double> reach = arm.reach();
  double travel = 0.0;
  for (int j = 0; j < arm.joints(); ++j) travel += reach[j] * std::abs(to(j) - from(j));
  const double step = 2.0 * collision.padding();  // > 0 (CollisionModel)
  const int steps = std::max(1, static_cast<int>(std::ceil(travel / step)));
  PathCheck check;
  for (int k = 0; k <= steps; ++k) {
    const double s = static_cast<double>(k) / steps;
    ++check.samples;
    if (auto contact = collision.contact(from + s * (to - from))) {
      check.contact = contact;
      check.at = s;
      return check;
    }
  }
  return check;
}

std::optional<std::string> limit_problem(const Arm& arm, const Eigen::VectorXd& q, double margin) {
  for (int j = 0; j < arm.joints(); ++j) {
    const JointLimit& limit = arm.limits()[j];
    if (q(j) < limit.lower + margin || q(j) > limit.upper - margin)
      return limit.name + " at " + degrees_text(q(j)) + ", within " + degrees_text(margin) + " of its limits [" +
             degrees_text(limit.lower) + ", " + degrees_text(limit.upper) + "]";
  }
  return std::nullopt;
}

std::optional<std::string> view_problem(const Rig& rig, const std::optional<CameraModel>& camera,
                                        const Eigen::Isometry3d& T_camera_pattern, const PlannerOptions& options) {
  const Eigen::Isometry3d T_camera_face = T_camera_pattern * rig.T_pattern_face;
  const Eigen::Vector3d centre = T_camera_face.translation();
  const double distance = centre.norm();
  if (distance < options.min_distance || distance > options.max_distance)
    return "the target would be " + number_text(distance, 3) + " m from the camera, outside [" +
           number_text(options.min_distance, 3) + ", " + number_text(options.max_distance, 3) + "] m";
  // The face's normal (z) points towards a camera that sees it.
  const double tilt = std::acos(std::clamp(T_camera_face.linear().col(2).dot(-centre / distance), -1.0, 1.0));
  if (tilt > options.max_tilt)
    return "the camera would see the target " + degrees_text(tilt) + " off its normal, beyond " + degrees_text(options.max_tilt);
  std::vector<Eigen::Vector3d> points{Eigen::Vector3d::Zero()};
  const Eigen::Vector2d half = 0.5 * rig.face_size;
  for (const double sx : {-1.0, 1.0})
    for (const double sy : {-1.0, 1.0}) points.emplace_back(sx * half.x(), sy * half.y(), 0.0);
  for (const Eigen::Vector3d& point : points) {
    const Eigen::Vector3d p = T_camera_face * point;
    if (p.z() <= 0.0) return std::string("part of the target would be behind the camera");
    bool inside;
    if (camera && camera->width > 0 && camera->height > 0) {
      const Eigen::Vector3d pixel = camera->K * (p / p.z());
      const double mx = options.image_margin * camera->width, my = options.image_margin * camera->height;
      inside = pixel.x() >= mx && pixel.x() <= camera->width - mx && pixel.y() >= my && pixel.y() <= camera->height - my;
    } else {
      inside = std::abs(std::atan2(p.x(), p.z())) <= 0.5 * options.field_of_view_x * (1.0 - 2.0 * options.image_margin) &&
               std::abs(std::atan2(p.y(), p.z())) <= 0.5 * options.field_of_view_y * (1.0 - 2.0 * options.image_margin);
    }
    if (!inside) return std::string("the target's face would not be whole in the image");
  }
  return std::nullopt;
}

ViewPlan plan_view(const CollisionModel& collision, const Rig& rig, const std::optional<CameraModel>& camera,
                   const Eigen::VectorXd& current, const std::vector<ViewCandidate>& candidates,
                   const PlannerOptions& options) {
  const Arm& arm = collision.arm();
  if (current.size() != arm.joints())
    throw HandEyeError(ErrorCode::WrongLength,
                       "the current joints have " + std::to_string(current.size()) + " values, the arm " +
                           std::to_string(arm.joints()) + " movable joints",
                       "plan_view", "pass the joints of the chain from the base to the effector, in the URDF's order");
  ViewPlan plan;
  plan.start = current;
  plan.verdicts.resize(candidates.size());
  Rng rng(options.seed);
  auto refuse = [&](std::size_t i, Refusal refusal, std::string reason) {
    plan.verdicts[i].refusal = refusal;
    plan.verdicts[i].reason = std::move(reason);
    ++plan.refused[static_cast<int>(refusal)];
  };
  for (std::size_t i = 0; i < candidates.size() && (options.check_all || !plan.found()); ++i) {
    plan.verdicts[i].checked = true;
    const ViewCandidate& candidate = candidates[i];
    if (!options.workspace.contains(candidate.T_base_effector.translation())) {
      const Eigen::Vector3d t = candidate.T_base_effector.translation();
      refuse(i, Refusal::OutsideWorkspace,
             "the effector would be at (" + number_text(t.x(), 3) + ", " + number_text(t.y(), 3) + ", " +
                 number_text(t.z(), 3) + ") m, outside the workspace box");
      continue;
    }
    if (auto problem = candidate.view_known ? view_problem(rig, camera, candidate.T_camera_pattern, options)
                                            : std::nullopt) {
      refuse(i, Refusal::TargetNotInView, *problem);
      continue;
    }
    const std::vector<Eigen::VectorXd> solutions = arm.inverse(candidate.T_base_effector, current, options.ik_seeds, rng);
    if (solutions.empty()) {
      refuse(i, Refusal::NoInverseKinematics, "no joint solution reaches the effector pose");
      continue;
    }
    // The nearest solution that passes; otherwise the reason of the one that got furthest
    // (the Refusal values are in the order of the checks).
    std::optional<Refusal> why;
    std::string reason;
    auto failed = [&](Refusal refusal, const std::string& text) {
      if (!why || static_cast<int>(refusal) > static_cast<int>(*why)) why = refusal, reason = text;
    };
    for (const Eigen::VectorXd& q : solutions) {
      if (const std::optional<std::string> problem = limit_problem(arm, q, options.joint_margin)) {
        failed(Refusal::OutsideJointLimits, *problem);
        continue;
      }
      const double step = largest_joint_change(q, current);
      if (step > options.max_joint_step) {
        failed(Refusal::JointStepTooLarge,
               "a joint would turn " + degrees_text(step) + ", more than " + degrees_text(options.max_joint_step));
        continue;
      }
      if (auto contact = collision.contact(q)) {
        failed(Refusal::CollisionAtGoal, contact->text() + " at the goal");
        continue;
      }
      const PathCheck path = check_path(collision, current, q);
      plan.path_samples += path.samples;
      if (path.contact) {
        failed(Refusal::CollisionOnPath, path.contact->text() + " at " + number_text(100.0 * path.at, 3) + "% of the move");
        continue;
      }
      if (!plan.found()) {
        plan.chosen = static_cast<int>(i);
        plan.goal = q;
      }
      why.reset();
      break;
    }
    if (why) refuse(i, *why, reason);
  }
  return plan;
}

}  // namespace handeye::motion
