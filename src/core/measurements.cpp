#include "handeye_covariance/core/measurements.h"

namespace handeye {

MotionPair motion_between(const Rig& rig, const PoseSample& from, const PoseSample& to) {
  MotionPair motion;
  motion.A = rig.robot_motion(from.T_base_effector, to.T_base_effector);
  motion.B = to.T_camera_pattern * from.T_camera_pattern.inverse();
  return motion;
}

}  // namespace handeye
