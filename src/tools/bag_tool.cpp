// handeye_bag: the commands of `handeye` that read or write rosbags. `handeye bag`
// and `handeye sim --output x.bag` run this program, so that `handeye` itself
// links no ROS library. The bag replay drives the node's CalibrationSession.
#include <unistd.h>

#include <filesystem>
#include <iostream>

#include "handeye_covariance/tools/cli_common.h"
#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/io/summary.h"
#include "handeye_covariance/corners/corner_calibration.h"
#include "handeye_covariance/ros/bag.h"

namespace handeye {
namespace cli {
namespace {

int bag_command(const Args& args, std::ostream& out, std::ostream& err) {
  std::string bag_path, config_path, output, samples_out, target, image_topic, camera_info_topic;
  HonestyArgs honesty;
  po::options_description options("bag: calibrate from a rosbag, without a roscore");
  options.add_options()("help,h", "show this help")(
      "bag,b", po::value(&bag_path)->required(), "the recorded bag (/tf, /tf_static and the detections, or images)")(
      "config,c", po::value(&config_path), "YAML with the node's settings (config/calibration_defaults.yaml keys)")(
      "target", po::value(&target), "a bag of images: the target file (config/targets/); overrides target_file")(
      "image-topic", po::value(&image_topic), "a bag of images: the image topic (raw or compressed); default: the "
                                              "bag's one image topic when it has no detections")(
      "camera-info-topic", po::value(&camera_info_topic), "a bag of images: their CameraInfo; default: camera_info "
                                                          "beside the image topic")(
      "output,o", po::value(&output), "result file; default: <bag stem>_result.yaml in the current directory")(
      "samples-out", po::value(&samples_out), "also write the samples taken (the samples file format)");
  add_honesty_options(options, honesty);
  po::variables_map vm;
  if (!parse("bag", "--bag FILE [--config YAML] [--target FILE] [--output FILE] [--samples-out FILE]", options, args, vm,
             out)) {
    return kOk;
  }
  if (output.empty()) output = default_result_path(bag_path);

  SessionConfig config;
  if (!config_path.empty()) read_session_config(config_path, config);
  if (!target.empty()) config.target_file = target;
  if (!image_topic.empty()) config.image_topic = image_topic;
  if (!camera_info_topic.empty()) config.camera_info_topic = camera_info_topic;
  SessionSettings settings = session_settings(config);
  // The config's honesty keys, unless the command line sets them.
  if (vm.count("split-check")) settings.honesty.splits = honesty.options.splits;
  if (vm.count("reference-sessions")) settings.honesty.replicates = honesty.options.replicates;
  if (vm.count("split-runs")) settings.honesty.run_length = honesty.options.run_length;
  if (honesty.no_inflation) settings.inflate_when_overconfident = false;
  const std::string shared_robot_error = vm.count("shared-robot-error") ? honesty.shared_robot_error : config.shared_robot_error;
  HonestyArgs{settings.honesty, !settings.inflate_when_overconfident, shared_robot_error}.apply(settings);  // checks the values
  settings.session_file.clear();  // the node's session file is the node's
  settings.refine_corners = corner_refiner();  // method corners
  CalibrationSession session(settings);
  ProgressBar progress(err, "reading the bag", ::isatty(STDERR_FILENO) != 0);
  const BagReplay replay = replay_bag(bag_path, config, session, [&](double f) { progress(f); });
  const SessionSnapshot snapshot = session.snapshot();
  const Calibration calibration = session.calibrate_checked(snapshot);  // before writing anything

  out << "Read " << bag_path << " (" << number_text(replay.duration, 4) << " s):";
  for (const auto& [topic, count] : replay.messages) out << " " << topic << " " << count << ",";
  if (replay.images > 0) {
    out << "\n  images on " << replay.image_topic << " (CameraInfo " << replay.camera_info_topic << "): " << replay.images
        << ", target found in " << replay.detections << ", pooled pixel sigma " << number_text(replay.pixel_sigma) << " px";
  }
  out << "\n  detections " << replay.detections << ", paired with a robot pose " << replay.observations
      << ", samples accepted " << snapshot.samples.samples.size() << "\n";
  for (const auto& [kind, count] : replay.refusals) {
    out << "  refused " << count << " x " << kind << ": " << replay.refusal_examples.at(kind) << "\n";
  }
  if (replay.stamps_went_back > 0) {
    out << "  header stamps went back " << replay.stamps_went_back
        << " time(s) in the bag (a looping recording, or a detector publishing out of order): replayed in stamp order\n";
  }
  if (replay.repeated_stamps > 0) {
    out << "  " << replay.repeated_stamps << " detection(s) repeat a stamp already seen (the same image twice): each used once\n";
  }
  const io::ResultContext context = io::context_of(snapshot.samples);
  io::write_file_atomically(output, io::format_result(calibration, context));
  if (!samples_out.empty()) io::write_file_atomically(samples_out, io::format_samples(snapshot.samples));
  out << io::human_summary(calibration, context);
  out << "  result written to     " << output << "\n";
  if (!samples_out.empty()) out << "  samples written to    " << samples_out << "\n";
  return kOk;
}

int sim_bag_command(const Args& args, std::ostream& out, std::ostream&) {
  SimArgs a;
  BagSimulationOptions bag;
  std::string target;
  po::options_description options("sim --output x.bag: a simulated calibration session with known truth, as a rosbag");
  add_sim_options(options, a);
  options.add_options()(
      "pause", po::value(&bag.pause), "s the robot holds each pose (default 2)")(
      "move", po::value(&bag.move), "s between poses (default 1)")(
      "depth-noise-mm", po::value(&bag.depth_noise_mm), "1 sigma of the pattern's depth (default 1.5)")(
      "tilt-noise-deg", po::value(&bag.tilt_noise_deg), "1 sigma of the pattern's tilt (default 0.15)")(
      "dropout", po::value(&bag.dropout), "share of frames without a detection (default 0.05)")(
      "wrong-detections", po::value(&bag.wrong_detections), "share of flipped poses (default 0.005)")(
      "latency", po::value(&bag.latency), "s from capture to message (default 0.05)")(
      "detection-type", po::value(&bag.detection_type), "tags (default), pose_with_covariance, pose, tf, or images "
                                                        "(rendered camera images, with --target)")(
      "target", po::value(&target), "images: the target to draw (config/targets/)")(
      "rate", po::value(&bag.detection_rate), "Hz of detections or images (default 20)")(
      "compressed", po::bool_switch(&bag.compressed), "images: as sensor_msgs/CompressedImage (PNG)");
  po::variables_map vm;
  if (!parse("sim", "--output FILE.bag [options]", options, args, vm, out)) return kOk;
  bag.setup = a.checked_setup();
  bag.poses = a.samples;
  bag.seed = a.seed;
  // In a bag the pattern's translation and rotation sigma are the lateral and roll ones.
  if (vm.count("pattern-translation-noise-mm")) bag.lateral_noise_mm = a.translation_mm;
  if (vm.count("pattern-rotation-noise-deg")) bag.roll_noise_deg = a.rotation_deg;
  bag.detection_covariance = !a.omit_noise;
  if (!target.empty()) bag.target = io::read_target(target);
  const SimulatedBag written = write_simulated_bag(a.output, bag);
  out << "wrote a " << written.duration << " s simulated " << a.setup_name << " bag to " << a.output << ": "
      << written.tf_messages << " /tf, " << written.detections << (bag.detection_type == "images" ? " images" : " detections")
      << " (" << written.wrong_detections << " wrong)\n";
  std::string truth = a.truth;
  if (truth.empty()) {
    truth = (std::filesystem::path(a.output).parent_path() / std::filesystem::path(a.output).stem()).string() + "_truth.yaml";
  }
  const Rig rig{bag.setup, written.frames};
  io::ResultContext context;  // the truth always goes beside the bag
  context.setup = rig.setup;
  context.parent = rig.camera_parent_frame();
  context.child = rig.frames.camera;
  io::write_file_atomically(truth, io::format_pose_file({written.X, Matrix6d::Zero()}, context));
  out << "wrote the true X to " << truth << "\n";
  return kOk;
}

}  // namespace
}  // namespace cli
}  // namespace handeye

int main(int argc, char** argv) {
  static const handeye::cli::CommandTable commands = {
      {"bag", {"calibrate from a rosbag (/tf, /tf_static, detections) without a roscore", handeye::cli::bag_command}},
      {"sim", {"write a simulated session with known truth as a rosbag (--output x.bag)", handeye::cli::sim_bag_command}},
  };
  return handeye::cli::run_commands(commands, argc, argv, std::cout, std::cerr);
}
