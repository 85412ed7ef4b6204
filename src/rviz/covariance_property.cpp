#include "covariance_property.h"

namespace handeye {
namespace rviz_plugin {

CalibrationCovarianceProperty::CalibrationCovarianceProperty(rviz::Property* parent, const char* changed_slot,
                                                             QObject* receiver)
    : rviz::BoolProperty("Covariance", true, "Draw the uncertainty of the calibration.", parent, changed_slot, receiver) {
  setDisableChildrenIfFalse(true);
  sigmas_ = new rviz::FloatProperty("Scale (sigma)", 3.0f, "Ellipsoid size in standard deviations.", this,
                                    changed_slot, receiver);
  sigmas_->setMin(0.1f);
  magnify_ = new rviz::FloatProperty(
      "Magnify", 1.0f,
      "Draw the ellipsoids this many times larger (a good calibration's are millimetres); the label says so.", this,
      changed_slot, receiver);
  magnify_->setMin(1.0f);
  alpha_ = new rviz::FloatProperty("Alpha", 0.6f, "Opacity of the ellipsoids.", this, changed_slot, receiver);
  alpha_->setMin(0.0f);
  alpha_->setMax(1.0f);
  position_ = new rviz::BoolProperty("Position", true, "Ellipsoid of the camera position (translation covariance).",
                                     this, changed_slot, receiver);
  position_color_ = new rviz::ColorProperty("Position color", QColor(255, 0, 255), "Color of the position ellipsoid.",
                                            this, changed_slot, receiver);
  orientation_ = new rviz::BoolProperty(
      "Orientation", true, "One disc per axis: where the axis tip wobbles (rotation covariance).", this, changed_slot,
      receiver);
  orientation_frame_ = new rviz::EnumProperty("Orientation frame", "Local",
                                              "Axes of the discs: the camera's own (Local) or the parent frame's (Fixed).",
                                              this, changed_slot, receiver);
  orientation_frame_->addOption("Local", static_cast<int>(Frame::Local));
  orientation_frame_->addOption("Fixed", static_cast<int>(Frame::Fixed));
  axis_length_ = new rviz::FloatProperty("Axis length", 0.1f, "Distance of the orientation discs from the origin (m).",
                                         this, changed_slot, receiver);
  axis_length_->setMin(0.001f);
  label_ = new rviz::BoolProperty("Label", true, "Text with the worst-axis 1 sigma in mm and degrees.", this,
                                  changed_slot, receiver);
}

}  // namespace rviz_plugin
}  // namespace handeye
