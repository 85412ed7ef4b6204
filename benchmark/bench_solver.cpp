// Solve-plus-covariance time, all sizes in one process so the ratios are fair.
// Regenerate BENCHMARKS.md figures with:  ./scripts/bench
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/estimation/joint_estimator.h"
#include "handeye_covariance/estimation/next_best_pose.h"
#include "handeye_covariance/estimation/outliers.h"
#include "handeye_covariance/estimation/shared_robot_error.h"
#include "handeye_covariance/estimation/solve.h"
#include "handeye_covariance/session/calibration_session.h"
#include "handeye_covariance/simulation/simulation.h"

namespace {

using namespace handeye;

/// Minor page faults so far: a solve that faults its buffers in anew each time
/// (glibc returning freed memory to the kernel) pays for it here, about 10 us a
/// fault on this sandbox. Reported per iteration, beside the time.
long minor_faults() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}
void count_faults(benchmark::State& state, long before) {
  state.counters["faults"] = benchmark::Counter(static_cast<double>(minor_faults() - before), benchmark::Counter::kAvgIterations);
}

// Independent motion pairs, the paper's protocol at lambda = 1e-4.
void BM_SolveMotions(benchmark::State& state) {
  Rng rng(1);
  const MotionSet set = simulate_motions(rng, random_pose(rng, 0.5), static_cast<int>(state.range(0)), paper_noise(1e-4));
  benchmark::DoNotOptimize(solve(set).pose_covariance);  // warm-up: first-touch page faults are not the solver
  for (auto _ : state) {
    Calibration c = solve(set);
    benchmark::DoNotOptimize(c.pose_covariance);
  }
  state.SetComplexityN(state.range(0));
}
BENCHMARK(BM_SolveMotions)->Arg(30)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond)->Complexity(benchmark::oN);

// A pose stream of k+1 samples (each paired with the next 30: about 30 k motions),
// with the correlated covariance.
void BM_SolveSamples(benchmark::State& state) {
  Rng rng(2);
  const SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand),
                                              static_cast<int>(state.range(0)) + 1, paper_noise(1e-5));
  benchmark::DoNotOptimize(solve(s.samples).pose_covariance);  // warm-up, as above
  for (auto _ : state) {
    Calibration c = solve(s.samples);
    benchmark::DoNotOptimize(c.pose_covariance);
  }
  state.SetComplexityN(state.range(0));
}
BENCHMARK(BM_SolveSamples)->Arg(30)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond)->Complexity(benchmark::oN);

// No noise block: the noise is estimated from the residuals (several solves).
void BM_SolveSamplesEstimatedNoise(benchmark::State& state) {
  Rng rng(3);
  SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand),
                                        static_cast<int>(state.range(0)) + 1, paper_noise(1e-5));
  s.samples.noise.reset();
  benchmark::DoNotOptimize(solve(s.samples).pose_covariance);  // warm-up, as above
  for (auto _ : state) {
    Calibration c = solve(s.samples);
    benchmark::DoNotOptimize(c.pose_covariance);
  }
}
BENCHMARK(BM_SolveSamplesEstimatedNoise)->Arg(30)->Unit(benchmark::kMicrosecond);

// The pose-level estimator on the same pose streams: X, Y and their 12x12 covariance.
void BM_SolveJoint(benchmark::State& state) {
  Rng rng(2);
  const SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand),
                                              static_cast<int>(state.range(0)) + 1, paper_noise(1e-5));
  benchmark::DoNotOptimize(solve_joint(s.samples).pose_covariance);  // warm-up, as above
  const long faults = minor_faults();
  for (auto _ : state) {
    Calibration c = solve_joint(s.samples);
    benchmark::DoNotOptimize(c.pose_covariance);
  }
  count_faults(state, faults);
  state.SetComplexityN(state.range(0));
}
BENCHMARK(BM_SolveJoint)->Arg(30)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond)->Complexity(benchmark::oN);

// The same with no noise block: a 6x6 camera noise estimated, iterated with the solve.
void BM_SolveJointEstimatedNoise(benchmark::State& state) {
  Rng rng(3);
  SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand),
                                        static_cast<int>(state.range(0)) + 1, paper_noise(1e-5));
  s.samples.noise.reset();
  benchmark::DoNotOptimize(solve_joint(s.samples).pose_covariance);
  const long faults = minor_faults();
  for (auto _ : state) {
    Calibration c = solve_joint(s.samples);
    benchmark::DoNotOptimize(c.pose_covariance);
  }
  count_faults(state, faults);
}
BENCHMARK(BM_SolveJointEstimatedNoise)->Arg(30)->Unit(benchmark::kMicrosecond);

// One session's estimated-noise cost depends on how many rounds its fit takes
// (one for the session above; two for about a fifth of sessions): the ratio to
// the given noise is taken over 32 seeded 31-pose sessions, all solved per
// iteration (range 0: noise given; 1: no noise block).
constexpr int kSessions = 32;
void BM_SolveJointSessions(benchmark::State& state) {
  std::vector<SampleSet> sessions;
  for (int seed = 0; seed < kSessions; ++seed) {
    Rng rng(100 + seed);
    SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 31, paper_noise(1e-5));
    if (state.range(0) == 1) s.samples.noise.reset();
    sessions.push_back(s.samples);
  }
  for (const SampleSet& s : sessions) benchmark::DoNotOptimize(solve_joint(s).pose_covariance);
  const long faults = minor_faults();
  for (auto _ : state) {
    for (const SampleSet& s : sessions) {
      Calibration c = solve_joint(s);
      benchmark::DoNotOptimize(c.pose_covariance);
    }
  }
  count_faults(state, faults);
  state.counters["sessions"] = kSessions;
}
BENCHMARK(BM_SolveJointSessions)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// The calibrated honesty check (split_check.h) of a session of n samples as the
// tools run it: 200 random halves against 100 simulated honest sessions of 40 halves
// each (about 4 400 half-session solves), outlier rejection on. Range 2: 0, with the
// second look of the default (halves of runs, from 16 samples: 200 more against the
// same sessions split by 20 of them), 1: random halves alone. Range 3: 1, the halves
// under the session's noise (the default), 0: each half fitting its own (until stop
// 49). Range 1: 0, no noise given (the camera's and robot's estimated); 1, each detection with its own
// covariance stated 50x too small in sigma, as the real sessions' detectors state it
// (the missing part estimated: the costlier path; halves of 5 fail its start there,
// robot and camera angles beyond the understated noise, and the check is not run).
void BM_HonestyCheck(benchmark::State& state) {
  Rng rng(5);
  SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand),
                                        static_cast<int>(state.range(0)), paper_noise(1e-5));
  if (state.range(1) == 1) {
    MeasurementNoise understated = *s.samples.noise;
    understated.camera.rotation /= 2500.0, understated.camera.translation /= 2500.0;
    understated.robot = PoseNoise{};
    for (PoseSample& sample : s.samples.samples) sample.noise = understated;
  }
  s.samples.noise.reset();
  SessionSettings settings = session_settings(s.samples);
  settings.honesty.run_length = static_cast<int>(state.range(2));  // 0: both looks (the default); 1: random halves alone
  settings.honesty.hold_noise = state.range(3) == 1;  // 1: the halves under the session's noise (the default); 0: refitted
  settings.shared_robot_error = SharedErrorUse::Off;  // the check alone (BM_SharedRobotError times the model's fit)
  CalibrationSession session(settings);
  session.replace(s.samples.samples, "benchmark");
  std::string verdict;
  for (auto _ : state) {
    const Calibration c = session.calibrate_checked(session.snapshot());
    verdict = std::string(to_string(c.honesty->verdict)) + " " + (!c.honesty->ran() ? c.honesty->text : number_text(c.honesty->ratio, 3));
    benchmark::DoNotOptimize(c.pose_covariance);
  }
  state.SetLabel(verdict);  // "not run ..." would say the check was not timed
}
// The advice calibrate_checked adds beside the check: the shared robot error's fit
// (shared_robot_error.h) about an n-sample joint fit, its noise estimated.
void BM_SharedRobotError(benchmark::State& state) {
  Rng rng(5);
  SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand),
                                        static_cast<int>(state.range(0)), paper_noise(1e-5));
  s.samples.noise.reset();
  const Calibration fitted = solve_joint(s.samples);
  bool chosen = false;
  for (auto _ : state) {
    const SharedRobotErrorFit fit = fit_shared_robot_error(s.samples, fitted);
    chosen = fit.chosen;
    benchmark::DoNotOptimize(fit.pose_covariance);
  }
  state.SetLabel(chosen ? "chosen" : "not chosen");
}
BENCHMARK(BM_SharedRobotError)->Arg(16)->Arg(30)->Arg(40)->Unit(benchmark::kMillisecond);
// calibrate_checked of `samples` with the defaults, their noise estimated (what `handeye
// solve` runs); the label: whether the shared robot error was used (`say_model`) and the
// honesty check's verdict and ratio.
void time_calibrate_checked(benchmark::State& state, SampleSet samples, bool say_model) {
  samples.noise.reset();
  CalibrationSession session(session_settings(samples));
  session.replace(samples.samples, "benchmark");
  std::string label;
  for (auto _ : state) {
    const Calibration c = session.calibrate_checked(session.snapshot());
    label = say_model ? std::string(c.shared_robot_error && c.shared_robot_error->used ? "used, " : "not used, ") : "";
    label += std::string(to_string(c.honesty->verdict)) + " " + number_text(c.honesty->ratio, 3);
    benchmark::DoNotOptimize(c.pose_covariance);
  }
  state.SetLabel(label);
}
// calibrate_checked of an n-sample session whose robot poses carry an error shared by
// nearby poses (simulation.h add_shared_robot_error: 2 mm, 0.15 degree per axis), its
// noise estimated, with the defaults: the model chosen and used, and the honesty check
// of it (check_shared_robot_error: 200 GLS splits, 100 bootstrap sessions, both looks).
void BM_SharedErrorSession(benchmark::State& state) {
  Rng rng(5);
  SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand),
                                        static_cast<int>(state.range(0)), paper_noise(1e-6));
  add_shared_robot_error(rng, s.samples, 2e-3, radians(0.15));
  time_calibrate_checked(state, s.samples, true);
}
BENCHMARK(BM_SharedErrorSession)->Arg(16)->Arg(30)->Arg(40)->Unit(benchmark::kMillisecond);

// The robust solve (outliers.h: the consensus screen, then the residual gate) of an
// n-sample session, its noise estimated, with the screen comparing every pair of samples
// (second argument 0, as before consensus_partners) or each sample with its 60 partners (1,
// the default; the same screen up to 61 samples).
void BM_RobustSolve(benchmark::State& state) {
  Rng rng(5);
  SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand),
                                        static_cast<int>(state.range(0)), paper_noise(1e-5));
  s.samples.noise.reset();
  OutlierOptions options;
  if (state.range(1) == 0) options.consensus_partners = static_cast<int>(2 * ((state.range(0) + 1) / 2));
  std::size_t rejected = 0;
  for (auto _ : state) {
    const Calibration c = solve_robust(s.samples, Method::Joint, options);
    rejected = c.rejected.size();
    benchmark::DoNotOptimize(c.pose_covariance);
  }
  state.SetLabel(std::to_string(rejected) + " rejected");
}
BENCHMARK(BM_RobustSolve)
    ->Args({50, 0})->Args({50, 1})->Args({250, 0})->Args({250, 1})->Args({1000, 0})->Args({1000, 1})
    ->Args({2000, 0})->Args({2000, 1})
    ->Unit(benchmark::kMillisecond);
// What `handeye solve` runs on an n-sample session with the defaults, its noise estimated
// (calibrate_checked: the robust solve, the noise model, the honesty check's two looks).
void BM_CalibrateChecked(benchmark::State& state) {
  Rng rng(5);
  SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand),
                                        static_cast<int>(state.range(0)), paper_noise(1e-5));
  time_calibrate_checked(state, s.samples, false);
}
BENCHMARK(BM_CalibrateChecked)->Arg(16)->Arg(50)->Arg(250)->Arg(1000)->Arg(2000)->Unit(benchmark::kMillisecond);

BENCHMARK(BM_HonestyCheck)
    ->Args({10, 0, 0, 1})
    ->Args({16, 0, 1, 1})
    ->Args({16, 0, 0, 1})
    ->Args({30, 0, 1, 0})
    ->Args({30, 0, 1, 1})
    ->Args({30, 0, 0, 1})
    ->Args({16, 1, 1, 1})
    ->Args({16, 1, 0, 1})
    ->Args({30, 1, 1, 0})
    ->Args({30, 1, 1, 1})
    ->Args({30, 1, 0, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2);

}  // namespace

// One next-best-pose suggestion: 150 sampled candidates ranked by the predicted
// covariance for a session of n samples (what the node does after each sample).
// The pairs estimator re-solves for every candidate; the joint one adds each
// candidate's rank-6 term to the 12x12 information.
void suggest_next_pose(benchmark::State& state, Method method) {
  Rng rng(3);
  const SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand),
                                              static_cast<int>(state.range(0)), paper_noise(1e-5));
  const Calibration c = estimate(s.samples, method);
  const SuggestOptions options;
  for (auto _ : state) {
    const Suggestion suggestion = rank_candidates(s.samples, c, sample_candidates(s.samples, c, options), options);
    benchmark::DoNotOptimize(suggestion.ranked.front().score);
  }
}
void BM_SuggestNextPose(benchmark::State& state) { suggest_next_pose(state, Method::Pairs); }
BENCHMARK(BM_SuggestNextPose)->Arg(10)->Arg(30)->Unit(benchmark::kMillisecond);
void BM_SuggestNextPoseJoint(benchmark::State& state) { suggest_next_pose(state, Method::Joint); }
BENCHMARK(BM_SuggestNextPoseJoint)->Arg(30)->Arg(300)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
