#include "handeye_covariance/core/measurements.h"

namespace handeye {

const char* to_string(Setup setup) {
  return setup == Setup::EyeInHand ? "eye_in_hand" : "eye_to_hand";
}

MotionPair motion_between(Setup setup, const PoseSample& from, const PoseSample& to) {
  MotionPair motion;
  // Eye-in-hand: E_i X P_i = T_base_pattern for all i  =>  (E_j^-1 E_i) X = X (P_j P_i^-1).
  // Eye-to-hand: E_i Y = X P_i (Y = T_effector_pattern) =>  (E_j E_i^-1) X = X (P_j P_i^-1).
  motion.A = setup == Setup::EyeInHand ? to.T_base_effector.inverse() * from.T_base_effector
                                       : to.T_base_effector * from.T_base_effector.inverse();
  motion.B = to.T_camera_pattern * from.T_camera_pattern.inverse();
  return motion;
}

}  // namespace handeye
