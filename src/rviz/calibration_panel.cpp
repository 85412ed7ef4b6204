#include "calibration_panel.h"

#include <QApplication>
#include <QComboBox>
#include <QGridLayout>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QLineEdit>
#include <QMessageBox>
#include <QPushButton>
#include <std_msgs/String.h>
#include <std_srvs/Trigger.h>
#include <QTableWidget>
#include <QTextDocument>
#include <QTimer>
#include <QVBoxLayout>

#include <ros/master.h>
#include <ros/names.h>

#include <pluginlib/class_list_macros.hpp>

#include <algorithm>
#include <thread>

namespace handeye {
namespace rviz_plugin {

namespace {

const char kStatusSuffix[] = "handeye_calibration/status";
const char kDefaultNamespace[] = "/handeye_eye_on_hand/";

QString mm(double value) { return QString::number(value, 'f', 2); }
QString deg(double value) { return QString::number(value, 'f', 3); }

/// "/a/b/" from "a/b", "/a/b" or "/a/b/".
std::string normalised(std::string ns) {
  if (ns.empty() || ns.front() != '/') ns.insert(ns.begin(), '/');
  if (ns.back() != '/') ns.push_back('/');
  return ns;
}

QPushButton* button(const QString& text, const char* name, const QString& tip) {
  auto* b = new QPushButton(text);
  b->setObjectName(name);
  b->setToolTip(tip);
  return b;
}

QLabel* label(const char* name) {
  auto* l = new QLabel;
  l->setObjectName(name);
  l->setWordWrap(true);
  l->setTextFormat(Qt::RichText);  // node text goes in escaped
  l->setTextInteractionFlags(Qt::TextSelectableByMouse);
  return l;
}

}  // namespace

CalibrationPanel::CalibrationPanel(QWidget* parent) : rviz::Panel(parent) {
  namespace_box_ = new QComboBox;
  namespace_box_->setObjectName("namespace");
  namespace_box_->setEditable(true);
  namespace_box_->setToolTip("The calibration node's namespace: its services are <namespace>calibrate, ..., its "
                             "status <namespace>handeye_calibration/status. Nodes that are running are listed.");
  auto* top = new QHBoxLayout;
  top->addWidget(new QLabel("Node"));
  top->addWidget(namespace_box_, 1);

  samples_label_ = label("samples_label");
  sigma_label_ = label("sigma_label");
  object_label_ = label("object_label");
  target_label_ = label("target_label");
  event_label_ = label("event_label");
  reply_label_ = label("reply_label");
  motion_label_ = label("motion_label");
  check_label_ = label("check_label");

  take_button_ = button("Take sample", "take_sample", "Sample the current robot pose and detection (the robot must stand still)");
  remove_button_ = button("Remove selected", "remove_sample", "Remove the sample selected in the table");
  calibrate_button_ = button("Calibrate", "calibrate", "Solve for X with its covariance; publish it and write the result file");
  save_button_ = button("Save", "save_calibration", "Write the calibration to the node's calibration_file");
  reset_button_ = button("Reset", "reset", "Drop every sample (asks first)");
  suggest_button_ = button("Suggest pose", "suggest_pose",
                           "Rank next poses by the predicted object error; the best is drawn in 3D (ghost frame, frustum)");
  move_button_ = button("Move", "move",
                        "Move the arm to the next view the session ranks (planned and checked first) and sample there");
  auto_button_ = button("Auto", "auto_calibrate", "Plan, move and sample until the target object error (Stop stops it)");
  stop_button_ = button("Stop", "stop_motion", "Stop the arm at once (a hold trajectory)");
  check_button_ = button("Check", "check_calibration",
                         "Is the calibration still right? Takes 5 new views (as samples are taken) into a list of their "
                         "own and tests them against X, Y and their covariance: consistent, or X / Y changed");
  auto* buttons = new QGridLayout;
  buttons->addWidget(take_button_, 0, 0);
  buttons->addWidget(remove_button_, 0, 1);
  buttons->addWidget(suggest_button_, 0, 2);
  buttons->addWidget(calibrate_button_, 1, 0);
  buttons->addWidget(save_button_, 1, 1);
  buttons->addWidget(reset_button_, 1, 2);
  buttons->addWidget(move_button_, 2, 0);
  buttons->addWidget(auto_button_, 2, 1);
  buttons->addWidget(stop_button_, 2, 2);
  buttons->addWidget(check_button_, 3, 0);

  table_ = new QTableWidget(0, 5);
  table_->setObjectName("samples");
  table_->setHorizontalHeaderLabels({"#", "mm", "deg", "sigma", "state"});
  table_->horizontalHeaderItem(1)->setToolTip("translation residual: the pattern's pose against what X predicts");
  table_->horizontalHeaderItem(2)->setToolTip("rotation residual");
  table_->horizontalHeaderItem(3)->setToolTip("the residual in sigmas of its predicted covariance (6 dof); above ~5 is suspect");
  table_->verticalHeader()->setVisible(false);
  table_->horizontalHeader()->setStretchLastSection(true);
  table_->setSelectionBehavior(QAbstractItemView::SelectRows);
  table_->setSelectionMode(QAbstractItemView::SingleSelection);
  table_->setEditTriggers(QAbstractItemView::NoEditTriggers);

  check_table_ = new QTableWidget(0, 6);
  check_table_->setObjectName("check_views");
  check_table_->setHorizontalHeaderLabels({"view", "mm", "1σ mm", "deg", "1σ deg", "sigma"});
  check_table_->horizontalHeaderItem(1)->setToolTip("the view's error against what the calibration predicts");
  check_table_->horizontalHeaderItem(2)->setToolTip("the error's RMS the calibration predicts for this view");
  check_table_->horizontalHeaderItem(5)->setToolTip("Mahalanobis length (6 dof): about 2.3 on average when nothing changed");
  check_table_->verticalHeader()->setVisible(false);
  check_table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  check_table_->setVisible(false);  // until a check has views

  auto* layout = new QVBoxLayout;
  layout->addLayout(top);
  layout->addWidget(samples_label_);
  layout->addWidget(sigma_label_);
  layout->addWidget(object_label_);
  layout->addWidget(target_label_);
  layout->addLayout(buttons);
  layout->addWidget(motion_label_);
  layout->addWidget(check_label_);
  layout->addWidget(check_table_);
  layout->addWidget(reply_label_);
  layout->addWidget(table_, 1);
  layout->addWidget(event_label_);
  setLayout(layout);

  connect(namespace_box_->lineEdit(), &QLineEdit::editingFinished, this, &CalibrationPanel::on_namespace_chosen);
  connect(namespace_box_, QOverload<int>::of(&QComboBox::activated), this, &CalibrationPanel::on_namespace_chosen);
  connect(take_button_, &QPushButton::clicked, this, &CalibrationPanel::take_sample);
  connect(remove_button_, &QPushButton::clicked, this, &CalibrationPanel::remove_selected);
  connect(calibrate_button_, &QPushButton::clicked, this, &CalibrationPanel::calibrate);
  connect(save_button_, &QPushButton::clicked, this, &CalibrationPanel::save_calibration);
  connect(reset_button_, &QPushButton::clicked, this, &CalibrationPanel::reset);
  connect(suggest_button_, &QPushButton::clicked, this, &CalibrationPanel::suggest);
  connect(move_button_, &QPushButton::clicked, this, &CalibrationPanel::move);
  connect(auto_button_, &QPushButton::clicked, this, &CalibrationPanel::auto_calibrate);
  connect(stop_button_, &QPushButton::clicked, this, &CalibrationPanel::stop_motion);
  connect(check_button_, &QPushButton::clicked, this, &CalibrationPanel::check_calibration);
  timer_ = new QTimer(this);
  connect(timer_, &QTimer::timeout, this, &CalibrationPanel::check_connection);
  reply_timer_ = new QTimer(this);
  connect(reply_timer_, &QTimer::timeout, this, &CalibrationPanel::collect_replies);
}

CalibrationPanel::~CalibrationPanel() = default;

void CalibrationPanel::onInitialize() {
  if (namespace_.empty()) set_namespace(kDefaultNamespace);
  timer_->start(1000);
}

void CalibrationPanel::load(const rviz::Config& config) {
  rviz::Panel::load(config);
  QString ns;
  if (!config.mapGetString("Namespace", &ns) || !set_namespace(ns)) set_namespace(kDefaultNamespace);
}

void CalibrationPanel::save(rviz::Config config) const {
  rviz::Panel::save(config);
  config.mapSetValue("Namespace", QString::fromStdString(namespace_));
}

void CalibrationPanel::on_namespace_chosen() {
  const std::string ns = normalised(namespace_box_->currentText().trimmed().toStdString());
  if (ns != namespace_ && set_namespace(QString::fromStdString(ns))) Q_EMIT configChanged();
}

bool CalibrationPanel::set_namespace(const QString& text) {
  const std::string ns = normalised(text.trimmed().toStdString());
  std::string why;
  ros::Subscriber subscriber;
  if (ns != "/" && !ros::names::validate(ns.substr(0, ns.size() - 1), why)) {
    why = "not a ROS name: " + why;
  } else {
    try {
      subscriber = node_.subscribe<CalibrationStatus>(ns + kStatusSuffix, 1,
                                                      [this](const CalibrationStatus::ConstPtr& s) { on_status(s); });
    } catch (const ros::Exception& e) {
      why = e.what();
    }
  }
  if (!subscriber) {
    reply_label_->setText(QString("<span style='color:#e05050'>Namespace %1 refused (%2); still following %3</span>")
                              .arg(QString::fromStdString(ns).toHtmlEscaped(), QString::fromStdString(why).toHtmlEscaped(),
                                   QString::fromStdString(namespace_).toHtmlEscaped()));
    namespace_box_->setEditText(QString::fromStdString(namespace_));
    return false;
  }
  namespace_ = ns;
  status_sub_ = subscriber;
  // Only a node that moves the arm publishes it; the line stays empty otherwise.
  motion_sub_ = node_.subscribe<std_msgs::String>(ns + "handeye_calibration/motion_status", 1,
                                                  [this](const std_msgs::String::ConstPtr& m) {
                                                    motion_label_->setText("<b>Motion</b> " +
                                                                           QString::fromStdString(m->data).toHtmlEscaped());
                                                  });
  check_sub_ = node_.subscribe<CalibrationCheckMsg>(ns + "handeye_calibration/check", 1,
                                                   [this](const CalibrationCheckMsg::ConstPtr& c) { on_check(c); });
  check_table_->setRowCount(0);
  check_table_->setVisible(false);
  namespace_box_->setEditText(QString::fromStdString(namespace_));
  have_status_ = false;
  status_ = CalibrationStatus();
  table_->setRowCount(0);
  for (QLabel* l : {sigma_label_, object_label_, target_label_, event_label_, reply_label_, motion_label_, check_label_}) {
    l->clear();
  }
  samples_label_->setText("Waiting for " + QString::fromStdString(namespace_ + kStatusSuffix).toHtmlEscaped() + " ...");
  last_status_ = ros::WallTime::now();
  return true;
}

void CalibrationPanel::check_connection() {
  const double silent = (ros::WallTime::now() - last_status_).toSec();
  if (have_status_ && silent > 5.0) {
    event_label_->setText(QString("<b>No status from %1 for %2 s</b>: has the calibration node stopped?")
                              .arg(QString::fromStdString(namespace_).toHtmlEscaped())
                              .arg(static_cast<int>(silent)));
  }
  // The namespaces on offer: every CalibrationStatus topic (only while waiting, and
  // only with a master, whose call would otherwise block rviz until it returns).
  if (have_status_ || !ros::master::check()) return;
  ros::master::V_TopicInfo topics;
  if (!ros::master::getTopics(topics)) return;
  const std::string suffix = kStatusSuffix;
  for (const ros::master::TopicInfo& t : topics) {
    if (t.datatype != "handeye_covariance/CalibrationStatus" || t.name.size() <= suffix.size()) continue;
    const QString ns = QString::fromStdString(t.name.substr(0, t.name.size() - suffix.size()));
    if (namespace_box_->findText(ns) < 0) namespace_box_->addItem(ns);
  }
  // The first item added becomes the current one: the box keeps saying what is followed.
  if (!namespace_box_->lineEdit()->hasFocus()) namespace_box_->setEditText(QString::fromStdString(namespace_));
  if (!have_status_ && silent > 5.0) {
    samples_label_->setText(QString("No calibration node in %1 (no %2). Start calibrate.launch, or pick a node above.")
                                .arg(QString::fromStdString(namespace_).toHtmlEscaped(),
                                     QString::fromStdString(namespace_ + kStatusSuffix).toHtmlEscaped()));
  }
}

void CalibrationPanel::on_status(const CalibrationStatus::ConstPtr& s) {
  status_ = *s;
  have_status_ = true;
  last_status_ = ros::WallTime::now();
  samples_label_->setText(QString("<b>%1 samples</b> (%2 for an estimate) — %3")
                              .arg(s->samples)
                              .arg(s->samples_needed)
                              .arg(QString::fromStdString(s->state).replace('_', ' ').toHtmlEscaped()));
  if (s->has_estimate) {
    sigma_label_->setText(QString("X 1σ (%1 samples): x %2, y %3, z %4 mm; rx %5, ry %6, rz %7°")
                              .arg(s->estimate_samples)
                              .arg(mm(s->sigma_translation_mm[0]), mm(s->sigma_translation_mm[1]),
                                   mm(s->sigma_translation_mm[2]), deg(s->sigma_rotation_deg[0]),
                                   deg(s->sigma_rotation_deg[1]), deg(s->sigma_rotation_deg[2])));
    object_label_->setText(QString("Object at %1 m: %2 mm 1σ (target %3 mm)")
                               .arg(QString::number(s->working_distance, 'f', 2), mm(s->object_error_mm),
                                    mm(s->target_tolerance_mm)));
    target_label_->setText(s->target_reached
                               ? "<span style='color:#2e9e44'><b>Target reached</b></span>"
                               : QString("<span style='color:#d9822b'><b>Target not reached</b></span>%1")
                                     .arg(s->has_suggestion ? QString(": next pose brings %1 mm (drawn in 3D)")
                                                                  .arg(mm(s->next_pose_object_error_mm))
                                                            : QString()));
  } else {
    sigma_label_->setText("X: no estimate yet");
    object_label_->clear();
    target_label_->clear();
  }
  event_label_->setText(QString::fromStdString(s->last_event).toHtmlEscaped());

  // Any publisher may speak on ~status: lengths are checked, not assumed.
  const int samples = std::max(0, s->samples);
  const bool fitted = s->sample_residual_mm.size() == static_cast<std::size_t>(samples) &&
                      s->sample_residual_deg.size() == s->sample_residual_mm.size() &&
                      s->sample_residual_sigma.size() == s->sample_residual_mm.size();
  const int selected = table_->currentRow();
  table_->setRowCount(samples);
  for (int i = 0; i < samples; ++i) {
    const auto rejected = std::find(s->rejected_samples.begin(), s->rejected_samples.end(), i);
    const bool is_rejected = rejected != s->rejected_samples.end();
    const std::size_t k = static_cast<std::size_t>(rejected - s->rejected_samples.begin());
    const QString reason =
        is_rejected && k < s->rejected_reasons.size() ? QString::fromStdString(s->rejected_reasons[k]) : QString();
    const QStringList cells = {QString::number(i),
                               fitted ? mm(s->sample_residual_mm[i]) : QString("-"),
                               fitted ? deg(s->sample_residual_deg[i]) : QString("-"),
                               fitted ? QString::number(s->sample_residual_sigma[i], 'f', 1) : QString("-"),
                               is_rejected ? "rejected: " + reason : QString(fitted ? "kept" : "")};
    for (int column = 0; column < cells.size(); ++column) {
      auto* item = new QTableWidgetItem(cells[column]);
      if (column < 4) item->setTextAlignment(Qt::AlignRight | Qt::AlignVCenter);
      if (is_rejected) {
        item->setBackground(QColor(120, 40, 40));
        item->setToolTip(Qt::convertFromPlainText(reason));
      }
      table_->setItem(i, column, item);
    }
  }
  table_->resizeColumnsToContents();
  if (selected >= 0 && selected < samples) table_->selectRow(selected);
}

template <class Service>
void CalibrationPanel::call(const std::string& service, Service srv, std::function<QString(const Service&)> describe) {
  const std::string name = namespace_ + service;
  set_busy(true);
  reply_label_->setText(QString("%1 ...").arg(QString::fromStdString(name).toHtmlEscaped()));
  auto reply = std::make_shared<Reply>();
  pending_.push_back(reply);
  if (!reply_timer_->isActive()) reply_timer_->start(50);
  std::thread([reply, name, srv, describe]() mutable {
    const QString quoted = QString::fromStdString(name).toHtmlEscaped();
    try {
      if (!ros::service::waitForService(name, ros::Duration(2.0))) {
        reply->text = QString("No service %1: is the calibration node running in this namespace?").arg(quoted);
      } else if (!ros::service::call(name, srv)) {
        reply->text = QString("%1 failed in transport (did the node stop?)").arg(quoted);
      } else {
        reply->success = srv.response.success;
        reply->text = reply->success ? describe(srv) : QString::fromStdString(srv.response.message).toHtmlEscaped();
      }
    } catch (const ros::Exception& e) {
      reply->text = QString("%1: %2").arg(quoted, QString(e.what()).toHtmlEscaped());
    }
    reply->done = true;
  }).detach();
}

void CalibrationPanel::collect_replies() {
  for (auto it = pending_.begin(); it != pending_.end();) {
    if ((*it)->done) {
      show_reply((*it)->text, (*it)->success);
      it = pending_.erase(it);
    } else {
      ++it;
    }
  }
  if (pending_.empty()) reply_timer_->stop();
}

void CalibrationPanel::show_reply(const QString& text, bool success) {
  set_busy(false);
  reply_label_->setText(success ? text : "<span style='color:#e05050'>" + text + "</span>");  // escaped already
}

void CalibrationPanel::set_busy(bool busy) {
  calls_in_flight_ = std::max(0, calls_in_flight_ + (busy ? 1 : -1));
  for (QPushButton* b : {take_button_, remove_button_, calibrate_button_, save_button_, reset_button_, suggest_button_,
                         move_button_, auto_button_, check_button_}) {
    b->setEnabled(calls_in_flight_ == 0);
  }
}

namespace {
QString trigger_reply(const std_srvs::Trigger& s) { return QString::fromStdString(s.response.message).toHtmlEscaped(); }
}  // namespace

void CalibrationPanel::move() { call<std_srvs::Trigger>("move", {}, trigger_reply); }
void CalibrationPanel::auto_calibrate() { call<std_srvs::Trigger>("auto_calibrate", {}, trigger_reply); }
void CalibrationPanel::stop_motion() { call<std_srvs::Trigger>("stop_motion", {}, trigger_reply); }

void CalibrationPanel::check_calibration() {
  CheckCalibration srv;
  srv.request.views = 5;
  call<CheckCalibration>("check_calibration", srv, [](const CheckCalibration& c) {
    return QString::fromStdString(c.response.message).toHtmlEscaped();
  });
}

void CalibrationPanel::on_check(const CalibrationCheckMsg::ConstPtr& c) {
  const QString text = QString::fromStdString(c->text).toHtmlEscaped();
  if (c->state == "collecting") {
    check_label_->setText(QString("<b>Check</b> %1").arg(text));
    return;
  }
  const QString colour = c->state == "changed" ? "#e05050" : c->state == "consistent" ? "#2e9e44" : "#d9822b";
  QString advice;
  for (const std::string& a : c->advice) advice += "<br>" + QString::fromStdString(a).toHtmlEscaped();
  check_label_->setText(QString("<b>Check</b> <span style='color:%1'><b>%2</b></span>: %3%4")
                            .arg(colour, QString::fromStdString(c->state).toHtmlEscaped(), text, advice));
  // Any publisher may speak on ~check: lengths are checked, not assumed.
  const std::size_t n = c->view_error_mm.size();
  const bool whole = c->view_sigma_mm.size() == n && c->view_error_deg.size() == n && c->view_sigma_deg.size() == n &&
                     c->view_mahalanobis.size() == n;
  check_table_->setRowCount(whole ? static_cast<int>(n) : 0);
  for (std::size_t i = 0; whole && i < n; ++i) {
    const bool left_out = std::find(c->left_out.begin(), c->left_out.end(), static_cast<int>(i)) != c->left_out.end();
    const QStringList cells = {QString::number(i) + (left_out ? " (left out)" : ""), mm(c->view_error_mm[i]),
                               mm(c->view_sigma_mm[i]), deg(c->view_error_deg[i]), deg(c->view_sigma_deg[i]),
                               QString::number(c->view_mahalanobis[i], 'f', 1)};
    for (int column = 0; column < cells.size(); ++column) {
      auto* item = new QTableWidgetItem(cells[column]);
      if (column > 0) item->setTextAlignment(Qt::AlignRight | Qt::AlignVCenter);
      // Beyond 4 sigma: chi2(6) above 16, 1.4% of the views when nothing changed.
      if (c->view_mahalanobis[i] > 4.0) item->setBackground(QColor(120, 40, 40));
      check_table_->setItem(static_cast<int>(i), column, item);
    }
  }
  check_table_->resizeColumnsToContents();
  check_table_->setVisible(whole && n > 0);
}

void CalibrationPanel::take_sample() {
  call<TakeSample>("take_sample", {}, [](const TakeSample& s) {
    return QString("Sample taken: %1 samples").arg(s.response.samples);
  });
}

void CalibrationPanel::remove_selected() {
  const int row = table_->currentRow();
  if (row < 0 || table_->selectionModel()->selectedRows().isEmpty()) {
    reply_label_->setText("Select a sample in the table first.");
    return;
  }
  RemoveSample srv;
  srv.request.index = row;
  call<RemoveSample>("remove_sample", srv, [row](const RemoveSample& s) {
    return QString("Removed sample %1: %2 samples").arg(row).arg(s.response.samples);
  });
  table_->clearSelection();  // the row now holds the next sample: a second press must choose again
}

void CalibrationPanel::calibrate() {
  call<Calibrate>("calibrate", {}, [](const Calibrate& s) {
    const auto& r = s.response;
    QString text = QString("Calibrated (%1) from %2 samples, noise %3; written to %4")
                       .arg(QString::fromStdString(r.method).toHtmlEscaped())
                       .arg(r.samples_used)
                       .arg(QString::fromStdString(r.noise_origin).replace('_', ' ').toHtmlEscaped(),
                            QString::fromStdString(r.calibration_file).toHtmlEscaped());
    if (!r.rejected_samples.empty()) text += QString("; %1 sample(s) rejected").arg(r.rejected_samples.size());
    if (r.honesty == "not run") {
      text += "<br>honesty check not run: " + QString::fromStdString(r.honesty_text).toHtmlEscaped();
    } else if (!r.honesty.empty()) {
      // The verdict first, in words; then the figures it rests on.
      text += QString("<br><b>%1</b>: split-half NEES %2 against %3 (5-95%: %4 to %5) for an honest covariance here%6")
                  .arg(QString::fromStdString(r.honesty_text).toHtmlEscaped())
                  .arg(r.split_half_nees, 0, 'f', 2)
                  .arg(r.honest_nees, 0, 'f', 2)
                  .arg(r.honest_nees_band[0], 0, 'f', 2)
                  .arg(r.honest_nees_band[1], 0, 'f', 2)
                  .arg(r.covariance_inflation > 1.0 ? QString("; the covariance is the model's x%1").arg(r.covariance_inflation, 0, 'f', 2)
                                                    : QString());
    }
    for (const std::string& w : r.warnings) text += "<br>warning: " + QString::fromStdString(w).toHtmlEscaped();
    return text;
  });
}

void CalibrationPanel::save_calibration() {
  call<SaveCalibration>("save_calibration", {}, [](const SaveCalibration& s) {
    return QString("Saved to %1").arg(QString::fromStdString(s.response.path).toHtmlEscaped());
  });
}

void CalibrationPanel::reset() {
  const auto answer = QMessageBox::question(
      this, "Reset the session",
      QString("Drop all %1 samples? The session file is emptied too.").arg(have_status_ ? status_.samples : 0));
  if (answer != QMessageBox::Yes) return;
  call<Reset>("reset", {}, [](const Reset&) { return QString("Reset: no samples"); });
}

void CalibrationPanel::suggest() {
  call<SuggestPose>("suggest_pose", {}, [](const SuggestPose& s) {
    const auto& r = s.response;
    QString text = QString("Best next pose: object 1σ %1 → %2 mm (drawn in 3D); ")
                       .arg(mm(r.current_object_error_mm),
                            r.predicted_object_error_mm.empty() ? QString("-") : mm(r.predicted_object_error_mm[0]));
    text += r.poses_to_target >= 0 ? QString("%1 more pose(s) reach the target").arg(r.poses_to_target)
                                   : QString("the target is not within 30 more poses");
    return text;
  });
}

}  // namespace rviz_plugin
}  // namespace handeye

PLUGINLIB_EXPORT_CLASS(handeye::rviz_plugin::CalibrationPanel, rviz::Panel)
