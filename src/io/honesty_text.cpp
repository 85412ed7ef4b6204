#include "handeye_covariance/io/honesty_text.h"

#include <cmath>

#include "handeye_covariance/core/errors.h"

namespace handeye {
namespace io {

std::string honesty_verdict_text(Honesty verdict, double ratio, int run_length) {
  const double sigma = std::sqrt(ratio);
  const std::string halves =
      run_length > 1 ? " (halves of runs of " + std::to_string(run_length) + " consecutive samples)" : "";
  switch (verdict) {
    case Honesty::Overconfident:
      return "overconfident x" + number_text(ratio, 2) + ": sigma is about " + number_text(sigma, 2) + "x too small" + halves;
    case Honesty::Underconfident:
      return "underconfident x" + number_text(ratio, 2) + ": sigma is about " + number_text(1.0 / sigma, 2) + "x too large" +
             halves;
    case Honesty::Honest:
    case Honesty::NotRun:
      break;
  }
  return "honest" + halves;
}

std::string honesty_text(const HonestyCheck& check) {
  return check.ran() ? honesty_verdict_text(check.verdict, check.ratio, check.observed.run_length) : check.text;
}

}  // namespace io
}  // namespace handeye
