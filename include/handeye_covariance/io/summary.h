// The short human summary printed by the command line tools: X, and 1 sigma
// per axis in mm and degrees (SI inside, mm and degrees for people).
#pragma once

#include <string>

#include "handeye_covariance/io/yaml_io.h"

namespace handeye {
namespace io {

std::string human_summary(const Calibration& calibration, const ResultContext& context);

}  // namespace io
}  // namespace handeye
