// How many samples each strategy needs before the predicted object 1 sigma at
// the working distance reaches a target: random reachable views against the
// next-best-pose suggestions (both criteria). Simulated sessions with known
// truth, seeded; each run also checks that the final covariance is honest
// (6-dof NEES of X against the truth).
//
//   handeye_next_best_pose [--seeds 30] [--target-mm 0.15] [--candidates 100] [--max-samples 80]
// Prints a Markdown table (scripts/bench puts it in BENCHMARKS.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/simulation/monte_carlo.h"
#include "handeye_covariance/simulation/simulation.h"
#include "handeye_covariance/estimation/next_best_pose.h"

namespace {

using namespace handeye;

struct Run {
  int samples = 0;       // samples when the target was reached (max_samples + 1: not reached)
  double nees = 0.0;     // 6-dof, final X against the truth
};

enum class Strategy { Random, ObjectSigma, Determinant };
const char* name(Strategy s) {
  return s == Strategy::Random ? "random reachable view" : s == Strategy::ObjectSigma ? "suggested, object_sigma" : "suggested, determinant";
}

Run run_session(Strategy strategy, Setup setup, unsigned seed, double target, int candidates, int max_samples) {
  Rng rng(seed);
  MeasurementNoise noise;  // the sim defaults: pattern 0.5 mm / 0.05 deg, robot 0.05 mm / 0.01 deg
  const double deg = kRadiansPerDegree;
  noise.camera = {std::pow(0.05 * deg, 2) * Eigen::Matrix3d::Identity(), std::pow(0.5e-3, 2) * Eigen::Matrix3d::Identity()};
  noise.robot = {std::pow(0.01 * deg, 2) * Eigen::Matrix3d::Identity(), std::pow(0.05e-3, 2) * Eigen::Matrix3d::Identity()};
  const Eigen::Isometry3d X = typical_X(setup);
  SimulatedSession session = simulate_session(rng, setup, X, 3, noise);  // the same 3 starting poses for every strategy
  SampleSet samples = session.samples;
  SuggestOptions options;
  options.criterion = strategy == Strategy::Determinant ? SuggestCriterion::Determinant : SuggestCriterion::ObjectSigma;
  options.candidates = strategy == Strategy::Random ? 1 : candidates;
  Run run;
  for (;;) {
    const Calibration c = solve(samples);
    const int n = static_cast<int>(samples.samples.size());
    if (target_progress(c, target, options.working_distance).reached || n > max_samples) {
      run.samples = n;
      const Vector6d e = pose_error(c.T_parent_camera, X);
      run.nees = e.dot(c.pose_covariance.ldlt().solve(e));
      return run;
    }
    options.seed = seed * 1000u + static_cast<unsigned>(n);
    const std::vector<Eigen::Isometry3d> pool = sample_candidates(samples, c, options);
    if (pool.empty()) {
      std::fprintf(stderr, "no reachable candidate (seed %u)\n", seed);
      std::exit(1);
    }
    const Eigen::Isometry3d E =
        strategy == Strategy::Random ? pool.front() : rank_candidates(samples, c, pool, options).ranked.front().T_base_effector;
    // The robot goes there; the camera sees the true pattern, both with noise.
    const Eigen::Isometry3d P = samples.rig.predicted_view(E, X, session.T_world_pattern);
    PoseSample s;
    s.T_base_effector = perturb(rng, E, noise.robot);
    s.T_camera_pattern = perturb(rng, P, noise.camera);
    samples.samples.push_back(s);
  }
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 30, candidates = 100, max_samples = 80;
  double target_mm = 0.15;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i];
    if (key == "--seeds") seeds = std::atoi(argv[i + 1]);
    else if (key == "--target-mm") target_mm = std::atof(argv[i + 1]);
    else if (key == "--candidates") candidates = std::atoi(argv[i + 1]);
    else if (key == "--max-samples") max_samples = std::atoi(argv[i + 1]);
    else { std::fprintf(stderr, "unknown option %s\n", argv[i]); return 2; }
  }
  std::printf("Target: predicted object 1 sigma <= %.3f mm at 0.7 m; %d seeded sessions per row, each starting "
              "from the same 3 random poses; %d candidates per suggestion; pattern noise 0.5 mm / 0.05 deg, "
              "robot 0.05 mm / 0.01 deg.\n\n", target_mm, seeds, candidates);
  std::printf("| setup | strategy | mean samples | median | max | samples vs random | NEES X (6-dof, mean) |\n");
  std::printf("|---|---|---:|---:|---:|---:|---:|\n");
  for (Setup setup : {Setup::EyeInHand, Setup::EyeToHand}) {
    double random_mean = 0.0;
    for (Strategy strategy : {Strategy::Random, Strategy::ObjectSigma, Strategy::Determinant}) {
      std::vector<int> counts;
      double nees = 0.0;
      for (int s = 1; s <= seeds; ++s) {
        const Run r = run_session(strategy, setup, static_cast<unsigned>(s), metres(target_mm), candidates, max_samples);
        counts.push_back(r.samples);
        nees += r.nees / seeds;
      }
      std::sort(counts.begin(), counts.end());
      double mean = 0.0;
      for (int c : counts) mean += static_cast<double>(c) / seeds;
      if (strategy == Strategy::Random) random_mean = mean;
      std::printf("| %s | %s | %.1f | %d | %d | %s | %.2f |\n", to_string(setup), name(strategy), mean,
                  counts[counts.size() / 2], counts.back(),
                  strategy == Strategy::Random ? "reference" : (std::to_string(static_cast<int>(std::lround(100.0 * (1.0 - mean / random_mean)))) + "% fewer").c_str(),
                  nees);
      std::fflush(stdout);
    }
  }
  return 0;
}
