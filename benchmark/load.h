// The load driver: feeds a running calibration node as a fast robot and camera
// would, for a given time, and records how the node copes. The robot TF comes at
// `tf_rate`, the tag detections at `detection_rate` (stamped when published, so
// their age at the node is pure pipeline: transport, TF wait, queue, work). The
// simulated robot stops at `poses` viewpoints per session (pause, then move);
// after the last one the driver calls /reset and the next session starts, so a
// long run is many realistic sessions, not one ever-growing sample set.
//
// Once a second it reads the node's CPU time and RSS from /proc/<pid> (the pid
// from the node's XML-RPC getPid) and its ~status (detections handled, their
// age). Used by the 10-minute benchmark (handeye_load) and the 20-s rostest.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace handeye {

struct LoadOptions {
  double duration = 600.0;      // s
  double tf_rate = 1000.0;      // Hz
  double detection_rate = 30.0; // Hz
  int poses = 60;               // per session (a long one: the node's work grows with it)
  double pause = 2.0, move = 1.0;  // s, at each pose and between poses
  /// s of robot TF before the first detection, as a robot publishes TF long before the
  /// camera pipeline runs; without it the first detections wait tf_timeout for TF
  /// history and are refused (a start-up effect, not the node's work).
  double tf_warmup = 1.0;
  std::string node = "/handeye_eye_on_hand/handeye_calibration";  // its ~status and pid
  std::string reset_service = "/handeye_eye_on_hand/reset";
  std::string detections_topic = "/tag_detections";
  std::string base_frame = "base_link", effector_frame = "tool0", camera_frame = "camera_optical_frame";
  int tag_id = 0;
  int seed = 1;
};

/// One row per second.
struct LoadRow {
  double t = 0.0;                  // s since the start
  double node_cpu_percent = 0.0;   // of one core, over the last second
  double driver_cpu_percent = 0.0;
  double node_rss_mb = 0.0;
  int samples = 0;                 // in the node's current session
  std::uint64_t detections_sent = 0, detections_handled = 0, tf_sent = 0;
  double age_median_ms = 0.0, age_p99_ms = 0.0, age_max_ms = 0.0;  // node's window of 300
};

struct LoadReport {
  std::vector<LoadRow> rows;
  std::uint64_t detections_sent = 0, detections_handled = 0, tf_sent = 0;
  int sessions = 0;                  // resets done + the last one
  std::vector<int> samples_per_session;  // at the moment of each reset
  double tf_rate_achieved = 0.0;     // Hz
  double node_cpu_percent = 0.0;     // mean over the run
  double driver_cpu_percent = 0.0;
  double rss_first_minute_mb = 0.0;  // max RSS over the first 20% of the run
  double rss_last_minute_mb = 0.0;   // max RSS over the last 20%
  double rss_max_mb = 0.0;
  double rss_slope_mb_per_min = 0.0; // least-squares slope over the second half
  double age_median_ms = 0.0;        // median of the per-second medians
  double age_p99_worst_ms = 0.0;     // worst per-second p99
  double age_max_ms = 0.0;
  /// Detection age against the session's size: rows grouped by their sample
  /// count in bins of `bin_width` samples (the node's window of 300 detections
  /// spans about 3 samples, so a row belongs to its bin up to that blur).
  struct AgeBin {
    int first_sample = 0, last_sample = 0;
    int rows = 0;
    double median_ms = 0.0, p99_worst_ms = 0.0, max_ms = 0.0;
  };
  std::vector<AgeBin> age_by_samples;
};

/// Runs the load against the node (ros::init must have been called). Throws
/// std::runtime_error when the node cannot be found or does not subscribe.
LoadReport run_load(const LoadOptions& options);

std::string format_load_csv(const LoadReport& report);
/// A Markdown summary for BENCHMARKS.md.
std::string format_load_summary(const LoadReport& report, const LoadOptions& options);

}  // namespace handeye
