#include "load.h"

#include <ros/master.h>
#include <ros/network.h>
#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>
#include <xmlrpcpp/XmlRpc.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <fstream>
#include <iomanip>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <unistd.h>

#include "handeye_covariance/core/statistics.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/simulation/simulation.h"
#include "handeye_covariance/ros/messages.h"
#include "handeye_covariance/ros/msg_conversion.h"

namespace handeye {
namespace {

using Clock = std::chrono::steady_clock;

/// The pid of a ROS node, from its own XML-RPC server (the master knows its URI).
int node_pid(const std::string& node) {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  args[1] = node;
  if (!ros::master::execute("lookupNode", args, result, payload, true)) {
    throw std::runtime_error("load driver: node " + node + " is not registered with the master; is it running?");
  }
  std::string host;
  uint32_t port = 0;
  if (!ros::network::splitURI(static_cast<std::string>(payload), host, port)) {
    throw std::runtime_error("load driver: cannot parse the URI of " + node);
  }
  XmlRpc::XmlRpcClient client(host.c_str(), static_cast<int>(port), "/");
  XmlRpc::XmlRpcValue params, answer;
  params[0] = ros::this_node::getName();
  if (!client.execute("getPid", params, answer) || answer.getType() != XmlRpc::XmlRpcValue::TypeArray ||
      answer.size() < 3) {
    throw std::runtime_error("load driver: getPid failed on " + node);
  }
  return static_cast<int>(answer[2]);
}

/// utime + stime of a process, in seconds (/proc/<pid>/stat fields 14 and 15).
double cpu_seconds(const std::string& stat_path) {
  std::ifstream in(stat_path);
  std::string line;
  std::getline(in, line);
  const std::size_t close = line.rfind(')');
  if (close == std::string::npos) throw std::runtime_error("load driver: cannot read " + stat_path);
  std::istringstream fields(line.substr(close + 2));
  std::string field;
  double utime = 0, stime = 0;
  for (int i = 3; i <= 15 && fields >> field; ++i) {  // field 3 is the state
    if (i == 14) utime = std::stod(field);
    if (i == 15) stime = std::stod(field);
  }
  return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

double rss_mb(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string key;
  while (in >> key) {
    if (key == "VmRSS:") {
      double kb = 0;
      in >> kb;
      return kb / 1024.0;
    }
    in.ignore(1 << 12, '\n');
  }
  throw std::runtime_error("load driver: no VmRSS for pid " + std::to_string(pid) + "; did the node exit?");
}

/// Calls `f` at `rate` Hz on a steady schedule (late ticks are not made up) until `stop`.
template <typename F>
std::thread periodic(double rate, const std::atomic<bool>& stop, F f) {
  return std::thread([rate, &stop, f]() mutable {
    const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate));
    // The offered rate is the rate asked for: ticks a busy machine delayed are
    // sent at once when the thread runs again (as TF arrives after a network
    // stall), and only a stall longer than 0.1 s is given up on.
    const auto longest_catch_up = std::chrono::milliseconds(100);
    auto next = Clock::now();
    while (!stop) {
      f();
      next += period;
      const auto now = Clock::now();
      if (next < now - longest_catch_up) next = now;
      std::this_thread::sleep_until(next);
    }
  });
}

double median_or_zero(const std::vector<double>& v) { return v.empty() ? 0.0 : handeye::median(v); }

}  // namespace

LoadReport run_load(const LoadOptions& o) {
  ros::NodeHandle nh;
  Rng rng(static_cast<std::uint64_t>(o.seed));
  const RigTrajectory trajectory = make_rig_trajectory(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), o.poses, o.pause, o.move);
  const double session_period = o.poses * (o.pause + o.move);
  PoseNoise noise;
  noise.rotation = std::pow(radians(0.05), 2) * Eigen::Matrix3d::Identity();
  noise.translation = std::pow(0.3e-3, 2) * Eigen::Matrix3d::Identity();

  ros::Publisher tf_pub = nh.advertise<tf2_msgs::TFMessage>("/tf", 100);
  ros::Publisher detection_pub = nh.advertise<TagDetectionArray>(o.detections_topic, 100);
  std::mutex status_mutex;
  CalibrationStatus status;
  bool have_status = false;
  ros::Subscriber status_sub = nh.subscribe<CalibrationStatus>(o.node + "/status", 10, [&](const CalibrationStatus::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(status_mutex);
    status = *msg;
    have_status = true;
  });
  ros::ServiceClient reset = nh.serviceClient<Reset>(o.reset_service);
  ros::ServiceClient list = nh.serviceClient<ListSamples>(ros::names::parentNamespace(o.reset_service) + "/list_samples");
  ros::AsyncSpinner spinner(1);
  spinner.start();

  const ros::WallTime connect_deadline = ros::WallTime::now() + ros::WallDuration(20.0);
  while (tf_pub.getNumSubscribers() == 0 || detection_pub.getNumSubscribers() == 0 || !have_status) {
    if (ros::WallTime::now() > connect_deadline) {
      throw std::runtime_error("load driver: " + o.node + " did not subscribe to /tf and " + o.detections_topic +
                               " (or publish ~status) within 20 s");
    }
    ros::WallDuration(0.05).sleep();
  }
  if (!reset.waitForExistence(ros::Duration(10.0))) throw std::runtime_error("load driver: no service " + o.reset_service);
  const int pid = node_pid(o.node);  // registered by now: it publishes ~status
  std::uint32_t handled_before = 0;
  {
    std::lock_guard<std::mutex> lock(status_mutex);
    handled_before = status.detections_received;
  }

  const Clock::time_point start = Clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  auto session_time = [&](double t) { return std::fmod(t, session_period); };
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> tf_sent{0}, detections_sent{0};

  std::thread tf_thread = periodic(o.tf_rate, stop, [&] {
    const double t = elapsed();
    tf2_msgs::TFMessage msg;
    msg.transforms.push_back(conversions::to_transform_stamped(trajectory.effector_at(session_time(t)), o.base_frame,
                                                               o.effector_frame, ros::Time::now()));
    tf_pub.publish(msg);
    ++tf_sent;
  });
  Rng detection_rng(static_cast<std::uint64_t>(o.seed) + 1);
  std::thread detection_thread = periodic(o.detection_rate, stop, [&] {
    // Stamped now and published at once: the robot TF for this stamp is at most 1/tf_rate away.
    const ros::Time stamp = ros::Time::now();
    const double t = elapsed();
    if (t < o.tf_warmup) return;
    TagDetectionArray array;
    array.header.stamp = stamp;
    array.header.frame_id = o.camera_frame;
    TagDetection detection;
    detection.id = {o.tag_id};
    detection.size = {0.1};
    detection.pose.header = array.header;
    detection.pose.pose.pose = conversions::to_pose_msg(perturb(detection_rng, trajectory.pattern_at(session_time(t)), noise));
    array.detections.push_back(detection);
    detection_pub.publish(array);
    ++detections_sent;
  });

  LoadReport report;
  const double driver_cpu_start = cpu_seconds("/proc/self/stat");
  const std::string node_stat = "/proc/" + std::to_string(pid) + "/stat";
  const double node_cpu_start = cpu_seconds(node_stat);
  double last_node_cpu = node_cpu_start, last_driver_cpu = driver_cpu_start, last_t = 0.0;
  int session = 0;
  for (int second = 1; second <= static_cast<int>(std::ceil(o.duration)); ++second) {
    std::this_thread::sleep_until(start + std::chrono::seconds(second));
    const double t = elapsed();
    const int now_session = static_cast<int>(t / session_period);
    if (now_session != session) {  // the robot went back to the first pose: a new session
      ListSamples samples;
      report.samples_per_session.push_back(list.call(samples) ? samples.response.samples : -1);
      Reset r;
      if (!reset.call(r) || !r.response.success) throw std::runtime_error("load driver: /reset failed");
      session = now_session;
    }
    LoadRow row;
    row.t = t;
    const double node_cpu = cpu_seconds(node_stat), driver_cpu = cpu_seconds("/proc/self/stat");
    row.node_cpu_percent = 100.0 * (node_cpu - last_node_cpu) / (t - last_t);
    row.driver_cpu_percent = 100.0 * (driver_cpu - last_driver_cpu) / (t - last_t);
    last_node_cpu = node_cpu;
    last_driver_cpu = driver_cpu;
    last_t = t;
    row.node_rss_mb = rss_mb(pid);
    row.tf_sent = tf_sent;
    row.detections_sent = detections_sent;
    {
      std::lock_guard<std::mutex> lock(status_mutex);
      row.samples = status.samples;
      row.detections_handled = status.detections_received - handled_before;
      row.age_median_ms = status.detection_age_median_ms;
      row.age_p99_ms = status.detection_age_p99_ms;
      row.age_max_ms = status.detection_age_max_ms;
    }
    report.rows.push_back(row);
  }
  stop = true;
  tf_thread.join();
  detection_thread.join();
  const double run_time = elapsed();
  ListSamples samples;
  report.samples_per_session.push_back(list.call(samples) ? samples.response.samples : -1);
  report.sessions = static_cast<int>(report.samples_per_session.size());
  report.node_cpu_percent = 100.0 * (last_node_cpu - node_cpu_start) / last_t;
  report.driver_cpu_percent = 100.0 * (last_driver_cpu - driver_cpu_start) / last_t;
  report.tf_sent = tf_sent;
  report.detections_sent = detections_sent;
  report.tf_rate_achieved = static_cast<double>(tf_sent) / run_time;

  // The node's count arrives with its next ~status (at least once a second).
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(5.0);
  while (ros::WallTime::now() < deadline) {
    {
      std::lock_guard<std::mutex> lock(status_mutex);
      report.detections_handled = status.detections_received - handled_before;
    }
    if (report.detections_handled >= report.detections_sent) break;
    ros::WallDuration(0.1).sleep();
  }

  const std::size_t n = report.rows.size();
  const std::size_t fifth = std::max<std::size_t>(1, n / 5);
  std::vector<double> medians;
  double sx = 0, sy = 0, sxx = 0, sxy = 0, m = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const LoadRow& r = report.rows[i];
    if (i < fifth) report.rss_first_minute_mb = std::max(report.rss_first_minute_mb, r.node_rss_mb);
    if (i >= n - fifth) report.rss_last_minute_mb = std::max(report.rss_last_minute_mb, r.node_rss_mb);
    report.rss_max_mb = std::max(report.rss_max_mb, r.node_rss_mb);
    medians.push_back(r.age_median_ms);
    report.age_p99_worst_ms = std::max(report.age_p99_worst_ms, r.age_p99_ms);
    report.age_max_ms = std::max(report.age_max_ms, r.age_max_ms);
    if (i >= n / 2) {
      const double x = r.t / 60.0;
      sx += x, sy += r.node_rss_mb, sxx += x * x, sxy += x * r.node_rss_mb, m += 1;
    }
  }
  report.age_median_ms = median_or_zero(medians);
  constexpr int kBin = 10;
  int largest = 0;
  for (const LoadRow& r : report.rows) largest = std::max(largest, r.samples);
  for (int first = 0; first <= largest; first += kBin) {
    LoadReport::AgeBin bin;
    bin.first_sample = first;
    bin.last_sample = first + kBin - 1;
    std::vector<double> bin_medians;
    for (const LoadRow& r : report.rows) {
      if (r.samples < first || r.samples > bin.last_sample || r.detections_handled == 0) continue;
      ++bin.rows;
      bin_medians.push_back(r.age_median_ms);
      bin.p99_worst_ms = std::max(bin.p99_worst_ms, r.age_p99_ms);
      bin.max_ms = std::max(bin.max_ms, r.age_max_ms);
    }
    bin.median_ms = median_or_zero(bin_medians);
    if (bin.rows > 0) report.age_by_samples.push_back(bin);
  }
  if (m >= 2 && m * sxx - sx * sx > 0) report.rss_slope_mb_per_min = (m * sxy - sx * sy) / (m * sxx - sx * sx);
  return report;
}

std::string format_load_csv(const LoadReport& report) {
  std::ostringstream out;
  out << "t_s,node_cpu_percent,driver_cpu_percent,node_rss_mb,samples,tf_sent,detections_sent,detections_handled,"
         "age_median_ms,age_p99_ms,age_max_ms\n";
  out << std::fixed << std::setprecision(3);
  for (const LoadRow& r : report.rows) {
    out << r.t << ',' << r.node_cpu_percent << ',' << r.driver_cpu_percent << ',' << r.node_rss_mb << ',' << r.samples
        << ',' << r.tf_sent << ',' << r.detections_sent << ',' << r.detections_handled << ',' << r.age_median_ms << ','
        << r.age_p99_ms << ',' << r.age_max_ms << '\n';
  }
  return out.str();
}

std::string format_load_summary(const LoadReport& r, const LoadOptions& o) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(1);
  out << "| | |\n|---|---|\n";
  out << "| run | " << o.duration << " s, TF " << o.tf_rate << " Hz (achieved " << r.tf_rate_achieved << " Hz), detections "
      << o.detection_rate << " Hz, " << r.sessions << " sessions of " << o.poses << " poses |\n";
  out << "| samples per session | ";
  for (std::size_t i = 0; i < r.samples_per_session.size(); ++i) out << (i ? ", " : "") << r.samples_per_session[i];
  out << " |\n";
  out << "| detections sent / handled | " << r.detections_sent << " / " << r.detections_handled << " |\n";
  out << "| node CPU (mean, % of one core) | " << r.node_cpu_percent << " |\n";
  out << "| driver CPU (mean, % of one core) | " << r.driver_cpu_percent << " |\n";
  out << std::setprecision(2);
  out << "| node RSS: max of first 20% / last 20% / overall | " << r.rss_first_minute_mb << " / " << r.rss_last_minute_mb
      << " / " << r.rss_max_mb << " MB |\n";
  out << "| node RSS slope over the second half | " << r.rss_slope_mb_per_min << " MB/min |\n";
  out << std::setprecision(1);
  out << "| detection age at the node: median / worst p99 / max | " << r.age_median_ms << " / " << r.age_p99_worst_ms
      << " / " << r.age_max_ms << " ms |\n";
  out << "\nDetection age against the number of samples in the session:\n\n"
         "| samples | seconds | age median [ms] | worst p99 [ms] | max [ms] |\n|---|---:|---:|---:|---:|\n";
  for (const LoadReport::AgeBin& b : r.age_by_samples) {
    out << "| " << b.first_sample << "-" << b.last_sample << " | " << b.rows << " | " << b.median_ms << " | "
        << b.p99_worst_ms << " | " << b.max_ms << " |\n";
  }
  return out.str();
}

}  // namespace handeye
