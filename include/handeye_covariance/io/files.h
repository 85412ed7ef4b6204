// Whole files: reading, writing atomically, `~/` paths; and the session settings
// file, which is here (not with a calibration file family) because it is the
// node's parameters in a file, read with the same YAML readers. No ROS.
#pragma once

#include <string>

#include "handeye_covariance/session/session_config.h"

namespace handeye {
namespace io {

/// Session settings from a YAML file with the node's parameter names (the
/// keys of config/calibration_defaults.yaml and calibrate.launch); keys absent
/// from the file keep their value in `config`. Unknown keys are refused (typos).
void read_session_config(const std::string& path, SessionConfig& config);

/// Write to `path.tmp-<pid>` then rename, so a reader never sees half a file
/// and a failure leaves no file behind. Creates missing parent directories.
void write_file_atomically(const std::string& path, const std::string& content);

/// Whole file as text; HandEyeError(IoError) when it cannot be read.
std::string read_file(const std::string& path);

/// `~/rest` as $HOME/rest (a path from a launch file or a parameter); any other path as it is.
std::string expand_home(const std::string& path);

}  // namespace io
}  // namespace handeye
