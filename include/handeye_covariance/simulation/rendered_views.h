// Views of a simulated rig as `handeye images` sees them: rendered (pattern_renderer.h)
// and detected with the pixel sigma pooled over the set (images/pooled_detector.h), for
// the studies that judge the package through its images (handeye_check_study
// --rendered, test_images).
#pragma once

#include <vector>

#include "handeye_covariance/simulation/pattern_renderer.h"

namespace handeye {

/// The views at the robot's true poses `effectors` of `rig` with true X and Y: each
/// rendered by `renderer` at the true camera-to-pattern pose (`target`'s face towards the
/// camera, as target_face says), detected, and recorded with the robot pose perturbed by
/// `robot_noise` (left perturbation; not stated: a session's robot noise is estimated).
/// Each sample carries its detection's covariance under the set's pooled pixel sigma, and
/// the set their mean as its block (with_default_noise, as the session solves it); a
/// view whose target is not found is left out. The set's rig is `rig` with the target's
/// face (Rig::T_pattern_face).
SampleSet rendered_views(Rng& rng, const Rig& rig, const std::vector<Eigen::Isometry3d>& effectors,
                         const Eigen::Isometry3d& X, const Eigen::Isometry3d& Y, const PatternRenderer& renderer,
                         const Target& target, const PoseNoise& robot_noise);

}  // namespace handeye
