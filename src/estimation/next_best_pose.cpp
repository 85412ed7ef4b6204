#include "handeye_covariance/estimation/next_best_pose.h"

#include <algorithm>
#include <cmath>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/estimation/joint_estimator.h"

#include <Eigen/Cholesky>

namespace handeye {

using Eigen::Isometry3d;

const char* to_string(SuggestCriterion criterion) {
  return criterion == SuggestCriterion::ObjectSigma ? "object_sigma" : "determinant";
}

SuggestCriterion criterion_from_string(const std::string& name) {
  if (name == "object_sigma") return SuggestCriterion::ObjectSigma;
  if (name == "determinant") return SuggestCriterion::Determinant;
  throw HandEyeError(ErrorCode::MalformedFile, "unknown criterion `" + name + "`", "criterion",
                     "use object_sigma (an object's 1 sigma at the working distance) or determinant");
}

double object_sigma(const PoseWithCovariance& X, double working_distance) {
  // The lever arm is X's rotation applied to the camera-frame point.
  return max_sigma(point_covariance(X, Eigen::Vector3d(0, 0, working_distance)));
}

namespace {
int samples_used(const Calibration& c) { return c.samples_used > 0 ? c.samples_used : c.motions_used + 1; }

/// Whether X's covariance rests on a noise the residuals estimated: no noise stated, a
/// missing part the joint estimator fitted (a component the residuals supported), or
/// the corners method's robot noise (it clears the pose-level components; its pixel
/// sigma, when estimated, sets noise_origin).
bool rests_on_estimated_noise(const Calibration& calibration) {
  bool estimated = calibration.noise_origin == NoiseOrigin::EstimatedFromResiduals;
  for (const Calibration::NoiseComponent& c : calibration.noise_components) estimated |= c.supported;
  return estimated || (calibration.corner_fit && calibration.corner_fit->robot_noise_estimated);
}
}  // namespace

int samples_short_of_target(const Calibration& calibration, int samples) {
  return rests_on_estimated_noise(calibration) ? std::max(0, kTargetMinimumSamplesEstimatedNoise - samples) : 0;
}

TargetProgress target_progress(const Calibration& calibration, double target, double working_distance) {
  TargetProgress p;
  p.object_sigma = object_sigma({calibration.T_parent_camera, calibration.pose_covariance}, working_distance);
  if (p.object_sigma > target) return p;
  const int samples = samples_used(calibration);
  if (samples_short_of_target(calibration, samples) > 0) {
    const bool stated = calibration.noise_origin == NoiseOrigin::Given;
    const bool corners_robot = stated && calibration.corner_fit && calibration.corner_fit->robot_noise_estimated;
    p.why_not = "the object sigma is within the target, but " +
                std::string(corners_robot ? "the robot's noise is"
                            : stated      ? "the stated noise is too small for the residuals and its missing part is"
                                          : "the noise is") +
                " estimated from the residuals of " + std::to_string(samples) + " samples: a target is reached from " +
                std::to_string(kTargetMinimumSamplesEstimatedNoise) +
                " (fewer reach it when their noise comes out small by chance" +
                (corners_robot ? "; or state the robot's noise)" : stated ? ")" : "; or state the noise)");
    return p;
  }
  p.reached = true;
  return p;
}

std::string poses_for_the_noise_text(const Plan& plan) {
  if (plan.poses_for_the_noise <= 0) return "";
  return "; at least " + std::to_string(plan.poses_for_the_noise) + ", as the noise is estimated: a target counts from " +
         std::to_string(kTargetMinimumSamplesEstimatedNoise) + " samples";
}

double criterion_value(const PoseWithCovariance& X, SuggestCriterion criterion, double working_distance) {
  if (criterion == SuggestCriterion::ObjectSigma) return object_sigma(X, working_distance);
  // log det through Cholesky: stable at the 1e-40 scale a 6x6 of mm and mrad has.
  const Eigen::LLT<Matrix6d> llt(X.covariance);
  if (llt.info() != Eigen::Success) return -std::numeric_limits<double>::infinity();
  return 2.0 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
}

namespace {

double angle_between(const Isometry3d& a, const Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear() * b.linear().transpose()).angle();
}

bool distinct_from_all(const Isometry3d& E, const std::vector<PoseSample>& samples, const SuggestOptions& o) {
  for (const PoseSample& s : samples) {
    if ((E.translation() - s.T_base_effector.translation()).norm() < o.min_translation &&
        angle_between(E, s.T_base_effector) < o.min_rotation) {
      return false;
    }
  }
  return true;
}

/// The samples with one more, noise-free predicted sample at effector pose E,
/// and the session's noise as the global block, so the prediction uses it.
SampleSet with_candidate(const SampleSet& samples, const MeasurementNoise& noise, const PoseSample& candidate) {
  SampleSet set = samples;
  if (!set.noise) set.noise = noise;
  set.samples.push_back(candidate);
  return set;
}

}  // namespace

std::vector<Isometry3d> sample_candidates(const SampleSet& samples, const Calibration& calibration,
                                          const SuggestOptions& options) {
  if (samples.samples.empty()) {
    throw HandEyeError(ErrorCode::NoData, "no samples to suggest from", "samples", "take at least 3 samples first");
  }
  Rng rng(options.seed);
  // The views look at the middle of the target's printed face (Rig::T_pattern_face).
  const Isometry3d face =
      (calibration.pattern ? calibration.pattern->pose : pattern_pose(samples, calibration.T_parent_camera)) *
      samples.rig.T_pattern_face;
  const Isometry3d& current = samples.samples.back().T_base_effector;
  std::vector<Isometry3d> candidates;
  for (int draw = 0; draw < 50 * options.candidates && static_cast<int>(candidates.size()) < options.candidates; ++draw) {
    const Isometry3d E = samples.rig.effector_for_view(calibration.T_parent_camera, face, random_view(rng, options.views));
    if ((E.translation() - current.translation()).norm() > options.max_step_translation ||
        angle_between(E, current) > options.max_step_rotation || !distinct_from_all(E, samples.samples, options)) {
      continue;
    }
    candidates.push_back(E);
  }
  return candidates;
}

namespace {

/// The detection noise a candidate view is predicted with: the samples' own
/// covariances averaged as information (a typical view; the arithmetic mean is
/// dominated by the worst views), else the calibration's noise model.
Matrix6d candidate_camera_noise(const SampleSet& samples, const Calibration& calibration) {
  Matrix6d information = Matrix6d::Zero();
  int count = 0;
  for (const PoseSample& s : samples.samples) {
    if (!s.noise) continue;
    const Eigen::LDLT<Matrix6d> ldlt(s.noise->camera.as_pose_covariance());
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) continue;
    information += ldlt.solve(Matrix6d::Identity());
    ++count;
  }
  if (count == 0) return calibration.noise.camera.as_pose_covariance();
  const Matrix6d C = (information / count).ldlt().solve(Matrix6d::Identity());
  return 0.5 * (C + C.transpose());
}

bool has_joint_covariance(const Calibration& c) {
  return (c.method == Method::Joint || c.method == Method::Corners) && c.pattern.has_value();
}

}  // namespace

Suggestion rank_candidates(const SampleSet& samples, const Calibration& calibration,
                           const std::vector<Isometry3d>& candidates, const SuggestOptions& options) {
  if (candidates.empty()) {
    throw HandEyeError(ErrorCode::NoData, "no candidate pose to rank", "candidates",
                       "give candidate poses, or widen the reach limits (max_step_translation, max_step_rotation)");
  }
  const Isometry3d& X = calibration.T_parent_camera;
  // Joint and corners both give (X, Y) with their 12x12 covariance. A candidate
  // adds its detected pose's information to it: for corners too, as an image's
  // pose with its covariance summarises its corners to first order.
  const bool joint = has_joint_covariance(calibration);
  const Isometry3d pattern = joint ? calibration.pattern->pose : pattern_pose(samples, X);
  Suggestion suggestion;
  const PoseWithCovariance current{X, calibration.pose_covariance};
  suggestion.current_score = criterion_value(current, options.criterion, options.working_distance);
  suggestion.current_object_sigma = object_sigma(current, options.working_distance);
  Matrix12d information = Matrix12d::Zero();
  if (joint) information = joint_covariance(calibration).ldlt().solve(Matrix12d::Identity());
  const Matrix6d camera = candidate_camera_noise(samples, calibration), robot = calibration.noise.robot.as_pose_covariance();
  SolverOptions solver;
  for (const Isometry3d& E : candidates) {
    PoseSample candidate;
    candidate.T_base_effector = E;
    // What the camera would see there: eq. (68) solved for the pattern pose.
    candidate.T_camera_pattern = samples.rig.predicted_view(E, X, pattern);
    ++suggestion.considered;
    try {
      ScoredPose scored;
      scored.T_base_effector = E;
      scored.T_camera_pattern = candidate.T_camera_pattern;
      if (joint) {
        // The candidate's rank-6 term at the current estimate (its residual is zero there).
        const JointResidual r = joint_residual(samples.rig, candidate, X, pattern);
        const Matrix6d S = camera + r.d_effector * robot * r.d_effector.transpose();
        const Eigen::LLT<Matrix6d> llt(S);
        if (llt.info() != Eigen::Success) throw HandEyeError(ErrorCode::InvalidNoise, "singular", "candidate", "");
        const Matrix12d after = (information + r.jacobian.transpose() * llt.solve(r.jacobian)).ldlt().solve(Matrix12d::Identity());
        scored.predicted_joint_covariance = 0.5 * (after + after.transpose());
        scored.predicted_covariance = scored.predicted_joint_covariance.topLeftCorner<6, 6>();
      } else {
        PoseSample with_noise = candidate;  // the same typical detection noise as the joint path
        with_noise.noise = MeasurementNoise{calibration.noise.robot, PoseNoise::from_pose_covariance(camera)};
        scored.predicted_covariance = solve(with_candidate(samples, calibration.noise, with_noise), solver).pose_covariance;
      }
      const PoseWithCovariance after{X, scored.predicted_covariance};
      scored.score = criterion_value(after, options.criterion, options.working_distance);
      scored.object_sigma = object_sigma(after, options.working_distance);
      suggestion.ranked.push_back(scored);
    } catch (const HandEyeError&) {
      ++suggestion.refused;  // e.g. a candidate the input checks refuse; others remain
    }
  }
  std::stable_sort(suggestion.ranked.begin(), suggestion.ranked.end(),
                   [](const ScoredPose& a, const ScoredPose& b) { return a.score < b.score; });
  return suggestion;
}

Plan plan_poses(const SampleSet& samples, const Calibration& calibration, double target_object_sigma, int max_poses,
                const SuggestOptions& options, const std::vector<Isometry3d>& fixed_candidates) {
  Plan plan;
  plan.start_object_sigma = object_sigma({calibration.T_parent_camera, calibration.pose_covariance}, options.working_distance);
  plan.poses_for_the_noise = samples_short_of_target(calibration, samples_used(calibration));
  const auto reached = [&](double sigma, std::size_t added) {
    return sigma <= target_object_sigma && static_cast<int>(added) >= plan.poses_for_the_noise;
  };
  plan.reached = reached(plan.start_object_sigma, 0);
  SampleSet planned = samples;
  if (!planned.noise) planned.noise = calibration.noise;
  Calibration current = calibration;  // joint: its covariance follows the plan's predictions
  std::vector<Isometry3d> remaining = fixed_candidates;
  SuggestOptions step_options = options;
  while (!plan.reached && static_cast<int>(plan.poses.size()) < max_poses) {
    step_options.seed = options.seed + static_cast<unsigned>(plan.poses.size());
    const std::vector<Isometry3d> candidates =
        fixed_candidates.empty() ? sample_candidates(planned, current, step_options) : remaining;
    if (candidates.empty()) break;
    const Suggestion s = rank_candidates(planned, current, candidates, step_options);
    if (s.ranked.empty()) break;
    const ScoredPose& best = s.ranked.front();
    plan.poses.push_back(best);
    PoseSample added;
    added.T_base_effector = best.T_base_effector;
    added.T_camera_pattern = best.T_camera_pattern;
    planned.samples.push_back(added);
    if (has_joint_covariance(current)) {
      const Eigen::Matrix<double, 12, 12>& C = best.predicted_joint_covariance;
      current.pose_covariance = C.topLeftCorner<6, 6>();
      current.cross_covariance = C.topRightCorner<6, 6>();
      current.pattern->covariance = C.bottomRightCorner<6, 6>();
    }
    plan.reached = reached(best.object_sigma, plan.poses.size());
    if (!fixed_candidates.empty()) {
      remaining.erase(std::find_if(remaining.begin(), remaining.end(), [&](const Isometry3d& E) {
        return E.isApprox(best.T_base_effector);
      }));
    }
  }
  return plan;
}

}  // namespace handeye
