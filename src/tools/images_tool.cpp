// handeye_images: `handeye images` runs it (it links OpenCV and libapriltag;
// `handeye` links neither). A folder of images and one robot pose per image, the
// camera and the target files, through the images library and the session.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <unistd.h>

#include "handeye_covariance/tools/cli_common.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/corners/corner_calibration.h"
#include "handeye_covariance/images/image_folder.h"
#include "handeye_covariance/io/summary.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/session/calibration_session.h"
#include "handeye_covariance/vision/target.h"

namespace handeye {
namespace cli {
namespace {

/// The images' detections as samples, each image's line printed (images and check).
images::ImageSession detect(const std::string& images_dir, const std::string& poses, const std::string& camera_path,
                            const std::string& target_path, Setup setup, std::ostream& out, std::ostream& err) {
  const CameraModel camera = images::read_camera(camera_path);
  const Target target = io::read_target(target_path);
  const std::vector<images::ImageWithPose> inputs = images::pair_images_with_poses(images_dir, poses);
  out << inputs.size() << " images in " << images_dir << ", target: " << target.describe() << "\n";
  if (is_half_turn_symmetric(target)) {
    out << "  note: this board looks the same turned by 180 degrees: each image's pose is one of two candidates, "
           "decided from the robot's motion (a board with one even and one odd number of inner corners avoids it)\n";
  }
  ProgressBar bar(err, "detecting", ::isatty(STDERR_FILENO) && &err == &std::cerr);
  const auto progress = [&](std::size_t i, std::size_t n, const images::ImageReport&) {
    bar(static_cast<double>(i + 1) / static_cast<double>(n));
  };
  Rig rig;
  rig.setup = setup;
  rig.frames = {"base", "effector", "camera", "pattern"};
  set_target(rig, target);  // where suggested views look, the view-following noise's shape, a symmetric board
  const images::ImageSession found = images::detect_images(inputs, camera, target, rig, progress);
  char line[256];
  for (const images::ImageReport& r : found.images) {
    if (r.used) {
      std::snprintf(line, sizeof line, "  %-28s %3d points, reprojection RMS %.3f px, sigma %.3f px, target at %.3f m\n",
                    r.image.c_str(), r.points, r.rms_px, r.sigma_px, r.distance);
      out << line;
    } else {
      out << "  " << r.image << "  skipped: " << r.why << "\n";
    }
  }
  return found;
}

int images_command(const Args& args, std::ostream& out, std::ostream& err) {
  std::string images_dir, poses, camera_path, target_path, setup_name, output, samples_out, robust = "auto";
  std::string method = "joint";
  bool refine_intrinsics = false;
  std::string target_error = "estimate";
  HonestyArgs honesty;
  po::options_description options("images: calibrate from a folder of images and one robot pose per image");
  options.add_options()("help,h", "show this help")(
      "images", po::value(&images_dir)->required(), "folder of .png/.jpg images (sorted by name)")(
      "poses", po::value(&poses)->required(),
      "folder of robot pose files (T_base_effector, m; matched by stem or by the number in it) or one CSV "
      "image,tx,ty,tz,qx,qy,qz,qw")(
      "camera", po::value(&camera_path)->required(), "ROS camera_info YAML, or OpenCV's YAML/XML (camera_matrix, "
                                                     "distortion_coefficients)")(
      "target", po::value(&target_path)->required(), ("target file (" + target_file_types() + ", or a tag layout)").c_str())(
      "setup", po::value(&setup_name)->required(), "eye_in_hand or eye_to_hand")(
      "robust", po::value(&robust), "auto (default), on or off, as for solve")(
      "method", po::value(&method), "joint (default): X and the pattern pose from each image's detected pose; corners: "
                                    "then refined by every corner's reprojection error (docs/how_it_works.md: when to use it)")(
      "refine-intrinsics", po::bool_switch(&refine_intrinsics),
      "with --method corners: also refine fx, fy, cx, cy, k1, k2, the camera file as their prior (the pose-level "
      "start then rejects no image: wrong intrinsics make the images disagree)")(
      "target-error-mm", po::value(&target_error),
      "with --method corners: the printed target's points off their nominal positions by this 1 sigma per axis "
      "(mm), the same in every image; 0: the target is exact; default `estimate`, from the corners")(
      "output,o", po::value(&output), "result file (YAML); default: <images folder>_result.yaml here")(
      "samples-out", po::value(&samples_out), "also write the samples (each detection with its covariance) for "
                                              "`handeye solve`");
  add_honesty_options(options, honesty);
  po::variables_map vm;
  if (!parse("images", "--images DIR --poses DIR_OR_CSV --camera FILE --target FILE --setup eye_in_hand|eye_to_hand",
             options, args, vm, out)) {
    return kOk;
  }
  const Setup setup = setup_from_string(setup_name, "--setup");
  if (method != "joint" && method != "corners") {
    throw HandEyeError(ErrorCode::MalformedFile, "unknown method `" + method + "`", "--method",
                       "use joint (from each image's pose) or corners (from every corner)");
  }
  if (refine_intrinsics && method != "corners") {
    throw HandEyeError(ErrorCode::MalformedFile, "--refine-intrinsics needs the corners", "--refine-intrinsics",
                       "add --method corners");
  }
  double target_point_sigma = -1.0;  // estimated
  if (target_error != "estimate") {
    char* end = nullptr;
    target_point_sigma = metres(std::strtod(target_error.c_str(), &end));
    if (end == target_error.c_str() || *end != '\0' || !(target_point_sigma >= 0.0) || !std::isfinite(target_point_sigma)) {
      throw HandEyeError(ErrorCode::MalformedFile, "`" + target_error + "` is not a length", "--target-error-mm",
                         "give the target points' 1 sigma in mm (0 for an exact target), or `estimate`");
    }
    if (method != "corners") {
      throw HandEyeError(ErrorCode::MalformedFile, "--target-error-mm needs the corners", "--target-error-mm",
                         "add --method corners");
    }
  }
  if (output.empty()) output = default_result_path(std::filesystem::path(images_dir).lexically_normal().string());
  const images::ImageSession found = detect(images_dir, poses, camera_path, target_path, setup, out, err);
  char line[256];
  const std::size_t used = found.samples.samples.size();
  out << used << " of " << found.images.size() << " images used, pooled pixel sigma " << number_text(found.pixel_sigma)
      << " px\n";
  if (!samples_out.empty()) {
    io::write_file_atomically(samples_out, io::format_samples(found.samples));
    out << "  samples written to    " << samples_out << "  (handeye solve --input " << samples_out << ")\n";
  }
  if (used < 3) {
    throw HandEyeError(ErrorCode::NoData, "only " + std::to_string(used) + " images give a target pose, need at least 3",
                       images_dir, "see the skipped images' reasons above; check --target against the printed target");
  }
  SessionSettings settings = session_settings(found.samples);
  settings.robust = robust_from_string(robust);
  honesty.apply(settings);
  if (method == "corners") {
    CornerOptions corner_options;
    corner_options.refine_intrinsics = refine_intrinsics;
    corner_options.target_point_sigma = target_point_sigma;
    settings.method = Method::Corners;
    settings.refine_corners = corner_refiner(corner_options);
  }
  // Wrong intrinsics make the images' poses disagree with each other: with
  // --refine-intrinsics the pose level only starts the corners and rejects nothing.
  if (refine_intrinsics) settings.reject_outliers = false;
  CalibrationSession session(settings);
  session.replace(found.samples.samples, "images in " + images_dir);
  const SessionSnapshot snapshot = session.snapshot();
  const Calibration calibration = session.calibrate_checked(snapshot);
  if (calibration.corner_fit) {
    for (const Calibration::CornerFit::Image& image : calibration.corner_fit->images) {
      std::snprintf(line, sizeof line, "  %-28s %3d corners, reprojection RMS %.3f px (corner fit)\n", image.name.c_str(),
                    image.corners, image.rms_px);
      out << line;
    }
    if (const auto& k = calibration.corner_fit->intrinsics) {
      std::snprintf(line, sizeof line,
                    "  intrinsics refined: fx %.2f +- %.2f, fy %.2f +- %.2f, cx %.2f +- %.2f, cy %.2f +- %.2f px, "
                    "k1 %.4f +- %.4f, k2 %.4f +- %.4f\n",
                    k->fx(0), k->fx(1), k->fy(0), k->fy(1), k->cx(0), k->cx(1), k->cy(0), k->cy(1), k->k1(0), k->k1(1),
                    k->k2(0), k->k2(1));
      out << line;
    }
  }
  const io::ResultContext context = io::context_of(snapshot.samples);
  io::write_file_atomically(output, io::format_result(calibration, context));
  out << io::human_summary(calibration, context);
  out << "  result written to     " << output << "\n";
  return kOk;
}

/// `handeye check --images ...`: the new views from images, then the same check as
/// `handeye check --input` (cli_common.h run_check).
int check_command(const Args& args, std::ostream& out, std::ostream& err) {
  std::string calibration, images_dir, poses, camera_path, target_path, output;
  double alpha = 0.01;
  po::options_description options("check: a saved calibration against new images");
  options.add_options()("help,h", "show this help")(
      "calibration,c", po::value(&calibration)->required(), "the calibration's result file")(
      "images", po::value(&images_dir)->required(), "folder of new images (sorted by name)")(
      "poses", po::value(&poses)->required(), "their robot poses, as `handeye images` takes them")(
      "camera", po::value(&camera_path)->required(), "the camera file")(
      "target", po::value(&target_path)->required(), "the target file")(
      "alpha", po::value(&alpha), "the false-alarm rate (default 0.01)")(
      "output,o", po::value(&output), "write the check (YAML)");
  po::variables_map vm;
  if (!parse("check", "--calibration FILE --images DIR --poses DIR_OR_CSV --camera FILE --target FILE [--output FILE]",
             options, args, vm, out)) {
    return kOk;
  }
  const io::CalibrationFile file = io::read_result(calibration);
  if (!file.context.setup) {
    throw HandEyeError(ErrorCode::MissingKey, "the calibration does not say its setup", calibration,
                       "a samples result has `setup: eye_in_hand|eye_to_hand`: save it again with `handeye solve`");
  }
  const images::ImageSession found = detect(images_dir, poses, camera_path, target_path, *file.context.setup, out, err);
  if (found.samples.samples.empty()) {
    throw HandEyeError(ErrorCode::NoData, "no new image gives a target pose", images_dir,
                       "see the skipped images' reasons above; check --target against the printed target");
  }
  return run_check(calibration, found.samples, output, alpha, out);
}

}  // namespace
}  // namespace cli
}  // namespace handeye

int main(int argc, char** argv) {
  using namespace handeye::cli;
  static const CommandTable table = {
      {"images", {"calibrate from a folder of images and one robot pose per image", images_command}},
      {"check", {"check a saved calibration against new images and their robot poses", check_command}}};
  return run_commands(table, argc, argv, std::cout, std::cerr);
}
