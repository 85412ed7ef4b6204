// Named, actionable errors. Every refusal says what was wrong, where, and what
// to do; the estimator never returns NaN or a result it cannot stand behind.
#pragma once

#include <stdexcept>
#include <string>

#include "handeye_covariance/core/units.h"  // messages give mm and degrees

namespace handeye {

enum class ErrorCode {
  MalformedFile,             // not YAML, or a key of the wrong type
  MissingKey,                // a required key is absent
  WrongLength,               // a list has the wrong number of entries
  NonFinite,                 // NaN or Inf in a pose or a covariance
  QuaternionNotUnit,         // |q| far from 1
  RotationNotOrthonormal,    // R^T R != I or det(R) != 1
  InvalidNoise,              // a covariance that is not symmetric positive semi-definite
  TooFewMotions,             // fewer than 2 motions
  PureTranslation,           // no motion rotates
  ParallelRotationAxes,      // every informative motion rotates about the same axis
  RotationTooSmallForNoise,  // rotations comparable to the stated rotation noise
  AngleMismatch,             // |angle(A) - angle(B)| far beyond the noise: not the same motion
  NoiseUnidentifiable,       // no noise given and too few motions to estimate it
  PoorlyConstrained,         // solved, but the rotation sigma is too large for a first-order covariance
  NoData,                    // a bag or stream without usable detections or samples
  IoError,                   // file cannot be read or written
  InvalidLayout,             // a tag pattern layout without tags, with a bad size or a duplicate id
  TooManyOutliers,           // more samples disagree with the rest than outlier rejection may drop
  NotConverged,              // an iterative solver stopped before it converged
};

/// A number for a message, with `significant_digits` digits ("0.0484", "1.2e-05").
std::string number_text(double value, int significant_digits = 3);


/// Stable name used in messages and in tests, e.g. "ParallelRotationAxes".
const char* to_string(ErrorCode code);

class HandEyeError : public std::runtime_error {
 public:
  /// what: what was wrong; where: the file/field/index; fix: what the user should do.
  HandEyeError(ErrorCode code, const std::string& what, const std::string& where,
               const std::string& fix);

  ErrorCode code() const { return code_; }

 private:
  ErrorCode code_;
};

}  // namespace handeye
