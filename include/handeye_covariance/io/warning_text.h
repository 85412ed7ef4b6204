// A calibration's warnings in words (estimator.h Warning: a kind and its figures), as the
// result file, the summary, the report and /calibrate give them.
#pragma once

#include <string>
#include <vector>

#include "handeye_covariance/estimation/estimator.h"

namespace handeye {
namespace io {

std::string warning_text(const Warning& warning);
std::vector<std::string> warning_texts(const std::vector<Warning>& warnings);

}  // namespace io
}  // namespace handeye
