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

std::vector<std::string> warning_texts(const std::vector<Warning>& warnings) {
  std::vector<std::string> texts;
  for (const Warning& w : warnings) texts.push_back(warning_text(w));
  return texts;
}

}  // namespace io
}  // namespace handeye
