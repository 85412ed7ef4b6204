// The display's properties: what to draw of the calibration's covariance, and how.
#pragma once

#include <rviz/properties/bool_property.h>
#include <rviz/properties/color_property.h>
#include <rviz/properties/enum_property.h>
#include <rviz/properties/float_property.h>

namespace handeye {
namespace rviz_plugin {

class CalibrationCovarianceProperty : public rviz::BoolProperty {
  Q_OBJECT
 public:
  enum class Frame { Local, Fixed };

  CalibrationCovarianceProperty(rviz::Property* parent, const char* changed_slot, QObject* receiver);

  bool position_enabled() const { return getBool() && position_->getBool(); }
  bool orientation_enabled() const { return getBool() && orientation_->getBool(); }
  bool label_enabled() const { return getBool() && label_->getBool(); }
  QColor position_color() const { return position_color_->getColor(); }
  float alpha() const { return alpha_->getFloat(); }
  float sigmas() const { return sigmas_->getFloat(); }
  float magnify() const { return magnify_->getFloat(); }
  float axis_length() const { return axis_length_->getFloat(); }
  Frame orientation_frame() const { return static_cast<Frame>(orientation_frame_->getOptionInt()); }

 private:
  rviz::FloatProperty *sigmas_, *magnify_, *alpha_, *axis_length_;
  rviz::BoolProperty *position_, *orientation_, *label_;
  rviz::ColorProperty* position_color_;
  rviz::EnumProperty* orientation_frame_;
};

}  // namespace rviz_plugin
}  // namespace handeye
