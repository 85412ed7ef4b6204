// libFuzzer target: detection messages -> samples, the path every live and
// replayed detection takes (observations.h, then the CalibrationSession the node
// and the bag replay share, and the estimator). The fuzz bytes fill a TagDetectionArray field by field: any
// ids, sizes, stamps, frames, poses and covariances, NaN and Inf included. The
// robot's TF is a fixed, valid chain. Anything may be refused; nothing may
// crash, leak, hit undefined behaviour or throw an unnamed exception, and every
// accepted sample must be a valid pose.
//
// Short run (./scripts/test):  fuzz_detection_messages -runs=10000 test/fuzz/corpus/messages
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstdint>

#include "handeye_covariance/session/calibration_session.h"
#include "handeye_covariance/core/validation.h"
#include "handeye_covariance/ros/observations.h"

namespace {

using namespace handeye;

tf2::BufferCore& robot_tf() {
  static tf2::BufferCore* buffer = [] {
    auto* b = new tf2::BufferCore(ros::Duration(100.0));
    for (int i = 0; i <= 100; ++i) {  // base_link -> tool0 from t = 1 s to 11 s: a new pose every 2 s
      const int pose = i / 20;
      geometry_msgs::TransformStamped t;
      t.header.stamp = ros::Time(1.0 + 0.1 * i);
      t.header.frame_id = "base_link";
      t.child_frame_id = "tool0";
      t.transform.translation.x = 0.5 + 0.05 * pose;
      t.transform.rotation.x = std::sin(0.2 * pose) * 0.6;
      t.transform.rotation.z = std::sin(0.2 * pose) * 0.8;
      t.transform.rotation.w = std::cos(0.2 * pose);
      b->setTransform(t, "fuzz");
    }
    return b;
  }();
  return *buffer;
}

double any_double(FuzzedDataProvider& in) {
  switch (in.ConsumeIntegralInRange<int>(0, 5)) {
    case 0: return std::nan("");
    case 1: return std::numeric_limits<double>::infinity();
    case 2: return in.ConsumeFloatingPoint<double>();  // anything
    default: return in.ConsumeFloatingPointInRange<double>(-2.0, 2.0);  // plausible
  }
}

std::string any_frame(FuzzedDataProvider& in) {
  switch (in.ConsumeIntegralInRange<int>(0, 3)) {
    case 0: return "";
    case 1: return "camera_optical_frame";
    case 2: return "tool0";
    default: return in.ConsumeRandomLengthString(16);
  }
}

ros::Time any_stamp(FuzzedDataProvider& in) {
  return ros::Time(in.ConsumeIntegralInRange<std::uint32_t>(0, 12), in.ConsumeIntegralInRange<std::uint32_t>(0, 999999999));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  SessionConfig config;
  config.tag_ids = {0};
  if (in.ConsumeBool()) config.tag_ids.clear();
  SessionSettings settings = session_settings(config);
  settings.session_file.clear();
  CalibrationSession session(settings);
  const int messages = in.ConsumeIntegralInRange<int>(1, 40);
  TagDetectionArray previous;
  for (int m = 0; m < messages && in.remaining_bytes() > 0; ++m) {
    if (m > 0 && in.ConsumeIntegralInRange<int>(0, 3) > 0) {
      // Mostly: the same detection 0.1 s later, as from a still robot, so the
      // sampler's stillness gate and acceptance are reached too.
      previous.header.stamp += ros::Duration(0.1);
      for (TagDetection& t : previous.detections) t.pose.header.stamp = ros::Time();
      std::optional<Refusal> refusal;
      if (const auto detection = select_detection(previous, config.tag_ids, refusal)) {
        const ObservationResult result = make_observation(robot_tf(), config.rig, *detection);
        if (result.observation) session.observe(*result.observation);
      }
      continue;
    }
    TagDetectionArray msg;
    msg.header.stamp = any_stamp(in);
    msg.header.frame_id = any_frame(in);
    const int detections = in.ConsumeIntegralInRange<int>(0, 3);
    for (int d = 0; d < detections; ++d) {
      TagDetection t;
      for (int k = in.ConsumeIntegralInRange<int>(0, 3); k > 0; --k) t.id.push_back(in.ConsumeIntegralInRange<int>(-1, 3));
      for (int k = in.ConsumeIntegralInRange<int>(0, 2); k > 0; --k) t.size.push_back(any_double(in));
      if (in.ConsumeBool()) t.pose.header.stamp = any_stamp(in);
      t.pose.header.frame_id = any_frame(in);
      auto& p = t.pose.pose.pose;
      p.position.x = any_double(in), p.position.y = any_double(in), p.position.z = any_double(in);
      p.orientation.x = any_double(in), p.orientation.y = any_double(in), p.orientation.z = any_double(in),
      p.orientation.w = any_double(in);
      const double norm = std::sqrt(p.orientation.x * p.orientation.x + p.orientation.y * p.orientation.y +
                                    p.orientation.z * p.orientation.z + p.orientation.w * p.orientation.w);
      if (in.ConsumeBool() && norm > 0.0) {  // often a unit quaternion, as real detectors send
        p.orientation.x /= norm, p.orientation.y /= norm, p.orientation.z /= norm, p.orientation.w /= norm;
      }
      if (in.ConsumeBool()) {
        for (double& c : t.pose.pose.covariance) c = any_double(in);
      }
      if (in.ConsumeBool()) {  // the corners behind the pose (method corners), of any shape
        const int points = in.ConsumeIntegralInRange<int>(0, 12);
        for (int k = 0; k < points; ++k) {
          geometry_msgs::Point o;
          o.x = any_double(in), o.y = any_double(in), o.z = any_double(in);
          t.object_points.push_back(o);
        }
        for (int k = in.ConsumeIntegralInRange<int>(0, 2 * points + 1); k > 0; --k) t.image_points.push_back(any_double(in));
        t.corner_block = in.ConsumeIntegralInRange<int>(-1, 20);
        for (int k = in.ConsumeIntegralInRange<int>(0, 40); k > 0; --k) t.corner_covariance.push_back(any_double(in));
        t.camera_info.width = in.ConsumeIntegralInRange<unsigned>(0, 2000);
        t.camera_info.height = in.ConsumeIntegralInRange<unsigned>(0, 2000);
        for (double& k : t.camera_info.K) k = any_double(in);
        if (in.ConsumeBool()) t.camera_info.K = {600, 0, 320, 0, 600, 240, 0, 0, 1};
        t.camera_info.distortion_model = in.ConsumeBool() ? "plumb_bob" : any_frame(in);
        for (int k = in.ConsumeIntegralInRange<int>(0, 6); k > 0; --k) t.camera_info.D.push_back(any_double(in));
      }
      msg.detections.push_back(t);
    }
    previous = msg;
    std::optional<Refusal> refusal;
    const std::optional<Detection> detection = select_detection(msg, config.tag_ids, refusal);
    if (!detection) continue;
    const ObservationResult result = make_observation(robot_tf(), config.rig, *detection);
    if (!result.observation) continue;
    session.observe(*result.observation);
  }
  static const bool report = std::getenv("FUZZ_REPORT") != nullptr;
  static long inputs = 0, with_samples = 0;
  ++inputs;
  const std::vector<PoseSample>& samples = session.samples();
  with_samples += samples.empty() ? 0 : 1;
  if (report && inputs % 20000 == 0) std::fprintf(stderr, "%ld inputs, %ld gave samples\n", inputs, with_samples);
  for (const PoseSample& sample : samples) {
    check_pose(sample.T_base_effector, "accepted sample");  // throws (and so aborts) if invalid
    check_pose(sample.T_camera_pattern, "accepted sample");
    if (sample.noise) check_covariance(sample.noise->camera, "accepted sample's covariance");
  }
  try {
    session.calibrate(session.snapshot());
  } catch (const HandEyeError&) {
  }
  return 0;
}
