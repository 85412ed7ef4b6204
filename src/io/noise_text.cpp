#include "handeye_covariance/io/noise_text.h"

#include <vector>

#include "handeye_covariance/core/units.h"

namespace handeye {
namespace io {
namespace {

/// How the noise model was chosen: "by BIC, + view-following image noise (BIC -2117.2
/// against -2093.2); + robot ... not fitted (score 1.2 < 5.1)".
std::string candidates_text(const std::vector<NoiseCandidate>& candidates, double price) {
  std::string chosen = "the first", others;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const NoiseCandidate& c = candidates[k];
    if (c.chosen) chosen = k == 0 ? "without more numbers" : c.name;
    if (c.chosen) continue;
    others += (others.empty() ? "" : ", ") + (k == 0 ? std::string("without") : c.name) +
              (c.fitted ? " (BIC " + number_text(c.bic, 6) + ")"
                        : " not fitted (score " + number_text(c.score, 2) + " < " + number_text(price, 2) + ")");
  }
  double chosen_bic = candidates.front().bic;
  for (const NoiseCandidate& c : candidates) chosen_bic = c.chosen ? c.bic : chosen_bic;
  return "noise model by BIC: " + chosen + " (BIC " + number_text(chosen_bic, 6) + ")" + (others.empty() ? "" : "; tried " + others);
}

std::string joint_text(const Calibration& c, const NoiseModelChoice& m) {
  std::string text;
  if (m.stated_too_small) {
    text = "the stated noise is too small for the residuals (chi2/dof " + number_text(m.stated_chi2_per_dof, 3) +
           "); estimated the missing part: ";
  } else {
    text = m.camera == NoiseModelChoice::Camera::Full      ? "a full 6x6 camera noise"
           : m.camera == NoiseModelChoice::Camera::PerAxis ? "per-axis camera variances"
                                                           : "one camera variance for translation and one for rotation";
    text += m.robot_rotation ? " and the robot's rotation noise" : ", robot taken as exact";
    text += " from " + std::to_string(m.residual_dof) + " samples' worth of residuals: ";
  }
  text += c.noise_components.empty() ? "nothing separable" : "";
  for (std::size_t k = 0; k < c.noise_components.size(); ++k) {
    const NoiseComponent& n = c.noise_components[k];
    if (k < m.correlation.size() && m.correlation[k]) continue;  // in the result file; the words name the variances
    const double unit = n.unit == "m" ? kMillimetresPerMetre : n.unit == "rad" ? kDegreesPerRadian : 1.0;
    text += (k ? ", " : "") + n.name + " " + number_text(n.value * unit, 3) +
            (n.unit == "m" ? " mm" : n.unit == "rad" ? " deg" : "") +
            (!n.supported ? " (not supported by the residuals)" : " +- " + number_text(n.sigma * unit, 2));
  }
  if (!m.stated_too_small) text += "; the robot's translation noise cannot be told from the camera's and is part of it";
  for (const std::string& name : m.inseparable) text += "; " + name + " not separable from the camera's: part of it";
  if (c.noise_candidates.size() > 1) text += "; " + candidates_text(c.noise_candidates, m.bic_price);
  return text + "; covariance x" + number_text(m.inflation, 3) + " (X), x" + number_text(m.pattern_inflation, 3) +
         " (pattern) for the noise estimate's own uncertainty";
}

std::string shared_text(const SharedErrorRecord& e) {
  return "; with a robot error shared by nearby poses (" + number_text(millimetres(e.translation_sigma), 3) + " mm, " +
         number_text(degrees(e.rotation_sigma), 3) + " deg per axis over " + number_text(e.length_scale, 2) +
         " m; the per-view noise x" + number_text(e.view_noise_scale, 3) + ")" +
         (e.given ? ", given" : ", chosen by BIC (gain " + number_text(e.bic_gain, 1) + ")");
}

std::string corners_text(const Calibration& c, const CornerFitRecord& f) {
  return std::string("corners: pixel sigma ") + (f.per_image_sigma ? "per image, pooled " : "") +
         number_text(f.pixel_sigma, 3) + " px" +
         (f.pixel_sigma_estimated ? " estimated from " + std::to_string(c.rotation_stage.dof) + " dof" : " given") +
         " under the detector's corner-noise model; robot poses " + f.robot + (f.intrinsics ? "; intrinsics refined" : "");
}

}  // namespace

void word_corner_fit(CornerFitRecord& f) {
  switch (f.robot_poses) {
    case CornerFitRecord::RobotPoses::Exact:
      f.robot = "exact";
      break;
    case CornerFitRecord::RobotPoses::Prior:
      f.robot = "free, prior 1 sigma " + number_text(millimetres(f.robot_prior_sigma[0]), 3) + " mm / " +
                number_text(degrees(f.robot_prior_sigma[1]), 3) + " deg (largest axis)";
      break;
    case CornerFitRecord::RobotPoses::Estimated:
      f.robot = "free, their noise estimated from the corners: 1 sigma " + number_text(millimetres(f.robot_sigma[0]), 3) +
                " mm / " + number_text(degrees(f.robot_sigma[1]), 3) + " deg per axis";
      break;
  }
  if (f.target_point_sigma == 0.0) {
    f.target_points = f.target_point_sigma_estimated ? "exact (the corners show no error of theirs)" : "exact (as given)";
  } else {
    f.target_points = "1 sigma " + number_text(millimetres(f.target_point_sigma), 3) + " mm" +
                      (f.target_point_sigma_estimated ? " estimated from the corners" : " given") + ": X's 1 sigma x" +
                      number_text(f.target_inflation[0], 3) + " in translation, x" +
                      number_text(f.target_inflation[1], 3) + " in rotation";
  }
  f.pixel_noise.clear();
  if (f.homogeneity_tested) {
    f.pixel_noise = std::string(f.homogeneity_passed ? "one pixel sigma for every image" : "each image its own pixel sigma") +
                    " (Bartlett's test of one sigma: chi2 " + number_text(f.homogeneity_chi2, 3) + " on " +
                    std::to_string(f.homogeneity_dof) + " dof, bound " + number_text(f.homogeneity_bound, 3) + ")";
  } else if (f.per_image_sigma) {
    f.pixel_noise = "each image its own pixel sigma (robust on)";
  }
}

std::string noise_model_text(const Calibration& c) {
  if (c.corner_fit) return corners_text(c, *c.corner_fit);
  std::string text = c.noise_model ? joint_text(c, *c.noise_model) : "";  // a given noise has no words of its own
  if (c.shared_robot_error && c.shared_robot_error->used) text += shared_text(*c.shared_robot_error);
  return text;
}

}  // namespace io
}  // namespace handeye
