// The load benchmark's driver node (benchmark/load.launch starts it with the
// calibration node): drives the node for ~duration seconds, then writes ~csv
// (one row per second) and ~summary (Markdown) and exits.
//   scripts/bench_load            # 10 minutes, TF 1 kHz, detections 30 Hz
#include <fstream>
#include <iostream>

#include "handeye_covariance/ros/params.h"
#include "load.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "load_driver");
  ros::NodeHandle pn("~");
  handeye::LoadOptions o;
  o.duration = handeye::param(pn, "duration", o.duration);
  o.tf_rate = handeye::param(pn, "tf_rate", o.tf_rate);
  o.detection_rate = handeye::param(pn, "detection_rate", o.detection_rate);
  o.poses = handeye::param(pn, "poses", o.poses);
  try {
    const handeye::LoadReport report = handeye::run_load(o);
    std::ofstream(handeye::param<std::string>(pn, "csv", "load.csv")) << handeye::format_load_csv(report);
    const std::string summary = handeye::format_load_summary(report, o);
    std::ofstream(handeye::param<std::string>(pn, "summary", "load.md")) << summary;
    std::cout << summary;
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}
