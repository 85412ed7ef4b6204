#include "handeye_covariance/io/warning_text.h"

#include <cmath>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/io/honesty_text.h"

namespace handeye {
namespace io {

std::string warning_text(const Warning& w) {
  switch (w.kind) {
    case Warning::Kind::StageAboveStatedNoise:
      return std::string(w.rotation_stage ? "rotation" : "translation") + " residuals are " +
             number_text(std::sqrt(w.chi2_per_dof), 2) + "x larger than the stated noise predicts (chi2/dof = " +
             number_text(w.chi2_per_dof, 3) +
             "); the covariance is likely optimistic. Check the noise block or estimate it (omit it, or use `handeye noise`).";
    case Warning::Kind::AboveStatedNoise:
      return "residuals are " + number_text(std::sqrt(w.chi2_per_dof), 2) +
             "x larger than the stated noise predicts; the covariance is likely optimistic";
    case Warning::Kind::StatedNoiseTooSmall:
      return "the stated noise is too small: residuals are " + number_text(std::sqrt(w.chi2_per_dof), 2) +
             "x what it predicts; the covariance uses the estimated missing noise (see noise_model)";
    case Warning::Kind::OutliersRejected:
      return std::to_string(w.count) + " sample(s) rejected as outliers (see `rejected`)";
    case Warning::Kind::Inflated:
      return "the split-half check says the noise model is " +
             honesty_verdict_text(Honesty::Overconfident, w.factor, w.run_length) + "; the covariance is the model's x" +
             number_text(w.factor, 3) + " (the model's alone: --no-inflation)";
    case Warning::Kind::SymmetricTarget:
      return "a symmetric target (its inner-corner counts are both odd or both even): " + std::to_string(w.count) + " of " +
             std::to_string(w.views) + " views turned by 180 degrees to agree with the robot's motion" +
             (w.ambiguous == 0 ? std::string() : ", " + std::to_string(w.ambiguous) + " left out as ambiguous") +
             "; a board with one even and one odd count avoids this decision";
  }
  return "";
}

std::string rejected_text(const Calibration::Rejected& r) {
  using Why = Calibration::Rejected::Why;
  const std::string from_prediction = " sigma (Mahalanobis, 6 dof) from what X and its robot pose predict; gate " +
                                      number_text(r.gate_sigmas, 3) + " sigma";
  const std::string ambiguous = "its pose is ambiguous: the target looks the same turned by 180 degrees, and ";
  const std::string distances = "the pose as detected is " + number_text(r.sigmas, 3) + " sigma and turned by 180 degrees " +
                                number_text(r.turned_sigmas, 3) + from_prediction;
  switch (r.why) {
    case Why::MotionsBreakAXXB:
      return "its motions to " + std::to_string(r.disagreeing) + " of " + std::to_string(r.compared) +
             " other samples break A X = X B (robot and camera rotation angles or screw pitches differ beyond " +
             number_text(degrees(r.angle_gate), 2) + " deg / " + number_text(millimetres(r.pitch_gate), 2) +
             " mm): a wrong detection or a mismatched stamp";
    case Why::FarFromPrediction:
      return "its pattern pose is " + number_text(r.sigmas, 3) + from_prediction;
    case Why::AmbiguousBothFit:
      return ambiguous + "both candidates fit: " + distances + " (the robot's motion cannot tell them apart)";
    case Why::AmbiguousNeitherFits:
      return ambiguous + "neither candidate fits: " + distances + " (a wrong detection, or a robot pose from another time)";
  }
  return "";
}

std::vector<std::string> warning_texts(const std::vector<Warning>& warnings) {
  std::vector<std::string> texts;
  for (const Warning& w : warnings) texts.push_back(warning_text(w));
  return texts;
}

}  // namespace io
}  // namespace handeye
