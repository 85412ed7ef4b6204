// The honesty check's verdict in words (split_check.h HonestyCheck: a verdict and its
// figures), as the result file, the summary, the report and /calibrate give it.
#pragma once

#include <string>

#include "handeye_covariance/estimation/split_check.h"

namespace handeye {
namespace io {

/// "honest", "overconfident x1.6: sigma is about 1.3x too small", "underconfident
/// x0.5: sigma is about 1.4x too large", each with "(halves of runs of k consecutive
/// samples)" when runs of k > 1 decided.
std::string honesty_verdict_text(Honesty verdict, double ratio, int run_length);
/// The check's verdict in those words, or why there is none (HonestyCheck::text).
std::string honesty_text(const HonestyCheck& check);

}  // namespace io
}  // namespace handeye
