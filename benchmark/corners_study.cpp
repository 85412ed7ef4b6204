// Rendered sessions with known truth: `--method corners` against the pose-level
// estimator on the same images, for BENCHMARKS.md.
//
// Each session: 30 eye-in-hand views at 0.4-1.0 m of a target (a 2 x 2 AprilTag
// board, a 6 x 5 ChArUco board, a 9 x 6 chessboard; one 48 mm AprilTag on request),
// rendered by PatternRenderer
// with the simulated camera's distortion, detected as `handeye images` detects
// them (detect_images: rectified, the pixel sigma pooled), calibrated as it
// calibrates them (the session's pose-level estimate, then refine_with_corners).
// Printed per target kind: the RMS error of X by both, their ratio, the
// Cramer-Rao bound of the corner model (the information J^T J / sigma^2 of the
// detected corners at the truth, sigma the corner fit's estimate, averaged over
// the sessions), the 6-dof NEES of X by both, and with --focal-error the refined
// focal length's coverage and X's bias in sigma.
//
// With --corner-bias, each detected corner is also compared with its true
// projection, and the mean error is printed per target kind: in the image's x
// and y, along the board's x and y axes, outwards from the board's centre and
// from each marker's centre, and away from the principal point. A shift that
// every corner shares (a few thousandths of a pixel) biases X once the pixel
// noise is a few hundredths; this is how libapriltag's shift and ChArUco's were
// found (docs/how_it_works.md, "Where it falls short"). --distances lo,hi narrows the views.
//
// --supersample s (default 5) is the renderer's: each sensor pixel the average of
// s x s samples. At 3 (the tests' default, for speed) the renderer's own corner
// errors show: noise-free 2 x 2 AprilTag boards at 0.85-1.0 m, X's error 1.34x the
// corner model's bound in translation, 0.97x at 5 (6 sessions). --noise g sets the
// rendered pixel noise (gray levels, default 2; 0 shows the renderer's and the
// detector's own errors).
//
// With --why, the sessions whose robot noise the fit took as stated and those
// where it estimated it from the corners are summarised apart: NEES of X, the
// predicted covariance against the bound, the target term's factor and the
// robot sigma found (what makes the corners' covariance larger than the bound).
//
//   handeye_corners_study --sessions 300 [--kinds apriltag,charuco,chessboard,apriltag_single] [--focal-error 0.01]
//                         [--corner-bias] [--why] [--distances 0.4,1.0] [--supersample 5] [--noise 2]
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/corners/corner_calibration.h"
#include "handeye_covariance/images/image_folder.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/session/calibration_session.h"
#include "handeye_covariance/simulation/monte_carlo.h"
#include "handeye_covariance/simulation/pattern_renderer.h"
#include "handeye_covariance/vision/pattern_pose.h"

namespace handeye {
namespace {

Target target_of(const std::string& kind) {
  if (kind == "apriltag") return make_target(io::read_tag_layout(HANDEYE_SOURCE_DIR "/config/tag_board_2x2.yaml"));
  if (kind == "charuco") return make_target(CharucoTarget{6, 5, 0.035, 0.026, "DICT_5X5_100"});
  if (kind == "chessboard") return make_target(ChessboardTarget{9, 6, 0.030});
  // One 48 mm tag, as the real eye-to-hand session: a pose weakly determined by 4 corners.
  if (kind == "apriltag_single") return make_target(single_tag_layout(10, 0.048));
  throw HandEyeError(ErrorCode::MalformedFile, "unknown target kind " + kind, "--kinds", "use apriltag, charuco, chessboard, apriltag_single");
}

/// Sums over detected corners of their error against the true projection (px),
/// and of its components (see the file's comment).
struct CornerBias {
  int corners = 0, marker_corners = 0;
  Eigen::Vector2d image = Eigen::Vector2d::Zero(), board_axes = Eigen::Vector2d::Zero();
  double from_board_centre = 0.0, from_marker_centre = 0.0, from_principal_point = 0.0, squares = 0.0;

  void add(const CornerBias& o) {
    corners += o.corners;
    marker_corners += o.marker_corners;
    image += o.image;
    board_axes += o.board_axes;
    from_board_centre += o.from_board_centre;
    from_marker_centre += o.from_marker_centre;
    from_principal_point += o.from_principal_point;
    squares += o.squares;
  }
};

/// One image's corners (raw pixels) against their projection at the true pose.
CornerBias corner_bias(const CameraModel& camera, const Eigen::Isometry3d& T_camera_face, const PointCorrespondences& seen) {
  CornerBias b;
  Eigen::Vector2d board_centre = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& u : seen.image) board_centre += u / static_cast<double>(seen.image.size());
  const Eigen::Vector2d principal_point(camera.K(0, 2), camera.K(1, 2));
  const auto direction = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& step) {
    return (project(camera, T_camera_face * (p + step)) - project(camera, T_camera_face * p)).normalized();
  };
  for (std::size_t k = 0; k < seen.image.size(); ++k) {
    const Eigen::Vector3d& p = seen.object[k];
    const Eigen::Vector2d& u = seen.image[k];
    const Eigen::Vector2d e = u - project(camera, T_camera_face * p);
    ++b.corners;
    b.image += e;
    b.board_axes += Eigen::Vector2d(e.dot(direction(p, Eigen::Vector3d(1e-4, 0, 0))), e.dot(direction(p, Eigen::Vector3d(0, 1e-4, 0))));
    b.from_board_centre += e.dot((u - board_centre).normalized());
    b.from_principal_point += e.dot((u - principal_point).normalized());
    b.squares += e.squaredNorm();
    if (seen.blocks == 8) {  // a marker's four corners, one block under the edge-fit model
      Eigen::Vector2d marker_centre = Eigen::Vector2d::Zero();
      for (std::size_t j = k / 4 * 4; j < k / 4 * 4 + 4; ++j) marker_centre += 0.25 * seen.image[j];
      b.from_marker_centre += e.dot((u - marker_centre).normalized());
      ++b.marker_corners;
    }
  }
  return b;
}

struct SessionResult {
  bool ok = false;
  std::string why;
  int images = 0;
  Vector6d poses_error, corners_error;
  Matrix6d poses_covariance, corners_covariance, bound;
  double focal = 0.0, focal_sigma = 0.0, true_focal = 0.0;
  bool per_image = false;  // the fit weighed each image by its own sigma
  bool robot_estimated = false;        // the robot noise came from the corners
  Eigen::Vector2d robot_sigma = Eigen::Vector2d::Zero();
  Eigen::Vector2d target_inflation = Eigen::Vector2d::Ones();
  CornerBias bias;
};

/// What every session of a study shares.
struct StudyOptions {
  int images = 30;
  double focal_error = 0.0;              // the given focal length's relative error
  Eigen::Vector2d distances{0.4, 1.0};   // m, camera to the pattern
  RenderOptions render;
};

SessionResult run_session(const std::string& kind, int index, const StudyOptions& study) {
  SessionResult out;
  const int n = study.images;
  const double focal_error = study.focal_error;
  const Target target = target_of(kind);
  const CameraModel camera = simulated_camera();
  CameraModel given = camera;
  given.K(0, 0) *= 1.0 + focal_error;
  given.K(1, 1) *= 1.0 + focal_error;
  out.true_focal = camera.K(0, 0);
  Rng rng(static_cast<std::uint64_t>(18000 + index));
  ViewpointOptions views;
  views.min_distance = study.distances[0];
  views.max_distance = study.distances[1];
  SimulatedSession truth = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), n, MeasurementNoise{}, views);
  // The views look at the pattern frame's origin; make them look at the printed face.
  const Eigen::Isometry3d face_inverse = target_face(target).inverse();
  truth.T_world_pattern = truth.T_world_pattern * face_inverse;
  const PatternRenderer renderer(target, camera, study.render);
  std::vector<images::ImageWithPose> inputs;
  std::vector<cv::Mat> rendered;
  for (std::size_t i = 0; i < truth.samples.samples.size(); ++i) {
    const PoseSample& s = truth.samples.samples[i];
    inputs.push_back({"view_" + std::to_string(i) + ".png", s.T_base_effector, "simulated", ""});
    rendered.push_back(renderer.render(s.T_camera_pattern * face_inverse, rng));
  }
  Rig rig;
  rig.setup = Setup::EyeInHand;
  rig.frames = {"base", "effector", "camera", "pattern"};
  rig.T_pattern_face = target_face(target);
  try {
    const images::ImageSession found = images::detect_images(inputs, rendered, given, target, rig);
    out.images = static_cast<int>(found.samples.samples.size());
    if (out.images < 6) {
      out.why = "only " + std::to_string(out.images) + " images detected";
      return out;
    }
    for (const PoseSample& sample : found.samples.samples) {  // named view_<i>.png
      const std::size_t i = std::stoul(sample.corners->source.substr(5));
      out.bias.add(corner_bias(camera, truth.samples.samples[i].T_camera_pattern * face_inverse, sample.corners->points));
    }
    SessionSettings settings = session_settings(found.samples);
    // As `handeye images --refine-intrinsics`: wrong intrinsics make the images' poses
    // disagree, so the pose level only starts the corners and rejects nothing.
    settings.reject_outliers = focal_error == 0.0;
    CalibrationSession session(settings);
    session.replace(found.samples.samples, "rendered");
    const SessionSnapshot snapshot = session.snapshot();
    const Calibration poses = session.calibrate(snapshot);
    CornerOptions options;
    options.refine_intrinsics = focal_error != 0.0;
    const CornerMethodResult corners =
        refine_with_corners(snapshot.samples, poses, options);
    out.poses_error = pose_error(poses.T_parent_camera, truth.X);
    out.corners_error = pose_error(corners.calibration.T_parent_camera, truth.X);
    out.poses_covariance = poses.pose_covariance;
    out.corners_covariance = corners.calibration.pose_covariance;
    out.per_image = corners.fit.per_image_sigma;
    out.robot_estimated = corners.fit.robot_noise_estimated;
    out.robot_sigma = corners.fit.robot_sigma;
    out.target_inflation = corners.fit.target_inflation;
    // The corner model's bound: its information at the truth, with the detected
    // corners' structure and noise model of the images the fit kept, each at the
    // sigma the fit weighed it with.
    std::map<std::string, double> sigma_of;
    for (const ImageReprojection& image : corners.fit.images) sigma_of[image.name] = image.sigma_px;
    std::vector<CornerView> detected;
    std::vector<double> row_weight;
    for (const PoseSample& sample : found.samples.samples) {
      const auto kept = sigma_of.find(sample.corners->source);
      if (kept == sigma_of.end()) continue;
      detected.push_back({sample.T_base_effector, sample.corners->points, sample.corners->source});
      row_weight.insert(row_weight.end(), 2 * sample.corners->points.image.size(), 1.0 / kept->second);
    }
    const CornerResiduals at_truth = corner_residuals(rig, camera, detected, truth.X, truth.T_world_pattern);
    const Eigen::MatrixXd weighted =
        Eigen::Map<const Eigen::VectorXd>(row_weight.data(), static_cast<Eigen::Index>(row_weight.size())).asDiagonal() *
        at_truth.jacobian;
    const Eigen::Matrix<double, 12, 12> information = weighted.transpose() * weighted;
    out.bound = information.inverse().topLeftCorner<6, 6>();
    if (corners.fit.intrinsics) {
      out.focal = (*corners.fit.intrinsics)[0];
      out.focal_sigma = std::sqrt(corners.fit.intrinsics_covariance(0, 0));
    }
    out.ok = true;
  } catch (const HandEyeError& e) {
    out.why = e.what();
  }
  return out;
}

struct Summary {
  int sessions = 0, failed = 0;
  double images = 0.0;
  Eigen::Vector2d poses_ms = Eigen::Vector2d::Zero(), corners_ms = Eigen::Vector2d::Zero(), bound_ms = Eigen::Vector2d::Zero();
  double nees_poses = 0.0, nees_corners = 0.0, focal_within_2_sigma = 0.0, per_image = 0.0;
  Vector6d bias_poses = Vector6d::Zero(), bias_corners = Vector6d::Zero();
  CornerBias corner_bias;
  std::string first_failure;
  /// For --why, per group of sessions (0: robot noise as stated, 1: estimated from
  /// the corners): sessions, NEES of X with corners, the predicted covariance's
  /// trace over the bound's (translation, rotation), the target term's factor on
  /// X's sigma, the robot sigma found (m, rad).
  struct Group {
    int sessions = 0;
    double nees = 0.0;
    Eigen::Vector2d over_bound = Eigen::Vector2d::Zero(), target = Eigen::Vector2d::Zero(), robot = Eigen::Vector2d::Zero();
  };
  std::array<Group, 2> groups;
};

// Mean squared translation (m^2) and rotation (rad^2) error, summed over the axes.
Eigen::Vector2d squares(const Vector6d& e) { return {e.head<3>().squaredNorm(), e.tail<3>().squaredNorm()}; }
Eigen::Vector2d traces(const Matrix6d& C) { return {C.topLeftCorner<3, 3>().trace(), C.bottomRightCorner<3, 3>().trace()}; }

Summary study(const std::string& kind, int M, const StudyOptions& options, int threads) {
  std::vector<SessionResult> results(static_cast<std::size_t>(M));
  std::atomic<int> next{0};
  std::vector<std::thread> workers;
  for (int t = 0; t < threads; ++t) {
    workers.emplace_back([&] {
      for (int k = next++; k < M; k = next++) results[static_cast<std::size_t>(k)] = run_session(kind, k, options);
    });
  }
  for (std::thread& w : workers) w.join();
  Summary s;
  for (const SessionResult& r : results) {
    if (!r.ok) {
      ++s.failed;
      if (s.first_failure.empty()) s.first_failure = r.why;
      continue;
    }
    ++s.sessions;
    s.images += r.images;
    s.corner_bias.add(r.bias);
    s.poses_ms += squares(r.poses_error);
    s.corners_ms += squares(r.corners_error);
    s.bound_ms += traces(r.bound);
    s.nees_poses += r.poses_error.dot(r.poses_covariance.ldlt().solve(r.poses_error));
    const double nees_corners = r.corners_error.dot(r.corners_covariance.ldlt().solve(r.corners_error));
    s.nees_corners += nees_corners;
    s.bias_poses += r.poses_error.cwiseQuotient(r.poses_covariance.diagonal().cwiseSqrt());
    s.bias_corners += r.corners_error.cwiseQuotient(r.corners_covariance.diagonal().cwiseSqrt());
    s.per_image += r.per_image ? 1.0 : 0.0;
    Summary::Group& g = s.groups[r.robot_estimated ? 1 : 0];
    ++g.sessions;
    g.nees += nees_corners;
    g.over_bound += traces(r.corners_covariance).cwiseQuotient(traces(r.bound));
    g.target += r.target_inflation;
    g.robot += r.robot_sigma;
    if (r.focal_sigma > 0.0) s.focal_within_2_sigma += std::abs(r.focal - r.true_focal) < 2.0 * r.focal_sigma;
  }
  const double m = std::max(1, s.sessions);
  s.images /= m;
  s.poses_ms /= m;
  s.corners_ms /= m;
  s.bound_ms /= m;
  s.nees_poses /= m;
  s.nees_corners /= m;
  s.bias_poses /= m;
  s.bias_corners /= m;
  s.focal_within_2_sigma /= m;
  s.per_image /= m;
  for (Summary::Group& g : s.groups) {
    const double k = std::max(1, g.sessions);
    g.nees /= k;
    g.over_bound /= k;
    g.target /= k;
    g.robot /= k;
  }
  return s;
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  using namespace handeye;
  int M = 300, threads = 2;
  StudyOptions options;
  options.render.supersample = 5;
  std::string kinds = "apriltag,charuco,chessboard";
  bool print_corner_bias = false, print_why = false;
  const auto usage = [&] {
    std::fprintf(stderr, "usage: %s [--sessions M] [--images n] [--kinds apriltag,charuco,chessboard] "
                         "[--focal-error e] [--threads t] [--corner-bias] [--why] [--distances lo,hi (m)] [--supersample s] [--noise gray levels]\n", argv[0]);
    return 2;
  };
  for (int i = 1; i < argc; ++i) {
    const std::string key = argv[i];
    if (key == "--corner-bias" || key == "--why") {
      (key == "--why" ? print_why : print_corner_bias) = true;
      continue;
    }
    if (i + 1 >= argc) return usage();
    const char* value = argv[++i];
    if (key == "--sessions") M = std::atoi(value);
    else if (key == "--images") options.images = std::atoi(value);
    else if (key == "--supersample") options.render.supersample = std::max(1, std::atoi(value));
    else if (key == "--noise") options.render.noise_sigma = std::max(0.0, std::atof(value));
    else if (key == "--threads") threads = std::max(1, std::atoi(value));
    else if (key == "--focal-error") options.focal_error = std::atof(value);
    else if (key == "--kinds") kinds = value;
    else if (key == "--distances") {
      Eigen::Vector2d& d = options.distances;
      if (std::sscanf(value, "%lf,%lf", &d[0], &d[1]) != 2 || !(d[0] > 0.0) || !(d[1] >= d[0])) {
        return usage();
      }
    } else {
      return usage();
    }
  }
  const double deg = kDegreesPerRadian;
  if (options.focal_error == 0.0) {
    std::printf("| target | sessions (images used) | X RMS poses [mm / deg] | X RMS corners [mm / deg] | corners / poses | "
                "corner-model bound [mm / deg] | corners / bound | poses / bound | NEES X poses | NEES X corners | per-image sigma |\n");
    std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  } else {
    std::printf("| target | sessions | focal within 2 sigma | X bias / sigma, corners (worst axis) | X bias / sigma, poses "
                "(worst axis) | NEES X corners | NEES X poses |\n");
    std::printf("|---|---:|---:|---:|---:|---:|---:|\n");
  }
  std::stringstream list(kinds);
  std::string kind;
  while (std::getline(list, kind, ',')) {
    const Summary s = study(kind, M, options, threads);
    const Eigen::Vector2d poses = s.poses_ms.cwiseSqrt(), corners = s.corners_ms.cwiseSqrt(), bound = s.bound_ms.cwiseSqrt();
    if (options.focal_error == 0.0) {
      std::printf("| %s | %d (%.1f) | %.3f / %.4f | %.3f / %.4f | %.2fx / %.2fx | %.3f / %.4f | %.2fx / %.2fx | %.2fx / %.2fx | %.2f | "
                  "%.2f | %.0f%% |\n",
                  kind.c_str(), s.sessions, s.images, millimetres(poses[0]), poses[1] * deg, millimetres(corners[0]), corners[1] * deg,
                  corners[0] / poses[0], corners[1] / poses[1], millimetres(bound[0]), bound[1] * deg, corners[0] / bound[0],
                  corners[1] / bound[1], poses[0] / bound[0], poses[1] / bound[1], s.nees_poses, s.nees_corners, 100.0 * s.per_image);
    } else {
      std::printf("| %s | %d | %.0f%% | %.2f | %.2f | %.2f | %.2f |\n", kind.c_str(), s.sessions,
                  100.0 * s.focal_within_2_sigma, s.bias_corners.cwiseAbs().maxCoeff(), s.bias_poses.cwiseAbs().maxCoeff(),
                  s.nees_corners, s.nees_poses);
    }
    if (print_why) {
      for (int robot = 0; robot < 2; ++robot) {
        const Summary::Group& g = s.groups[static_cast<std::size_t>(robot)];
        if (g.sessions == 0) continue;
        std::printf("\n%s, robot noise %s: %d sessions, NEES of X %.2f, covariance / bound (trace) %.2f / %.2f, target "
                    "term's factor on sigma %.3f / %.3f, robot sigma %.4f mm / %.5f deg\n",
                    kind.c_str(), robot ? "estimated from the corners" : "as stated", g.sessions, g.nees, g.over_bound[0],
                    g.over_bound[1], g.target[0], g.target[1], millimetres(g.robot[0]), g.robot[1] * deg);
      }
      std::printf("\n");
    }
    if (print_corner_bias && s.corner_bias.corners > 0) {
      const CornerBias& b = s.corner_bias;
      const double c = b.corners;
      std::printf("\n%s corner bias over %d corners [px]: image (%.4f, %.4f), board axes (%.4f, %.4f), outwards from the "
                  "board's centre %.4f, from each marker's %.4f, from the principal point %.4f; RMS %.4f\n\n",
                  kind.c_str(), b.corners, b.image.x() / c, b.image.y() / c, b.board_axes.x() / c, b.board_axes.y() / c,
                  b.from_board_centre / c, b.marker_corners > 0 ? b.from_marker_centre / b.marker_corners : 0.0,
                  b.from_principal_point / c, std::sqrt(b.squares / c));
    }
    if (s.failed > 0) std::printf("\n%d %s session(s) failed, the first: %s\n\n", s.failed, kind.c_str(), s.first_failure.c_str());
    std::fflush(stdout);
  }
  return 0;
}
