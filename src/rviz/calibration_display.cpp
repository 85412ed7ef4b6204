#include "calibration_display.h"

#include <pluginlib/class_list_macros.hpp>
#include <rviz/frame_manager.h>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/ros/msg_conversion.h"

namespace handeye {
namespace rviz_plugin {

CalibrationDisplay::CalibrationDisplay() {
  covariance_property_ = new CalibrationCovarianceProperty(this, SLOT(redraw()), this);
}

CalibrationDisplay::~CalibrationDisplay() = default;

void CalibrationDisplay::onInitialize() {
  MFDClass::onInitialize();
  visual_ = std::make_unique<CalibrationCovarianceVisual>(context_->getSceneManager(), scene_node_);
  visual_->set_visible(false);
}

void CalibrationDisplay::reset() {
  MFDClass::reset();
  last_.reset();
  drawn_ = false;
  if (visual_) visual_->set_visible(false);
}

void CalibrationDisplay::redraw() {
  if (last_) processMessage(last_);
}

void CalibrationDisplay::processMessage(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
  last_ = msg;
  drawn_ = false;
  // Validate before drawing: finite numbers and a unit quaternion.
  const geometry_msgs::Pose& p = msg->pose.pose;
  const bool finite = std::isfinite(p.position.x) && std::isfinite(p.position.y) && std::isfinite(p.position.z) &&
                      std::all_of(msg->pose.covariance.begin(), msg->pose.covariance.end(),
                                  [](double v) { return std::isfinite(v); });
  const double norm = conversions::quaternion_norm(p.orientation);
  if (!finite || !std::isfinite(norm) || std::abs(norm - 1.0) > 1e-3) {
    setStatus(rviz::StatusProperty::Error, "Calibration",
              finite ? QString("quaternion norm %1, not 1").arg(norm) : "NaN or Inf in the pose or covariance");
    visual_->set_visible(false);
    return;
  }
  if (!place_frame()) return;
  try {
    visual_->update(conversions::to_core(msg->pose), *covariance_property_);
  } catch (const HandEyeError& e) {
    setStatus(rviz::StatusProperty::Error, "Calibration", QString("cannot draw the covariance: ") + e.what());
    visual_->set_visible(false);
    return;
  }
  setStatus(rviz::StatusProperty::Ok, "Calibration", "OK");
  drawn_ = true;
  visual_->set_visible(covariance_property_->getBool());
}

bool CalibrationDisplay::place_frame() {
  // The covariance is expressed in the message's (parent) frame. X is a fixed
  // relation to that frame, so use its latest pose, not the one at the stamp:
  // an eye-in-hand camera moves with the flange.
  Ogre::Vector3 position;
  Ogre::Quaternion orientation;
  if (!context_->getFrameManager()->getTransform(last_->header.frame_id, ros::Time(), position, orientation)) {
    setStatus(rviz::StatusProperty::Error, "Transform",
              QString("no transform from [%1] to [%2]").arg(last_->header.frame_id.c_str()).arg(fixed_frame_));
    visual_->set_visible(false);
    return false;
  }
  setStatus(rviz::StatusProperty::Ok, "Transform", "OK");
  visual_->set_frame(position, orientation);
  return true;
}

void CalibrationDisplay::update(float wall_dt, float ros_dt) {
  MFDClass::update(wall_dt, ros_dt);
  if (drawn_ && place_frame()) visual_->set_visible(covariance_property_->getBool());
}

}  // namespace rviz_plugin
}  // namespace handeye

PLUGINLIB_EXPORT_CLASS(handeye::rviz_plugin::CalibrationDisplay, rviz::Display)
