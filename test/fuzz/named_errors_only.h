// The fuzz targets' one rule: a reader may return or throw HandEyeError (a named,
// actionable error); anything else escapes and libFuzzer reports it.
#pragma once

#include "handeye_covariance/core/errors.h"

template <typename F>
void named_errors_only(F&& f) {
  try {
    f();
  } catch (const handeye::HandEyeError&) {
    // expected: a refusal with its reason
  }
}
