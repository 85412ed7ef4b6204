// RViz panel that drives the calibration node of one namespace: what its ~status
// says (samples, X's 1 sigma, the object error at the working distance against the
// target), its services as buttons, and a table of the samples with each one's
// residual, the rejected ones marked with the reason. The suggested next pose is
// drawn by the node (~next_pose_markers, a MarkerArray display in the config).
//
// Threads: ~status arrives on rviz's thread (rviz spins the global callback queue
// in its update), so it updates the widgets directly. A service call runs on a
// thread of its own, so a slow /calibrate never freezes rviz; the thread touches no
// Qt object (rviz may be closing): it fills a Reply that a timer on rviz's thread
// collects.
#pragma once

#ifndef Q_MOC_RUN
#include <ros/ros.h>
#include <rviz/panel.h>

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "handeye_covariance/ros/messages.h"
#endif

class QComboBox;
class QLabel;
class QPushButton;
class QTableWidget;
class QTimer;

namespace handeye {
namespace rviz_plugin {

class CalibrationPanel : public rviz::Panel {
  Q_OBJECT
 public:
  explicit CalibrationPanel(QWidget* parent = nullptr);
  ~CalibrationPanel() override;

  void onInitialize() override;
  void load(const rviz::Config& config) override;
  void save(rviz::Config config) const override;

 private Q_SLOTS:
  void on_namespace_chosen();
  void take_sample();
  void remove_selected();
  void calibrate();
  void save_calibration();
  void reset();
  void suggest();
  /// The robot moving itself (the node's ~motion/enabled): move to the next
  /// view, calibrate by itself, stop at once.
  void move();
  void auto_calibrate();
  void stop_motion();
  /// A check of the calibration from 5 new views (/check_calibration); the verdict and
  /// the views' table follow ~check.
  void check_calibration();
  /// Once a second: a status that stopped coming, and the namespaces on offer.
  void check_connection();
  /// The replies of finished service calls, shown on rviz's thread.
  void collect_replies();

 private:
  /// Follows the calibration node in `ns` ("/handeye_eye_on_hand/"). A name ROS
  /// refuses is not taken: false, with the reason under the buttons.
  bool set_namespace(const QString& ns);
  void on_status(const CalibrationStatus::ConstPtr& status);
  void on_check(const CalibrationCheckMsg::ConstPtr& check);
  /// Calls `<ns><service>` off rviz's thread; `describe` turns the reply into the
  /// line shown under the buttons.
  template <class Service>
  void call(const std::string& service, Service srv, std::function<QString(const Service&)> describe);
  void show_reply(const QString& text, bool success);
  void set_busy(bool busy);

  struct Reply {
    std::atomic<bool> done{false};
    QString text;  // written by the call's thread before `done`
    bool success = false;
  };
  std::vector<std::shared_ptr<Reply>> pending_;

  ros::NodeHandle node_;
  ros::Subscriber status_sub_, motion_sub_, check_sub_;
  std::string namespace_;  // with a leading and a trailing '/'
  CalibrationStatus status_;
  ros::WallTime last_status_;
  bool have_status_ = false;
  int calls_in_flight_ = 0;

  QComboBox* namespace_box_;
  QLabel *samples_label_, *sigma_label_, *object_label_, *target_label_, *event_label_, *reply_label_, *motion_label_,
      *check_label_;
  QPushButton *take_button_, *remove_button_, *calibrate_button_, *save_button_, *reset_button_, *suggest_button_;
  QPushButton *move_button_, *auto_button_, *stop_button_;  // Stop is never disabled
  QPushButton* check_button_;
  QTableWidget *table_, *check_table_;  // the samples; the last check's views
  QTimer *timer_, *reply_timer_;
};

}  // namespace rviz_plugin
}  // namespace handeye
