// A check's words from its decision and numbers (check_text.h).
#include "handeye_covariance/io/check_text.h"

#include <algorithm>
#include <cmath>

#include "handeye_covariance/core/units.h"

namespace handeye {
namespace io {

namespace {
std::string p_text(double p) { return number_text(p, 2); }

/// "3.05 mm (1 sigma 0.31 mm) and 0.0306 deg (1 sigma 0.025 deg)": a change's size and its
/// 1 sigma along itself.
std::string change_text(const EstimatedChange::Delta& d) {
  const Eigen::Vector3d t = d.value.head<3>(), r = d.value.tail<3>();
  const double t_sigma = std::sqrt(std::max(0.0, t.dot(d.covariance.topLeftCorner<3, 3>() * t)) /
                                   std::max(t.squaredNorm(), 1e-300));
  const double r_sigma = std::sqrt(std::max(0.0, r.dot(d.covariance.bottomRightCorner<3, 3>() * r)) /
                                   std::max(r.squaredNorm(), 1e-300));
  return number_text(millimetres(t.norm()), 3) + " mm (1 sigma " + number_text(millimetres(t_sigma), 2) + " mm) and " +
         number_text(degrees(r.norm()), 3) + " deg (1 sigma " + number_text(degrees(r_sigma), 2) + " deg)";
}
}  // namespace

std::string check_verdict(const CalibrationCheck& check) {
  const std::string p = (check.p_below_resolution ? "p < " : "p = ") + p_text(check.p_value);
  const int k = check.dof / 6;
  std::string verdict;
  if (!check.changed) {
    verdict = "consistent (" + p + "): the " + std::to_string(k) + " new views fit the calibration within its covariance and noise";
  } else if (check.change.what == ChangedPose::Both) {
    verdict = "X and Y both changed (" + p + "): X by " + change_text(*check.change.X_change) + ", Y by " +
              change_text(*check.change.Y_change);
  } else if (check.change.what == ChangedPose::X) {
    verdict = "X changed (" + p + "): the camera moved on its mount by " + change_text(*check.change.X_change);
  } else {
    verdict = "Y changed (" + p + "): the target moved by " + change_text(*check.change.Y_change);
  }
  if (check.naming_uncertain) {
    verdict += std::string("; or ") + (check.change.what == ChangedPose::X ? "Y" : "X") +
               " changed instead: these views barely tell which (odds " + number_text(check.naming_odds, 2) + " : 1)";
  }
  if (!check.left_out.empty()) {
    const int view = check.left_out.front();
    verdict += "; view " + std::to_string(view) + " left out: " +
               number_text(check.views[static_cast<std::size_t>(view)].mahalanobis, 3) +
               " sigma off alone, a wrong detection (the others fit)";
  }
  return verdict;
}

std::vector<std::string> check_advice(const CalibrationCheck& check) {
  using Finding = CalibrationCheck::Finding;
  const int n = check.dof, k = check.dof / 6;
  std::vector<std::string> advice;
  for (Finding finding : check.findings) {
    switch (finding) {
      case Finding::LeftOutView:
        advice.push_back("look at view " + std::to_string(check.left_out.front()) +
                         ": its detection disagrees with the calibration and the other views");
        break;
      case Finding::TargetMoved:
        advice.push_back("the target moved: its pose Y is estimated again in a new session; X may still hold "
                         "(calibrate again to be sure)");
        break;
      case Finding::CameraMoved:
        advice.push_back("calibrate again: the published X is off by more than its covariance allows");
        break;
      case Finding::ResidualBeyondChange:
        advice.push_back("even the estimated change leaves the views " +
                         number_text(check.change.residual_chi2 / std::max(1, n - check.change.dof), 3) +
                         "x their expected chi2: a wrong detection or a noisier camera, not only a moved mount");
        break;
      case Finding::ScatterBeyondNoise:
        advice.push_back("the views scatter beyond the noise model (chi2 " + number_text(check.chi2, 3) + " on " +
                         std::to_string(n) + " dof, p = " + p_text(check.chi2_p_value) +
                         ") but not as a moved X or Y would: look at the view with the largest sigma");
        break;
      case Finding::XAndYAlike:
        advice.push_back("to tell a moved camera from a moved target, take the views turned about different axes "
                         "(rolled about the optical axis and tilted both ways): at these views the two look alike "
                         "(overlap " + number_text(check.x_y_overlap, 3) + ")");
        break;
      case Finding::NoPrediction:
        advice.push_back("the calibration carries no leave-one-out prediction (it takes 4 views or more, each left "
                         "out in turn with the rest still calibrating): its noise model alone may predict too narrow, and a p near "
                         "alpha says less than it seems; solve it again from more views (handeye solve or the node "
                         "save one)");
        break;
      case Finding::FewViews:
        advice.push_back("with " + std::to_string(k) +
                         " view(s) a change of X cannot be told well from one of Y: take 5 views, turned about "
                         "different axes");
        break;
    }
  }
  return advice;
}

}  // namespace io
}  // namespace handeye
