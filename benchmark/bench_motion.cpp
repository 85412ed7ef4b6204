// The view planner's cost for one step of the robot moving itself: the session's
// 150 ranked candidates (next_best_pose.h, after 6 samples on the simulated arm),
// then IK and every check (view_planner.h). One core.
//
//   handeye_bench_motion [--benchmark_repetitions=5 ...]
#include <fstream>

#include <benchmark/benchmark.h>

#include "handeye_covariance/estimation/joint_estimator.h"
#include "handeye_covariance/estimation/next_best_pose.h"
#include "handeye_covariance/simulation/arm_rig.h"
#include "handeye_covariance/simulation/simulation.h"

namespace {

using namespace handeye;

struct Step {
  ArmRig setup = ArmRig::load(HANDEYE_SOURCE_DIR "/urdf/sim_arm.urdf");
  std::unique_ptr<motion::CollisionModel> collision;
  Eigen::VectorXd start;
  SampleSet samples;
  Calibration calibration;
  std::vector<motion::ViewCandidate> candidates;
  SuggestOptions suggest;

  Step() {
    collision = std::make_unique<motion::CollisionModel>(setup.arm, motion::table_plane());
    Rng rng(7);
    MeasurementNoise noise;
    noise.robot.translation = 1e-8 * Eigen::Matrix3d::Identity();  // 0.1 mm
    noise.robot.rotation = 1e-8 * Eigen::Matrix3d::Identity();     // 0.1 mrad
    noise.camera.translation = Eigen::Vector3d(4e-8, 4e-8, 1e-6).asDiagonal();  // 0.2, 0.2, 1 mm
    noise.camera.rotation = Eigen::Vector3d(1e-6, 1e-6, 4e-8).asDiagonal();
    samples.rig = setup.rig;
    samples.noise = noise;
    for (int i = 0; i < 6; ++i) {
      const auto q = setup.random_start(rng, *collision, motion::PlannerOptions{});
      samples.samples.push_back(setup.sample_at(rng, *q, noise));
      start = *q;
    }
    calibration = solve_joint(samples);
    suggest.candidates = 150;
    suggest.views = setup.views;
    const auto poses = sample_candidates(samples, calibration, suggest);
    for (const ScoredPose& p : rank_candidates(samples, calibration, poses, suggest).ranked)
      candidates.push_back({p.T_base_effector, p.T_camera_pattern});
  }
};

Step& step() {
  static Step s;
  return s;
}

void BM_RankCandidates(benchmark::State& state) {
  Step& s = step();
  const auto poses = sample_candidates(s.samples, s.calibration, s.suggest);
  for (auto _ : state) benchmark::DoNotOptimize(rank_candidates(s.samples, s.calibration, poses, s.suggest));
  state.counters["candidates"] = static_cast<double>(poses.size());
}

// check_all = false: up to the first candidate that passes (what a move costs);
// true: a verdict for every one of the 150 (the goal: <= 200 ms).
void BM_PlanView(benchmark::State& state) {
  Step& s = step();
  motion::PlannerOptions options;
  options.check_all = state.range(0) != 0;
  motion::ViewPlan plan;
  for (auto _ : state) {
    plan = motion::plan_view(*s.collision, s.setup.rig, std::nullopt, s.start, s.candidates, options);
    benchmark::DoNotOptimize(plan);
  }
  int checked = 0;
  for (const auto& v : plan.verdicts) checked += v.checked;
  state.counters["candidates"] = static_cast<double>(s.candidates.size());
  state.counters["checked"] = checked;
  state.counters["path_samples"] = plan.path_samples;
  state.SetLabel(plan.summary());
}

}  // namespace

BENCHMARK(BM_RankCandidates)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PlanView)->Arg(0)->Arg(1)->ArgName("check_all")->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
