// The short human summary printed by the command line tools: X, and 1 sigma
// per axis in mm and degrees (SI inside, mm and degrees for people).
#pragma once

#include <string>

#include <vector>

#include "handeye_covariance/core/object_pose.h"
#include "handeye_covariance/estimation/calibration_check.h"
#include "handeye_covariance/estimation/split_check.h"
#include "handeye_covariance/io/check_text.h"
#include "handeye_covariance/io/warning_text.h"
#include "handeye_covariance/io/yaml_io.h"

namespace handeye {
namespace io {

std::string human_summary(const Calibration& calibration, const ResultContext& context);
/// One line (the node's /calibrate message): X = T_parent_child from n samples, its worst-axis
/// 1 sigma in mm and degrees, the shared robot error when used, and the honesty verdict.
std::string one_line_summary(const Calibration& calibration, const std::string& parent, const std::string& child);
/// The shared robot error's state in one phrase: "used", "advice" (preferred, not used),
/// "not preferred", "not fitted: <why>", or "off" (none).
std::string shared_error_state(const std::optional<Calibration::SharedError>& shared);

/// The split-half check's lines: the mean NEES of the halves' difference and
/// what it means (honest about 6; above 7.5 overconfident; below 5 cautious).
/// The calibrated honesty check's lines (Calibration::honesty): the verdict, the
/// session's split-half NEES against its reference, the band.
std::string honesty_lines(const Calibration::Honesty& honesty);
/// The shared robot error's lines of the summary (Calibration::shared_robot_error), about `calibration`.
std::string shared_error_lines(const Calibration::SharedError& shared, const Calibration& calibration);

/// The report's lines: 1 sigma per axis as predicted, by leave-one-out and by
/// split-half (mm, degrees), then the advice.
std::string report_summary(const CalibrationReport& report);

/// T_base_object with 1 sigma per axis, each term's share of the position
/// variance, and each point's worst-axis 1 sigma (`handeye compose`).
std::string object_summary(const ObjectPose& object, const std::string& base, const std::string& object_frame,
                           const std::vector<Eigen::Vector3d>& points);

/// `handeye check`: the verdict, each new view's residual against its predicted 1 sigma
/// (mm, degrees: the calibration's accuracy on views it has not seen), the
/// estimated change and the advice.
std::string check_summary(const CalibrationCheck& check);

}  // namespace io
}  // namespace handeye
