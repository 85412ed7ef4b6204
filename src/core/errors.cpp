#include "handeye_covariance/core/errors.h"

#include <charconv>

namespace handeye {

const char* to_string(ErrorCode code) {
  switch (code) {
    case ErrorCode::MalformedFile: return "MalformedFile";
    case ErrorCode::MissingKey: return "MissingKey";
    case ErrorCode::WrongLength: return "WrongLength";
    case ErrorCode::NonFinite: return "NonFinite";
    case ErrorCode::QuaternionNotUnit: return "QuaternionNotUnit";
    case ErrorCode::RotationNotOrthonormal: return "RotationNotOrthonormal";
    case ErrorCode::InvalidNoise: return "InvalidNoise";
    case ErrorCode::TooFewMotions: return "TooFewMotions";
    case ErrorCode::PureTranslation: return "PureTranslation";
    case ErrorCode::ParallelRotationAxes: return "ParallelRotationAxes";
    case ErrorCode::RotationTooSmallForNoise: return "RotationTooSmallForNoise";
    case ErrorCode::AngleMismatch: return "AngleMismatch";
    case ErrorCode::NoiseUnidentifiable: return "NoiseUnidentifiable";
    case ErrorCode::PoorlyConstrained: return "PoorlyConstrained";
    case ErrorCode::NoData: return "NoData";
    case ErrorCode::IoError: return "IoError";
    case ErrorCode::InvalidLayout: return "InvalidLayout";
    case ErrorCode::TooManyOutliers: return "TooManyOutliers";
    case ErrorCode::NotConverged: return "NotConverged";
  }
  return "Unknown";
}

std::string number_text(double value, int significant_digits) {
  // printf's %.*g in the "C" locale, by the standard's definition of to_chars,
  // at a fraction of snprintf's cost (the noise summary prints about 16 per solve).
  char buffer[64];
  const std::to_chars_result end =
      std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::general, significant_digits);
  return std::string(buffer, end.ptr);
}

namespace {
std::string format(ErrorCode code, const std::string& what, const std::string& where,
                   const std::string& fix) {
  std::string message = std::string(to_string(code)) + ": " + what;
  if (!where.empty()) message += " (at " + where + ")";
  if (!fix.empty()) message += ". Fix: " + fix;
  return message;
}
}  // namespace

HandEyeError::HandEyeError(ErrorCode code, const std::string& what, const std::string& where,
                           const std::string& fix)
    : std::runtime_error(format(code, what, where, fix)), code_(code) {}

}  // namespace handeye
