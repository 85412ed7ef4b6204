// On the simulated arm, from the same start poses, how many
// samples the robot moving itself (auto/auto_calibration.h: the session's
// ranking filtered by the planner) needs to reach an object 1 sigma at 0.7 m,
// against easy_handeye's fixed star of 17 poses around the start (rotations of
// +-25 and +-12.5 deg about the effector's x, y and z; +-5 cm in x, +-10 cm in y,
// +3.3 cm in z, in the base frame), run through the same session and the same
// planner checks. A sample is taken where the board is whole in the image.
// Seeded; no ROS.
//
//   handeye_auto_study [--seeds 20] [--target-mm 1.0] [--max-views 40] [--noise stated|estimated] [--controller on]
// Prints a Markdown table (scripts/bench puts it in BENCHMARKS.md).
// --controller on: every move through the simulated joint_trajectory_controller
// (simulation/trajectory_controller.h) and the move monitor, at speed scales from 1
// to 0.05 and dropped during each move: calibrations completed, false failures, how
// much longer moves took; then a stall at every part of a move (how soon it is caught
// after the arm stops) and a controller that refuses every command (how soon that is said).
// --noise estimated is the node's own configuration in simulated_arm.launch (the rig's
// detections without a covariance, the robot exact from TF, so the noise is estimated
// from the residuals): auto alone, and how honest X's covariance is where it stops
// (target_progress, next_best_pose.h), by the sample count it stopped at.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "handeye_covariance/core/statistics.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/estimation/split_check.h"
#include "handeye_covariance/auto/auto_calibration.h"
#include "handeye_covariance/simulation/arm_rig.h"
#include "handeye_covariance/simulation/trajectory_controller.h"

namespace {

using namespace handeye;

struct Run {
  std::string failure;       // --controller: a move that failed
  std::vector<double> slowdown;  // --controller: each move's time to arrival over its planned duration
  bool commands_whole = true;    // --controller: every command taken as sent
  int samples = 0;           // taken in all
  int to_target = -1;        // samples when the target was first reached; -1: not reached
  std::vector<double> sigma; // object sigma after each sample (0 before an estimate)
  int moves = 0, no_detection = 0;
  std::vector<double> plan_ms;
  double nees = 0.0;         // final X against the truth
};

bool estimated_noise = false;  // --noise estimated

MeasurementNoise rig_noise() {  // the simulated rig's detections (rig_simulator's defaults), a small robot noise
  MeasurementNoise noise;
  noise.camera.translation = std::pow(0.3e-3, 2) * Eigen::Matrix3d::Identity();
  noise.camera.rotation = std::pow(radians(0.05), 2) * Eigen::Matrix3d::Identity();
  if (estimated_noise) return noise;  // the node's robot pose comes from TF, exact
  noise.robot.translation = std::pow(0.05e-3, 2) * Eigen::Matrix3d::Identity();
  noise.robot.rotation = std::pow(radians(0.005), 2) * Eigen::Matrix3d::Identity();
  return noise;
}

struct Sim {
  const ArmRig& rig;
  const motion::CollisionModel& collision;
  Rng rng;
  CalibrationSession session;
  std::vector<PoseSample> samples;
  std::vector<Eigen::Isometry3d> failed;  // moves without a detection
  Run run;
  double target;

  Sim(const ArmRig& r, const motion::CollisionModel& c, unsigned seed, double target_sigma)
      : rig(r), collision(c), rng(seed), session(settings()), target(target_sigma) {}

  SessionSettings settings() const {
    SessionSettings s;
    s.rig = rig.rig;
    if (!estimated_noise) s.noise = rig_noise();
    s.suggest.views = rig.views;
    s.honesty.splits = 0;
    return s;
  }

  // The camera takes a sample at q if it sees the whole board; then the session calibrates.
  void take(const Eigen::VectorXd& q) {
    const Eigen::Isometry3d P = rig.rig.predicted_view(rig.arm.forward(q), rig.X, rig.Y);
    if (motion::view_problem(rig.rig, std::nullopt, P, motion::PlannerOptions{})) {
      ++run.no_detection;
      failed.push_back(rig.arm.forward(q));
      return;
    }
    samples.push_back(rig.sample_at(rng, q, rig_noise()));
    session.replace(samples, "sample");
    ++run.samples;
    double sigma = 0.0;
    bool reached = false;
    if (samples.size() >= 3) {
      try {
        const Calibration c = session.calibrate(session.snapshot());
        const TargetProgress progress = target_progress(c, target, 0.7);
        sigma = progress.object_sigma, reached = progress.reached;
        const Vector6d e = pose_error(c.T_parent_camera, rig.X);
        run.nees = e.dot(c.pose_covariance.ldlt().solve(e));
      } catch (const HandEyeError&) {
      }
    }
    run.sigma.push_back(sigma);
    if (run.to_target < 0 && reached) run.to_target = run.samples;
  }
};

// --controller: the speed scale each move starts at, and the one it drops to once half its path is covered.
struct SpeedProfile {
  const char* name;
  double scale = 1.0, dropped = 1.0;
};

Run run_auto(const ArmRig& rig, const motion::CollisionModel& collision, const Eigen::VectorXd& start, unsigned seed,
             double target, int max_views, const SpeedProfile* profile = nullptr) {
  Sim sim(rig, collision, seed, target);
  const AutoCalibration automatic(collision, std::nullopt);
  Eigen::VectorXd q = start;
  std::optional<SimulatedArm> arm;
  if (profile) arm.emplace(rig.arm, start);
  sim.take(q);
  while (sim.run.to_target < 0 && sim.run.moves < max_views) {
    const auto t0 = std::chrono::steady_clock::now();
    const NextMove move = automatic.next(sim.session, sim.session.snapshot(), q, sim.failed);
    sim.run.plan_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (!move.found) {
      std::fprintf(stderr, "seed %u: %s\n", seed, move.reason.c_str());
      break;
    }
    q = move.plan.goal;
    if (arm) {  // through the controller and the monitor, then the sampler's stillness
      arm->controller().set_speed_scale(profile->scale);
      const MoveRun m = run_move(*arm, rig.arm, move.trajectory, {}, {[&](SimulatedArm& a, const motion::MoveMonitor& mon) {
        if (mon.covered() > 0.5 * mon.path_length()) a.controller().set_speed_scale(profile->dropped);
      }});
      sim.run.commands_whole = sim.run.commands_whole && arm->all_taken_whole();
      if (m.status != motion::MoveStatus::Arrived) {
        sim.run.failure = m.reason;
        break;
      }
      sim.run.slowdown.push_back(m.decided / move.trajectory.back().time);
      const SamplerOptions& still = sim.session.settings().sampler;
      arm->wait_still(rig.arm, still.still_window, still.still_translation, still.still_rotation);
      q = arm->q();
    }
    ++sim.run.moves;
    sim.take(q);
  }
  return sim.run;
}

// A straight move between two random postures of the arm, at `fraction` of its velocity limits.
std::vector<motion::TrajectoryPoint> random_move(const motion::Arm& arm, Rng& rng, double fraction) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Eigen::VectorXd a(arm.joints()), b(arm.joints());
  for (int j = 0; j < arm.joints(); ++j) {
    const motion::JointLimit& l = arm.limits()[j];
    a(j) = l.lower + 0.5 + unit(rng) * (l.upper - l.lower - 1.0);
    b(j) = a(j) + 0.8 * (2.0 * unit(rng) - 1.0);
  }
  motion::MoveTiming timing;
  timing.speed_fraction = fraction;
  return motion::timed_move(arm, a, b, timing);
}

double median_of_counts(std::vector<double> v);

int controller_study(const ArmRig& rig, const motion::CollisionModel& collision, int seeds, double target,
                     int max_views) {
  std::printf("| speed scale | calibrations completed | moves | false failures | reached %.2g mm | median samples | "
              "move time over planned: median, max | commands not taken as sent |\n",
              millimetres(target));
  std::printf("|---|---:|---:|---:|---:|---:|---|---:|\n");
  for (const SpeedProfile& profile : {SpeedProfile{"1", 1.0, 1.0}, SpeedProfile{"0.5", 0.5, 0.5},
                                      SpeedProfile{"0.1", 0.1, 0.1}, SpeedProfile{"0.05", 0.05, 0.05},
                                      SpeedProfile{"1, 0.2 from half way", 1.0, 0.2},
                                      SpeedProfile{"0.1, 1 from half way", 0.1, 1.0}}) {
    int runs = 0, completed = 0, reached = 0, moves = 0, not_whole = 0;
    std::vector<double> samples, slowdown;
    std::string first_failure;
    for (int seed = 1; seed <= seeds; ++seed) {
      Rng rng(seed);
      const auto start = rig.random_start(rng, collision, motion::PlannerOptions{});
      if (!start) continue;
      ++runs;
      const Run r = run_auto(rig, collision, *start, 1000 + seed, target, max_views, &profile);
      completed += r.failure.empty();
      if (first_failure.empty()) first_failure = r.failure;
      reached += r.to_target > 0;
      moves += r.moves;
      not_whole += !r.commands_whole;
      if (r.to_target > 0) samples.push_back(r.to_target);
      slowdown.insert(slowdown.end(), r.slowdown.begin(), r.slowdown.end());
    }
    std::printf("| %s | %d of %d | %d | %d | %d | %.0f | %.1f, %.1f | %d |\n", profile.name, completed, runs, moves,
                runs - completed, reached, median_of_counts(samples), median_of_counts(slowdown),
                slowdown.empty() ? 0.0 : *std::max_element(slowdown.begin(), slowdown.end()), not_whole);
    if (!first_failure.empty()) std::printf("\nfirst failure at speed scale %s: %s\n\n", profile.name, first_failure.c_str());
  }
  // A protective stop at a fraction of a move's path: how soon after the arm stops the node says so.
  std::printf("\n| speed scale | the arm stops at | stalls | caught after the stop: median, 95%%, max [s] |\n");
  std::printf("|---:|---:|---:|---|\n");
  Rng rng(7);
  for (const double scale : {1.0, 0.1}) {
    for (const double fraction : {0.05, 0.25, 0.5, 0.75, 0.95}) {
      std::vector<double> caught;
      for (int k = 0; k < 40; ++k) {
        const auto trajectory = random_move(rig.arm, rng, k % 2 ? 0.1 : 0.2);
        ControllerOptions options;
        options.stop_fraction = fraction;
        SimulatedArm arm(rig.arm, trajectory.front().position, options);
        arm.controller().set_speed_scale(scale);
        double stopped = 0.0;
        Eigen::VectorXd last = arm.q();
        const MoveRun m = run_move(arm, rig.arm, trajectory, {}, {[&](SimulatedArm& a, const motion::MoveMonitor&) {
          if (stopped == 0.0 && motion::largest_joint_change(a.q(), last) == 0.0 && a.now() > 1000.05) stopped = a.now();
          last = a.q();
        }});
        if (m.status == motion::MoveStatus::Stalled && stopped > 0.0) caught.push_back(1000.0 + m.decided - stopped);
      }
      std::printf("| %.2g | %.0f%% | %zu | %.2f, %.2f, %.2f |\n", scale, 100.0 * fraction, caught.size(),
                  linear_quantile(caught, 0.5), linear_quantile(caught, 0.95),
                  caught.empty() ? 0.0 : *std::max_element(caught.begin(), caught.end()));
    }
  }
  // A controller that was not started: every command refused, the arm never moves.
  std::vector<double> said;
  for (int k = 0; k < 200; ++k) {
    const auto trajectory = random_move(rig.arm, rng, k % 2 ? 0.1 : 0.2);
    ControllerOptions options;
    options.running = false;
    SimulatedArm arm(rig.arm, trajectory.front().position, options);
    said.push_back(run_move(arm, rig.arm, trajectory).decided);
  }
  std::printf("\na controller that refuses every command, 200 random moves: \"did not start\" after median %.2f s, "
              "at most %.2f s\n",
              linear_quantile(said, 0.5), *std::max_element(said.begin(), said.end()));
  return 0;
}

// easy_handeye's CalibrationMovements._compute_poses_around_state, in its order.
std::vector<Eigen::Isometry3d> star(const Eigen::Isometry3d& E, double angle, double translation) {
  std::vector<Eigen::Isometry3d> poses;
  for (const double scale : {1.0, 0.5})
    for (int axis = 0; axis < 3; ++axis)
      for (const double sign : {1.0, -1.0}) {
        Eigen::Isometry3d p = E;
        p.rotate(Eigen::AngleAxisd(sign * scale * angle, Eigen::Vector3d::Unit(axis)));
        poses.push_back(p);
      }
  for (const Eigen::Vector3d& d : {Eigen::Vector3d(translation / 2, 0, 0), Eigen::Vector3d(-translation / 2, 0, 0),
                                   Eigen::Vector3d(0, translation, 0), Eigen::Vector3d(0, -translation, 0),
                                   Eigen::Vector3d(0, 0, translation / 3)}) {
    Eigen::Isometry3d p = E;
    p.translation() += d;
    poses.push_back(p);
  }
  return poses;
}

Run run_star(const ArmRig& rig, const motion::CollisionModel& collision, const Eigen::VectorXd& start, unsigned seed,
             double target) {
  Sim sim(rig, collision, seed, target);
  sim.take(start);
  Eigen::VectorXd q = start;
  for (const Eigen::Isometry3d& pose : star(rig.arm.forward(start), radians(25.0), 0.1)) {
    // Each star pose from the start (easy_handeye plans every one from there), checked as ours are.
    const motion::ViewPlan plan =
        motion::plan_view(collision, rig.rig, std::nullopt, q, {{pose, Eigen::Isometry3d::Identity(), false}}, {});
    if (!plan.found()) continue;
    q = plan.goal;
    ++sim.run.moves;
    sim.take(q);
  }
  return sim.run;
}

// --noise estimated: auto alone, X's NEES where it stopped, by the count it stopped at.
int estimated_noise_study(const ArmRig& rig, const motion::CollisionModel& collision, int seeds, double target,
                          int max_views) {
  std::vector<double> nees;
  std::vector<std::vector<double>> by_count(64);
  int runs = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    Rng rng(seed);
    const auto start = rig.random_start(rng, collision, motion::PlannerOptions{});
    if (!start) continue;
    ++runs;
    const Run a = run_auto(rig, collision, *start, 1000 + seed, target, max_views);
    if (a.to_target < 0) continue;
    nees.push_back(a.nees);
    by_count[std::min<std::size_t>(a.to_target, by_count.size() - 1)].push_back(a.nees);
  }
  double mean = 0.0, square = 0.0;
  for (double n : nees) mean += n / nees.size();
  for (double n : nees) square += (n - mean) * (n - mean) / std::max<std::size_t>(nees.size() - 1, 1);
  const auto beyond = [&](double bound) {
    return 100.0 * std::count_if(nees.begin(), nees.end(), [&](double n) { return n > bound; }) / std::max<std::size_t>(nees.size(), 1);
  };
  std::printf("| samples at the stop | runs | mean NEES of X |\n|---:|---:|---:|\n");
  for (std::size_t k = 0; k < by_count.size(); ++k) {
    if (by_count[k].empty()) continue;
    double m = 0.0;
    for (double n : by_count[k]) m += n / by_count[k].size();
    std::printf("| %zu | %zu | %.2f |\n", k, by_count[k].size(), m);
  }
  std::printf("\nnoise estimated from the residuals, robot exact: auto reached %.2g mm in %zu of %d runs; NEES of X where "
              "it stopped: mean %.2f +- %.2f (6 for an honest covariance), beyond chi2(6)'s 99%% point 16.81 in %.1f%%, "
              "beyond its 99.9%% point 22.46 in %.1f%%; quantiles 90%% %.2f, 99%% %.2f, 99.9%% %.2f.\n",
              millimetres(target), nees.size(), runs, mean, std::sqrt(square / std::max<std::size_t>(nees.size(), 1)), beyond(16.81),
              beyond(22.46), linear_quantile(nees, 0.9), linear_quantile(nees, 0.99), linear_quantile(nees, 0.999));
  return 0;
}

double median_of_counts(std::vector<double> v) {  // of an even count, the mean of the middle two
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 20, max_views = 40;
  double target_mm = 1.0;
  bool controller = false;
  const char* usage =
      "usage: handeye_auto_study [--seeds 20] [--target-mm 1.0] [--max-views 40] [--noise stated|estimated] "
      "[--controller on]\n";
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--seeds")) seeds = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--target-mm")) target_mm = std::atof(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--max-views")) max_views = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--controller") && !std::strcmp(argv[i + 1], "on")) controller = true;
    else if (!std::strcmp(argv[i], "--noise") && (!std::strcmp(argv[i + 1], "stated") || !std::strcmp(argv[i + 1], "estimated")))
      estimated_noise = !std::strcmp(argv[i + 1], "estimated");
    else {
      std::fprintf(stderr, "%s", usage);
      return 2;
    }
  }
  if (argc % 2 == 0) {
    std::fprintf(stderr, "%s", usage);
    return 2;
  }
  const ArmRig rig = ArmRig::load(HANDEYE_SOURCE_DIR "/urdf/sim_arm.urdf");
  const motion::CollisionModel collision(rig.arm, motion::table_plane());
  const double target = metres(target_mm);
  if (estimated_noise) return estimated_noise_study(rig, collision, seeds, target, max_views);
  if (controller) return controller_study(rig, collision, seeds, target, max_views);
  std::printf("| seed | auto: samples to %.2g mm | star: samples to %.2g mm | star: samples taken: sigma [mm] | "
              "auto: samples to the star's sigma | auto: NEES of X | moves without a detection (auto / star) |\n",
              target_mm, target_mm);
  std::printf("|---:|---:|---:|---:|---:|---:|---:|\n");
  std::vector<double> auto_samples, star_samples, auto_to_star, plan_ms, nees;
  int star_reached = 0, auto_reached = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    Rng rng(seed);
    const auto start = rig.random_start(rng, collision, motion::PlannerOptions{});
    if (!start) continue;
    const Run a = run_auto(rig, collision, *start, 1000 + seed, target, max_views);
    const Run s = run_star(rig, collision, *start, 1000 + seed, target);
    const double star_sigma = s.sigma.empty() ? 0.0 : s.sigma.back();
    // Auto's samples to reach what the star reaches in all its samples (running further if it must).
    const Run a2 = star_sigma > 0.0 ? run_auto(rig, collision, *start, 1000 + seed, star_sigma, max_views) : Run{};
    auto_reached += a.to_target > 0;
    star_reached += s.to_target > 0;
    if (a.to_target > 0) auto_samples.push_back(a.to_target);
    if (s.to_target > 0) star_samples.push_back(s.to_target);
    if (a2.to_target > 0) auto_to_star.push_back(static_cast<double>(a2.to_target) / s.samples);
    plan_ms.insert(plan_ms.end(), a.plan_ms.begin(), a.plan_ms.end());
    nees.push_back(a.nees);
    char star_text[64];
    if (star_sigma > 0.0)
      std::snprintf(star_text, sizeof star_text, "%d: %.3f", s.samples, millimetres(star_sigma));
    else
      std::snprintf(star_text, sizeof star_text, "%d: no estimate", s.samples);
    std::printf("| %d | %s | %s | %s | %s | %.2f | %d / %d |\n", seed,
                a.to_target > 0 ? std::to_string(a.to_target).c_str() : "not reached",
                s.to_target > 0 ? std::to_string(s.to_target).c_str() : "not reached", star_text,
                a2.to_target > 0 ? std::to_string(a2.to_target).c_str() : "not reached", a.nees, a.no_detection,
                s.no_detection);
  }
  double mean_nees = 0.0;
  for (double n : nees) mean_nees += n / nees.size();
  std::printf("\nauto reached %.2g mm in %d of %zu runs, median %.0f samples; the star in %d, median %.0f samples.\n",
              target_mm, auto_reached, nees.size(), median_of_counts(auto_samples), star_reached, median_of_counts(star_samples));
  std::printf("auto's samples to reach the star's final sigma over the star's samples: median %.2f (goal <= 0.6).\n",
              median_of_counts(auto_to_star));
  std::printf("planning one move (session ranking + planner): median %.1f ms; mean NEES of auto's final X %.2f "
              "(6 expected).\n",
              median_of_counts(plan_ms), mean_nees);
  return 0;
}
