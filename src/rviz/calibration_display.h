// RViz display of a hand-eye calibration: geometry_msgs/PoseWithCovarianceStamped
// (the node's ~calibration) drawn with its position ellipsoid, per-axis
// orientation discs and a 1-sigma label.
#pragma once

#ifndef Q_MOC_RUN
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <rviz/message_filter_display.h>

#include <memory>

#include "covariance_visual.h"
#endif

namespace handeye {
namespace rviz_plugin {

class CalibrationDisplay : public rviz::MessageFilterDisplay<geometry_msgs::PoseWithCovarianceStamped> {
  Q_OBJECT
 public:
  CalibrationDisplay();
  ~CalibrationDisplay() override;

 protected:
  void onInitialize() override;
  void reset() override;
  /// Every frame: follow the parent frame (X is fixed to it, not to a moment).
  void update(float wall_dt, float ros_dt) override;

 private Q_SLOTS:
  void redraw();

 private:
  void processMessage(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) override;
  bool place_frame();

  CalibrationCovarianceProperty* covariance_property_;
  std::unique_ptr<CalibrationCovarianceVisual> visual_;
  geometry_msgs::PoseWithCovarianceStamped::ConstPtr last_;
  bool drawn_ = false;  // the last message passed validation and was drawn
};

}  // namespace rviz_plugin
}  // namespace handeye
