// A check's words (calibration_check.h): the check decides and measures, this writes
// the sentences the CLI, the result file, the node and the monitor show.
#pragma once

#include <string>
#include <vector>

#include "handeye_covariance/estimation/calibration_check.h"

namespace handeye {
namespace io {

/// A check's plain verdict: "consistent (p = 0.43): the 5 new views fit ...", "X changed
/// (p = 2e-05): the camera moved on its mount by 3.05 mm (1 sigma 0.31 mm) and ...".
std::string check_verdict(const CalibrationCheck& check);
/// The advice for each of the check's findings, in order.
std::vector<std::string> check_advice(const CalibrationCheck& check);

}  // namespace io
}  // namespace handeye
