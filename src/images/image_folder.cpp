#include "handeye_covariance/images/image_folder.h"

#include <algorithm>
#include <cctype>
#include <map>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/core/validation.h"
#include "handeye_covariance/images/pooled_detector.h"
#include "handeye_covariance/io/yaml_io.h"

namespace handeye {
namespace images {
namespace {

namespace fs = std::filesystem;

std::string lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

/// The last run of digits in a file stem ("franka_image-3" -> "3"), without leading zeros.
std::optional<std::string> trailing_number(const std::string& stem) {
  std::size_t end = stem.find_last_of("0123456789");
  if (end == std::string::npos) return std::nullopt;
  std::size_t begin = end;
  while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1]))) --begin;
  std::string digits = stem.substr(begin, end - begin + 1);
  digits.erase(0, std::min(digits.find_first_not_of('0'), digits.size() - 1));
  return digits;
}

}  // namespace

CameraModel read_camera(const std::string& path) {
  if (!fs::exists(path)) throw HandEyeError(ErrorCode::IoError, "no such camera file", path, "check the path");
  const std::string text = io::read_file(path);
  const bool opencv = lower(fs::path(path).extension().string()) == ".xml" || text.rfind("%YAML", 0) == 0 ||
                      text.find("!!opencv-matrix") != std::string::npos;
  CameraModel camera = opencv ? parse_opencv_camera(text, path) : io::parse_camera_info(text, path);
  check_camera_model(camera, path);
  return camera;
}

std::vector<ImageWithPose> pair_images_with_poses(const fs::path& images, const fs::path& poses) {
  if (!fs::is_directory(images)) {
    throw HandEyeError(ErrorCode::IoError, "not a folder", images.string(), "give the folder that holds the images");
  }
  std::vector<ImageWithPose> out;
  for (const fs::directory_entry& entry : fs::directory_iterator(images)) {
    const std::string ext = lower(entry.path().extension().string());
    if (entry.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg")) out.push_back({entry.path(), {}, "", ""});
  }
  std::sort(out.begin(), out.end(), [](const ImageWithPose& a, const ImageWithPose& b) { return a.image < b.image; });
  if (out.empty()) {
    throw HandEyeError(ErrorCode::NoData, "no .png or .jpg image in the folder", images.string(),
                       "give the folder that holds the images");
  }
  if (!fs::exists(poses)) throw HandEyeError(ErrorCode::IoError, "no such file or folder", poses.string(), "check --poses");

  if (fs::is_regular_file(poses)) {  // one CSV for all: image,tx,ty,tz,qx,qy,qz,qw
    std::map<std::string, std::pair<Eigen::Isometry3d, std::string>> by_name;
    for (const io::PoseTableRow& row : io::parse_pose_table(io::read_file(poses.string()), poses.string())) {
      by_name[fs::path(row.image).filename().string()] = {row.T_base_effector, row.where};
    }
    for (ImageWithPose& item : out) {
      auto it = by_name.find(item.image.filename().string());
      if (it == by_name.end()) it = by_name.find(item.image.stem().string());
      if (it == by_name.end()) {
        item.why = "no line for it in " + poses.string();
        continue;
      }
      item.T_base_effector = it->second.first;
      item.pose_source = it->second.second;
    }
    return out;
  }

  std::vector<fs::path> pose_files;
  for (const fs::directory_entry& entry : fs::directory_iterator(poses)) {
    const std::string ext = lower(entry.path().extension().string());
    if (entry.is_regular_file() && (ext == ".yaml" || ext == ".yml" || ext == ".json" || ext == ".csv" || ext == ".txt")) {
      pose_files.push_back(entry.path());
    }
  }
  for (ImageWithPose& item : out) {
    std::vector<fs::path> same_stem, same_number;
    const auto number = trailing_number(item.image.stem().string());
    for (const fs::path& p : pose_files) {
      if (p.stem() == item.image.stem()) same_stem.push_back(p);
      else if (number && trailing_number(p.stem().string()) == number) same_number.push_back(p);
    }
    const std::vector<fs::path>& matches = same_stem.empty() ? same_number : same_stem;
    if (matches.size() > 1) {
      throw HandEyeError(ErrorCode::MalformedFile,
                         "two pose files match image " + item.image.filename().string() + ": " +
                             matches[0].filename().string() + " and " + matches[1].filename().string(),
                         poses.string(), "keep one pose file per image (the same stem, or the same number in it)");
    }
    if (matches.empty()) {
      item.why = "no pose file with its stem or its number in " + poses.string();
      continue;
    }
    item.T_base_effector = io::read_robot_pose(matches[0].string());
    item.pose_source = matches[0].string();
  }
  return out;
}

namespace {

ImageSession detect(const std::vector<ImageWithPose>& inputs, const std::function<cv::Mat(std::size_t)>& load,
                    const CameraModel& camera, const Target& target, const Rig& rig,
                    const std::function<void(std::size_t, std::size_t, const ImageReport&)>& progress) {
  PooledDetector detector(target);
  ImageSession session;
  session.samples.rig = rig;
  session.images.resize(inputs.size());
  std::vector<std::optional<std::size_t>> frame_of(inputs.size());  // the detector's frame of each input
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    ImageReport& report = session.images[i];
    report.image = inputs[i].image.filename().string();
    if (!inputs[i].T_base_effector) {
      report.why = inputs[i].why;
    } else {
      const cv::Mat image = load(i);
      if (image.empty()) {
        report.why = "cannot be read as an image";
      } else if (camera.width > 0 && (image.cols != camera.width || image.rows != camera.height)) {
        report.why = "is " + std::to_string(image.cols) + " x " + std::to_string(image.rows) + ", the camera file says " +
                     std::to_string(camera.width) + " x " + std::to_string(camera.height);
      } else {
        report.why = detector.add(image, camera).why;
        frame_of[i] = detector.size() - 1;
      }
    }
    if (progress) progress(i, inputs.size(), report);
  }
  session.pixel_sigma = detector.pixel_sigma();
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    if (!frame_of[i]) continue;
    const std::optional<PatternPose> pose = detector.pooled(*frame_of[i]);
    if (!pose) continue;
    ImageReport& report = session.images[i];
    report.used = true;
    report.points = pose->points;
    report.rms_px = pose->rms_px;
    report.sigma_px = session.pixel_sigma;
    report.distance = pose->T_camera_pattern.translation().norm();
    PoseSample sample;
    sample.T_base_effector = *inputs[i].T_base_effector;
    sample.T_camera_pattern = pose->T_camera_pattern;
    sample.noise = MeasurementNoise{PoseNoise{}, PoseNoise::from_pose_covariance(pose->covariance)};
    sample.corners = std::make_shared<const TargetCorners>(
        TargetCorners{camera, *detector.frame(*frame_of[i]).corners, report.image});
    session.samples.samples.push_back(sample);
  }
  return session;
}

}  // namespace

ImageSession detect_images(const std::vector<ImageWithPose>& inputs, const CameraModel& camera, const Target& target,
                           const Rig& rig, const std::function<void(std::size_t, std::size_t, const ImageReport&)>& progress) {
  const auto read = [&](std::size_t i) { return cv::imread(inputs[i].image.string(), cv::IMREAD_GRAYSCALE); };
  return detect(inputs, read, camera, target, rig, progress);
}

ImageSession detect_images(const std::vector<ImageWithPose>& inputs, const std::vector<cv::Mat>& images,
                           const CameraModel& camera, const Target& target, const Rig& rig) {
  if (images.size() != inputs.size()) {
    throw HandEyeError(ErrorCode::WrongLength,
                       std::to_string(images.size()) + " images for " + std::to_string(inputs.size()) + " inputs",
                       "detect_images", "give one image per input");
  }
  return detect(inputs, [&](std::size_t i) { return images[i]; }, camera, target, rig, {});
}

}  // namespace images
}  // namespace handeye
