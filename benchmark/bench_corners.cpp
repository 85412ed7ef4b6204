// The corner-level calibration's speed (corners/corner_calibration.h), side by side
// in one process: 30 images x 50 corners (a 10 x 5 grid, 0.3 px noise, robot poses
// off by 0.3 mm / 0.03 deg per axis), X + Y + covariance, with what is free:
//   /0 the robot exact (and so in its data: taken as exact, robot errors make the
//   images disagree and the per-image sigma's rounds begin), /1 the robot poses free
//   (noise given), /2 those and the intrinsics, /3 the robot poses free with their
//   noise estimated, /4 that and the intrinsics. Regenerate BENCHMARKS.md with
//   ./scripts/bench.
#include <benchmark/benchmark.h>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/corners/corner_calibration.h"
#include "handeye_covariance/simulation/pattern_renderer.h"
#include "handeye_covariance/simulation/simulation.h"

namespace handeye {
namespace {

struct Session {
  Rig rig;
  Eigen::Isometry3d X, Y;
  std::vector<CornerView> views;        // the robot poses as measured
  std::vector<CornerView> exact_views;  // the same corners at the true robot poses
  Matrix6d robot = Matrix6d::Zero();
};

const Session& session() {
  static const Session s = [] {
    Rng rng(2026);
    const SimulatedSession truth = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 30, MeasurementNoise{});
    const CameraModel camera = simulated_camera();
    Session out;
    out.rig.setup = Setup::EyeInHand;
    out.X = truth.X;
    out.Y = truth.T_world_pattern;
    out.robot.diagonal() << Eigen::Vector3d::Constant(0.09e-6), Eigen::Vector3d::Constant(std::pow(radians(0.03), 2));
    std::normal_distribution<double> pixel(0.0, 0.3);
    for (const PoseSample& sample : truth.samples.samples) {
      CornerView v;
      v.T_base_effector = perturb(rng, sample.T_base_effector, PoseNoise::from_pose_covariance(out.robot));
      for (int r = 0; r < 5; ++r) {
        for (int c = 0; c < 10; ++c) {
          const Eigen::Vector3d o(0.03 * (c - 4.5), 0.03 * (r - 2.0), 0.0);
          v.points.object.push_back(o);
          v.points.image.push_back(project(camera, sample.T_camera_pattern * o) + Eigen::Vector2d(pixel(rng), pixel(rng)));
        }
      }
      out.views.push_back(v);
      v.T_base_effector = sample.T_base_effector;
      out.exact_views.push_back(v);
    }
    return out;
  }();
  return s;
}

void BM_CornerCalibration(benchmark::State& state) {
  const Session& s = session();
  const CameraModel camera = simulated_camera();
  CornerOptions options;
  const int what = static_cast<int>(state.range(0));
  if (what == 1 || what == 2) options.robot_covariance = s.robot;
  options.estimate_robot_noise = what >= 3;
  options.refine_intrinsics = what == 2 || what == 4;
  // The pose-level start: 1 mm / 0.1 deg off the truth.
  Eigen::Isometry3d X0 = s.X, Y0 = s.Y;
  X0.translation() += Eigen::Vector3d(1e-3, -1e-3, 0.5e-3);
  Y0.linear() = Eigen::AngleAxisd(1.7e-3, Eigen::Vector3d::UnitY()) * Y0.linear();
  int rounds = 0;
  bool per_image = false;
  for (auto _ : state) {
    const CornerCalibration c = calibrate_corners(s.rig, camera, what == 0 ? s.exact_views : s.views, X0, Y0, options);
    rounds = c.noise_rounds;
    per_image = c.per_image_sigma;
    benchmark::DoNotOptimize(c.covariance.data());
  }
  state.counters["noise_rounds"] = rounds;
  state.counters["per_image_sigma"] = per_image ? 1 : 0;
}
BENCHMARK(BM_CornerCalibration)->DenseRange(0, 4)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace handeye

BENCHMARK_MAIN();
