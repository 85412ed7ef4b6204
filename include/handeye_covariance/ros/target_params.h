// The calibration target from a node's ~parameters, shared by target_detector
// and rig_simulator (which renders the same target).
#pragma once

#include <ros/node_handle.h>

#include "handeye_covariance/core/target.h"

namespace handeye {

/// The target from ~parameters: ~target_file (any kind, io::read_target), or,
/// for AprilTag, ~layout_file or one tag (~tag_id, ~tag_size, ~family). ~target
/// (chessboard | charuco | aruco | apriltag), when set, must be the file's kind
/// (aruco: one marker or a board). Throws HandEyeError naming the parameter and the fix.
Target target_from_params(const ros::NodeHandle& private_node);

}  // namespace handeye
