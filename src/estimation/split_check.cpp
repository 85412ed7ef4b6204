#include "handeye_covariance/estimation/split_check.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <numeric>
#include <random>

#include <Eigen/Eigenvalues>

#include "handeye_covariance/core/statistics.h"
#include "handeye_covariance/core/validation.h"
#include "handeye_covariance/estimation/noise_estimation.h"

namespace handeye {

int min_samples_for_runs(int run_length) {
  if (run_length <= 1) return 8;
  // Four runs at least, and the smaller half (the first may overshoot n / 2 by a run
  // less one sample: n - n / 2 - k + 1) of 4 or more: n >= 2 k + 5.
  return std::max(4 * run_length, 2 * run_length + 5);
}

HalfSplitter::HalfSplitter(int n, int run_length) : n_(n), run_length_(run_length), order_(static_cast<std::size_t>(n)) {
  std::iota(order_.begin(), order_.end(), 0);
}

std::array<std::vector<int>, 2> HalfSplitter::next(std::mt19937_64& rng) {
  std::array<std::vector<int>, 2> halves;
  if (run_length_ == 1) {
    std::shuffle(order_.begin(), order_.end(), rng);
    for (int k = 0; k < n_; ++k) halves[k < n_ / 2 ? 0 : 1].push_back(order_[static_cast<std::size_t>(k)]);
    return halves;
  }
  // Runs of run_length consecutive samples (acquisition order), cut at a random
  // phase; whole runs go to the first half until it holds n / 2 or more.
  const int phase = static_cast<int>(rng() % static_cast<unsigned>(run_length_));
  std::vector<std::vector<int>> runs(1);
  for (int i = 0; i < n_; ++i) {
    if (i > 0 && (i - phase) % run_length_ == 0) runs.emplace_back();
    runs.back().push_back(i);
  }
  std::shuffle(runs.begin(), runs.end(), rng);
  std::vector<bool> first(static_cast<std::size_t>(n_), false);
  int filled = 0;
  for (const std::vector<int>& run : runs) {
    if (filled >= n_ / 2) break;
    for (int i : run) first[static_cast<std::size_t>(i)] = true;
    filled += static_cast<int>(run.size());
  }
  for (int i = 0; i < n_; ++i) halves[first[static_cast<std::size_t>(i)] ? 0 : 1].push_back(i);
  return halves;
}

SplitCheck split_check(const SampleSet& samples, const SolveSamples& solve, int splits, unsigned seed, int run_length) {
  const int n = static_cast<int>(samples.samples.size());
  if (n < 8) {
    throw HandEyeError(ErrorCode::TooFewMotions,
                       "the split-half check needs at least 8 samples (two halves of 4), got " + std::to_string(n),
                       "samples", "record more samples; the check is meaningful from about 20");
  }
  if (run_length < 1 || n < min_samples_for_runs(run_length)) {
    throw HandEyeError(ErrorCode::TooFewMotions,
                       "halves of runs of " + std::to_string(run_length) + " consecutive samples need at least " +
                           std::to_string(min_samples_for_runs(std::max(run_length, 1))) +
                           " samples (and a run length >= 1), got " + std::to_string(n),
                       "split_runs", "use shorter runs, or 1 for random halves");
  }
  SplitCheck check;
  check.run_length = run_length;
  check.half_size = n / 2;
  std::mt19937_64 rng(seed);
  HalfSplitter splitter(n, run_length);
  for (int split = 0; split < splits; ++split) {
    const std::array<std::vector<int>, 2> index = splitter.next(rng);
    SampleSet halves[2];
    for (int h = 0; h < 2; ++h) {
      halves[h].rig = samples.rig, halves[h].noise = samples.noise;
      for (int i : index[static_cast<std::size_t>(h)]) halves[h].samples.push_back(samples.samples[static_cast<std::size_t>(i)]);
    }
    check.half_size = std::min(check.half_size, static_cast<int>(std::min(index[0].size(), index[1].size())));
    Calibration a, b;
    try {
      a = solve(halves[0]);
      b = solve(halves[1]);
    } catch (const HandEyeError& e) {
      if (check.first_failure.empty()) check.first_failure = e.what();
      ++check.failed;
      continue;
    }
    const Vector6d d = pose_error(a.T_parent_camera, b.T_parent_camera);
    const Matrix6d S = a.pose_covariance + b.pose_covariance;
    const double nees = d.dot(S.ldlt().solve(d));
    check.nees.push_back(nees);
    check.differences.push_back(d);
    check.difference_sigmas.push_back(S.diagonal().cwiseMax(0.0).cwiseSqrt());
    check.mean_nees_translation += d.head<3>().dot(S.topLeftCorner<3, 3>().ldlt().solve(d.head<3>()));
    check.mean_nees_rotation += d.tail<3>().dot(S.bottomRightCorner<3, 3>().ldlt().solve(d.tail<3>()));
  }
  summarise_splits(check);
  return check;
}

const char* to_string(Honesty honesty) {
  switch (honesty) {
    case Honesty::Honest: return "honest";
    case Honesty::Overconfident: return "overconfident";
    case Honesty::Underconfident: return "underconfident";
    case Honesty::NotRun: return "not run";
  }
  return "not run";
}

Honesty from_string(const std::string& name, Honesty) {
  for (Honesty h : {Honesty::Honest, Honesty::Overconfident, Honesty::Underconfident, Honesty::NotRun}) {
    if (name == to_string(h)) return h;
  }
  throw HandEyeError(ErrorCode::MalformedFile, "unknown honesty verdict `" + name + "`", "honesty: verdict",
                     "write honest, overconfident, underconfident or not run");
}

void record_honesty(Calibration& c, const HonestyCheck& check, bool inflate, const std::string& words) {
  Calibration::Honesty h;
  h.splits = check.observed.splits;
  h.half_size = check.observed.half_size;
  h.run_length = check.observed.run_length;
  h.random_ratio = check.random_ratio;
  h.runs = {check.runs_length, check.runs_ratio};
  h.runs_note = check.runs_note;
  h.split_half_nees = check.observed.trimmed_mean_nees;
  h.reference = {check.reference.replicates, check.reference.mean, check.reference.low, check.reference.high};
  h.ratio = check.ratio;
  h.verdict = check.ran() ? check.verdict : Honesty::NotRun;
  h.text = words;
  h.model_pose_covariance = c.pose_covariance;
  if (inflate && check.verdict == Honesty::Overconfident && check.inflation > 1.0) {
    const double k = check.inflation;
    h.inflation = k;
    scale_covariances(c, k);
    Warning w;
    w.kind = Warning::Kind::Inflated;
    w.factor = k;
    w.run_length = check.observed.run_length;
    c.warnings.insert(c.warnings.begin(), w);
  }
  c.honesty = h;
}

SampleSet simulate_like(const SampleSet& samples, const Calibration& fitted, const std::vector<Matrix6d>& residual_covariances,
                        std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  SampleSet out = samples;
  const Eigen::Isometry3d& X = fitted.T_parent_camera;
  const Eigen::Isometry3d Y = fitted.pattern ? fitted.pattern->pose : pattern_pose(samples, X);
  for (std::size_t i = 0; i < out.samples.size(); ++i) {
    PoseSample& s = out.samples[i];
    // S = L L^T; a semi-definite S (a zero-noise axis) by its eigen root.
    const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(residual_covariances.at(i));
    const Matrix6d root = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
    Vector6d z;
    for (int k = 0; k < 6; ++k) z[k] = normal(rng);
    const Vector6d eps = root * z;
    const Eigen::Isometry3d predicted = samples.rig.predicted_view(s.T_base_effector, X, Y);
    s.T_camera_pattern = se3::make_pose(so3::exp(eps.tail<3>()) * predicted.linear(), predicted.translation() + eps.head<3>());
    s.corners.reset();
  }
  return out;
}

void summarise_splits(SplitCheck& check) {
  check.splits = static_cast<int>(check.nees.size());
  if (check.splits == 0) return;
  check.mean_nees = std::accumulate(check.nees.begin(), check.nees.end(), 0.0) / check.splits;
  std::vector<double> sorted = check.nees;
  std::sort(sorted.begin(), sorted.end());
  const std::size_t cut = sorted.size() / 20;
  check.trimmed_mean_nees = std::accumulate(sorted.begin() + static_cast<long>(cut), sorted.end() - static_cast<long>(cut), 0.0) /
                            static_cast<double>(sorted.size() - 2 * cut);
  check.mean_nees_translation /= check.splits;
  check.mean_nees_rotation /= check.splits;
}

HonestyCheck judge_look(const SplitCheck& observed, const std::vector<SplitCheck>& replicates, int failed, int replicate_splits) {
  HonestyCheck check;
  check.observed = observed;
  SplitCheckReference& ref = check.reference;
  ref.splits = replicate_splits;
  ref.failed = failed;
  double within = 0.0;  // the mean over replicates of the NEES's variance across their splits
  for (const SplitCheck& replicate : replicates) {
    if (replicate.splits == 0) {
      ++ref.failed;
      continue;
    }
    ref.means.push_back(replicate.trimmed_mean_nees);
    // The spread across splits, of the middle 90% too (winsorised at its ends).
    std::vector<double> sorted = replicate.nees;
    std::sort(sorted.begin(), sorted.end());
    const std::size_t cut = sorted.size() / 20;
    double v = 0.0;
    for (std::size_t k = 0; k < sorted.size(); ++k) {
      const double nees = sorted[std::clamp(k, cut, sorted.size() - 1 - cut)];
      v += (nees - replicate.trimmed_mean_nees) * (nees - replicate.trimmed_mean_nees);
    }
    within += replicate.splits > 1 ? v / (replicate.splits - 1) : 0.0;
  }
  ref.replicates = static_cast<int>(ref.means.size());
  if (ref.replicates < 2 || check.observed.splits == 0) {
    check.text = ref.replicates < 2 ? "no reference: fewer than 2 simulated sessions could be split"
                                    : "no reference: no split of the session could be solved";
    return check;
  }
  const double count = ref.replicates;
  ref.mean = std::accumulate(ref.means.begin(), ref.means.end(), 0.0) / count;
  within /= count;
  double spread = 0.0;
  for (double m : ref.means) spread += (m - ref.mean) * (m - ref.mean);
  spread /= count - 1;
  // Var(mean of m splits) = Var(U) + within / m, U the session's mean over all splits.
  const double between = std::max(0.0, spread - within / ref.splits);
  const double scale = spread > 0.0 ? std::sqrt((between + within / check.observed.splits) / spread) : 1.0;
  std::vector<double> adjusted;
  for (double m : ref.means) adjusted.push_back(ref.mean + scale * (m - ref.mean));
  ref.low = linear_quantile(adjusted, 0.05);
  ref.high = linear_quantile(adjusted, 0.95);
  const double value = check.observed.trimmed_mean_nees;
  check.ratio = value / ref.mean;
  check.verdict = value > ref.high   ? Honesty::Overconfident
                  : value < ref.low ? Honesty::Underconfident
                                    : Honesty::Honest;
  check.inflation = check.verdict == Honesty::Overconfident ? check.ratio : 1.0;
  return check;
}

HonestyCheck worse_look(HonestyCheck random, const HonestyCheck* runs, int run_length) {
  random.random_ratio = random.ratio;
  random.random_verdict = random.verdict;
  if (run_length == 0 || runs == nullptr || !random.ran()) return random;
  if (!runs->ran()) {
    random.runs_note = "halves of runs of " + std::to_string(run_length) + ": " + runs->text;
    return random;
  }
  // The worse look decides: the runs when they read overconfident beyond the random halves.
  const bool runs_decide = runs->verdict == Honesty::Overconfident && runs->ratio > random.ratio;
  HonestyCheck check = runs_decide ? *runs : random;
  check.random_ratio = random.ratio;
  check.random_verdict = random.verdict;
  check.runs_length = run_length;
  check.runs_ratio = runs->ratio;
  check.runs_verdict = runs->verdict;
  check.runs_note = random.runs_note;
  return check;
}

namespace {

/// One look: the session's halves (random, or runs of run_length) against its
/// reference, the simulated sessions split the same way.
HonestyCheck one_look(const SampleSet& session, const std::vector<SampleSet>& simulated, int failed_fits,
                      const SolveSamples& solve_half, const HonestyOptions& options, int run_length, int replicate_splits) {
  const SplitCheck observed = split_check(session, solve_half, options.splits, options.seed, run_length);
  const int splits = std::min(options.splits, std::max(1, replicate_splits));
  std::vector<SplitCheck> replicates;
  for (const SampleSet& replica : simulated) {
    replicates.push_back(split_check(replica, solve_half, splits, options.seed, run_length));  // the session's own halves
  }
  return judge_look(observed, replicates, failed_fits, splits);
}

}  // namespace

int runs_length_for(const HonestyOptions& options, int n, std::string* why_not) {
  const int k = options.run_length;
  if (k == 1) return 0;
  if (k == 0) return n >= 16 ? std::clamp(n / 8, 2, 4) : 0;
  if (k < 0 || k > n / 4 || n < min_samples_for_runs(k)) {
    if (why_not) {
      *why_not = k < 0 ? "a run length must be >= 0 (0: chosen from the samples), got " + std::to_string(k)
                       : "halves of runs of " + std::to_string(k) + " consecutive samples need at least " +
                             std::to_string(min_samples_for_runs(k)) + " samples, there are " + std::to_string(n);
    }
    return 0;
  }
  return k;
}

SampleSet with_held_noise(const SampleSet& samples, const std::vector<Matrix6d>& S) {
  SampleSet held = samples;
  held.noise = MeasurementNoise{PoseNoise{}, PoseNoise::from_pose_covariance(S.at(0))};  // each sample has its own
  for (std::size_t i = 0; i < held.samples.size(); ++i) {
    held.samples[i].noise = MeasurementNoise{PoseNoise{}, PoseNoise::from_pose_covariance(S.at(i))};
    held.samples[i].corners.reset();
  }
  return held;
}

Calibration solve_with_held_noise(const SampleSet& half) {
  JointOptions options;
  options.estimate_missing_noise = false;
  options.robust = JointOptions::Robust::Off;
  return solve_joint(half, options);
}

HonestyCheck honesty_check(const SampleSet& samples, const Calibration& fitted, const SolveSamples& solve,
                           const HonestyOptions& options) {
  const std::vector<Matrix6d> S = residual_covariances(samples, fitted);
  // Held noise is solved by the joint estimator: another estimator's halves are its own.
  const bool hold = options.hold_noise && fitted.method == Method::Joint;
  const SolveSamples solve_half = hold ? SolveSamples(solve_with_held_noise) : solve;
  // The simulated sessions, once for both looks: drawn at the session's poses from its
  // fit, and with the noise held, each fitted in full as the session was.
  const int n = static_cast<int>(samples.samples.size());
  const int replicates = n <= options.full_replicates_up_to
                             ? options.replicates
                             : std::max(std::min(20, options.replicates), options.replicates * options.full_replicates_up_to / n);
  std::mt19937_64 rng(options.seed ^ 0x5eed5eedULL);
  std::vector<SampleSet> simulated;
  int failed_fits = 0;
  for (int r = 0; r < replicates; ++r) {
    SampleSet replica = simulate_like(samples, fitted, S, rng);
    if (hold) {
      try {
        const Calibration fit = solve(replica);
        replica = with_held_noise(replica, residual_covariances(replica, fit));
      } catch (const HandEyeError&) {
        ++failed_fits;
        continue;
      }
    }
    simulated.push_back(std::move(replica));
  }
  const SampleSet session = hold ? with_held_noise(samples, S) : samples;
  const HonestyCheck random = one_look(session, simulated, failed_fits, solve_half, options, 1, options.replicate_splits);
  std::string why_not;
  const int k = runs_length_for(options, n, &why_not);
  if (k == 0 || !random.ran()) {
    HonestyCheck alone = worse_look(random, nullptr, 0);
    alone.runs_note = why_not;
    return alone;
  }
  const HonestyCheck runs =
      one_look(session, simulated, failed_fits, solve_half, options, k, std::max(20, options.replicate_splits / 2));
  return worse_look(random, &runs, k);
}

}  // namespace handeye
