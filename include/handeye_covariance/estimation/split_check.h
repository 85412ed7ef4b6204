// The split-half check: is the covariance honest on this session? (No truth
// needed, so it works on real data.)
//
// The samples are split at random into two halves a and b, each is solved, and
// the difference of their X is judged under the sum of their covariances (the
// halves share no sample, so their errors are independent):
//     d = (t_a - t_b, log(R_a R_b^T)),   NEES = d^T (Sigma_a + Sigma_b)^-1 d.
// Over many random splits the mean NEES is about 6 when the covariance is
// honest; well above (> 7.5) it is overconfident, well below (< 5) too cautious.
// Each half holds about n/2 samples, so it says how honest the covariance of an
// n/2-pose session of this kind is.
//
// What random halves cannot see: an error shared by neighbouring samples. A robot
// whose pose error changes smoothly along its path (a kinematic error, drift) gives
// consecutive samples alike errors; random halves each hold about half of every
// stretch of the path, so the shared part cancels in d, while it does not cancel in
// X's error. Halves made of runs of consecutive samples (run_length > 1) keep
// neighbours together: such an error then enlarges d, and the check, against a
// reference split the same way, reads overconfident (docs/how_it_works.md).
#pragma once

#include <array>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/estimation/joint_estimator.h"

namespace handeye {

struct SplitCheck {
  int run_length = 1;       // 1: random halves; k: halves of runs of k consecutive samples
  int splits = 0;           // random splits solved
  int failed = 0;           // splits where a half could not be solved (too few or degenerate samples)
  int half_size = 0;        // samples in the smaller half (of any split)
  double mean_nees = 0.0;   // 6-dof, over the solved splits
  /// The mean of the middle 90% of the splits' NEES (5% dropped at each end): what
  /// the calibrated check compares, since a rare degenerate half (a noise number at
  /// its bound) gives a NEES of thousands that would otherwise decide the mean. It
  /// scales as the plain mean does: a covariance k times too small multiplies both by k.
  double trimmed_mean_nees = 0.0;
  double mean_nees_translation = 0.0, mean_nees_rotation = 0.0;  // 3-dof blocks
  std::vector<double> nees;  // each split's
  /// Each solved split's d (ROS order, m and rad) and the 1 sigma per axis its
  /// covariance Sigma_a + Sigma_b predicts: the per-axis check (report.h).
  std::vector<Vector6d> differences, difference_sigmas;
  std::string first_failure;  // the first half's error, when some failed
};

/// The halves of split_check as sample indices, one split per call: random halves
/// (the first n / 2 of a fresh shuffle of the last order, in that order, and the
/// rest), or whole runs of run_length consecutive samples cut at a random phase and
/// drawn until the first half holds n / 2 or more (each half ascending).
class HalfSplitter {
 public:
  HalfSplitter(int n, int run_length);
  std::array<std::vector<int>, 2> next(std::mt19937_64& rng);

 private:
  int n_, run_length_;
  std::vector<int> order_;
};

using SolveSamples = std::function<Calibration(const SampleSet&)>;

/// `splits` random halves (seeded) of `samples`, each solved by `solve`; with
/// run_length k > 1, each half is made of whole runs of k consecutive samples (in
/// the order they were taken), cut at a random phase and drawn at random until the
/// first half holds n / 2 or more. Throws HandEyeError(TooFewMotions) for fewer than
/// min_samples_for_runs(run_length) samples.
SplitCheck split_check(const SampleSet& samples, const SolveSamples& solve, int splits, unsigned seed,
                       int run_length = 1);
/// 8 for random halves; for runs of k, four runs and halves of 4 or more: max(4 k, 2 k + 5).
int min_samples_for_runs(int run_length);

// ---------------------------------------------------------------- calibrated to the session
//
// "Honest: 6" holds for large halves with a known noise. With 4-25 samples per
// half and the noise estimated from them, an honest covariance's mean split-half
// NEES is 6-7 with a long tail, and it depends on the poses: a reading of 8 may be
// chance. The reference is what an honest covariance gives on this very session,
// by a parametric bootstrap: sessions simulated at the session's own robot poses,
// each view drawn about what the fitted X and Y predict with its own fitted
// residual covariance S_i (joint_estimator.h, residual_covariances), each solved
// and split exactly as the session (the same solve, the same halves).

/// How many simulated sessions, and how many of the session's splits each solves.
struct HonestyOptions {
  int splits = 200;             // the session's random halves
  /// Simulated sessions; beyond `full_replicates_up_to` samples, fewer, in proportion
  /// (at least 20), so that a long session's check costs about what one of that
  /// size does: its halves are large, and the reference narrow.
  int replicates = 100;
  int full_replicates_up_to = 60;
  /// Each simulated session is split by the first this many of the session's
  /// halves: its mean NEES has the same expectation as with all of them, and the
  /// band is corrected for the extra spread of a mean over fewer splits.
  int replicate_splits = 40;
  /// The second look, for an error shared by neighbouring poses (a robot's kinematic
  /// error, drift): halves of runs of k consecutive samples (split_check), its
  /// reference split the same way, each simulated session by max(20,
  /// replicate_splits / 2) of them (20 keeps the trimmed mean's 5% cut). 0 (auto):
  /// from 16 samples, k = n / 8 within [2, 4]; 1: random halves alone; k >= 2: this
  /// k, from min_samples_for_runs(k). The verdict is the worse of the two looks (honesty_check).
  int run_length = 0;
  /// The halves are solved under the session's own noise: each sample's fitted
  /// residual covariance S_i held (with_held_noise, solve_with_held_noise), and each
  /// simulated session's halves under the S_i of its own fit of all its samples by
  /// `solve`. The check then judges the noise model the session's covariance was
  /// computed with. A half that fits its noise again from its n/2 samples judges a
  /// noisier estimate than the user gets, and on real errors shared by neighbouring
  /// poses its fits go astray beyond what the reference's draws do (docs/evidence.md).
  /// false, or `fitted` not the joint estimator's (its halves must be its own
  /// estimator's): each half is solved by `solve`, its noise fitted again.
  bool hold_noise = true;
  unsigned seed = 1;
};

/// The reference distribution of the mean split-half NEES.
struct SplitCheckReference {
  int replicates = 0;           // simulated sessions whose check gave a mean
  int failed = 0;               // simulated sessions that could not be fitted in full, or whose splits all failed
  int splits = 0;               // halves per simulated session
  double mean = 0.0;            // of their trimmed means (SplitCheck): what an honest covariance averages here
  /// The 5% and 95% quantiles of an honest session's mean over the session's own
  /// number of splits: the replicates' means, their spread corrected from
  /// `splits` to the session's (the within-session part of the variance of a mean
  /// of m splits is v / m, v the NEES's variance across one session's splits).
  double low = 0.0, high = 0.0;
  std::vector<double> means;    // each replicate's trimmed mean NEES
};


/// The session's split-half check against its reference, and what follows.
struct HonestyCheck {
  SplitCheck observed;
  SplitCheckReference reference;
  double ratio = 1.0;  // observed.trimmed_mean_nees / reference.mean: the covariance is this many times too small
  /// Overconfident: above the reference's 95% quantile; underconfident: below its 5%.
  Honesty verdict = Honesty::Honest;
  /// What the covariance should be multiplied by to be honest here: the ratio when
  /// overconfident, else 1 (an underconfident covariance is kept: it errs safe).
  double inflation = 1.0;
  /// Why there is no verdict ("no reference: ..."); empty when it ran (io::honesty_text
  /// words a verdict).
  std::string text;
  /// Whether there is a verdict: the session had solved splits and the reference at
  /// least two simulated sessions (the halves of 4 samples a small session leaves
  /// may all fail to solve).
  bool ran() const { return reference.replicates >= 2 && observed.splits > 0; }
  /// Both looks, whichever decided (observed.run_length says which did): the random
  /// halves' ratio, and the runs' length (0: not run), ratio and verdict; why the runs
  /// did not run when they were asked for.
  double random_ratio = 1.0;
  Honesty random_verdict = Honesty::Honest;
  int runs_length = 0;
  double runs_ratio = 1.0;
  Honesty runs_verdict = Honesty::Honest;
  std::string runs_note;
};

/// The runs' length HonestyOptions::run_length asks of n samples (0: no runs), and
/// why not when it asks for runs that n cannot hold.
int runs_length_for(const HonestyOptions& options, int n, std::string* why_not = nullptr);

/// The split-half check of `samples` (as split_check) and its parametric-bootstrap
/// reference from `fitted` (the calibration of all of `samples` by `solve`):
/// options.replicates simulated sessions, each split by the session's own halves;
/// then the same with halves of runs (options.run_length). The runs decide when they
/// read overconfident and above the random halves' ratio; otherwise the random
/// halves do. Throws HandEyeError(TooFewMotions) for fewer than 8 samples.
HonestyCheck honesty_check(const SampleSet& samples, const Calibration& fitted, const SolveSamples& solve,
                           const HonestyOptions& options = {});

/// A SplitCheck's splits, mean and trimmed mean from its `nees`; its 3-dof blocks'
/// sums (mean_nees_translation, mean_nees_rotation) become their means.
void summarise_splits(SplitCheck& check);
/// One look judged: the session's split check `observed` against `replicates`, the
/// simulated sessions' checks, each by the session's first `replicate_splits`
/// halves (`failed` sessions that could not be fitted). The reference's mean, its
/// band corrected to the session's number of splits, the ratio and the verdict.
/// What honesty_check does per look, and the shared robot error's check
/// (shared_robot_error.h) with halves of its own.
HonestyCheck judge_look(const SplitCheck& observed, const std::vector<SplitCheck>& replicates, int failed,
                        int replicate_splits);
/// The two looks as one check: the runs (of `run_length`; 0 or no `runs`: random
/// halves alone) decide when they read overconfident beyond the random halves.
HonestyCheck worse_look(HonestyCheck random, const HonestyCheck* runs, int run_length);

/// `samples` with each sample's noise held at its residual covariance S[i] (its
/// camera noise S_i, its robot noise zero; corners dropped): what
/// solve_with_held_noise solves a half of.
SampleSet with_held_noise(const SampleSet& samples, const std::vector<Matrix6d>& S);
/// The joint estimate under the samples' stated noise taken as true: no noise
/// estimated, no robust mode (the halves of the check with the noise held).
Calibration solve_with_held_noise(const SampleSet& half);

/// What `check` says, recorded in `calibration` (Calibration::honesty); with
/// `inflate`, an overconfident verdict multiplies X's, Y's and their cross
/// covariance by check.inflation (the model's X covariance is kept in the record).
/// `words`: the check's in words (io::honesty_text), for the record.
void record_honesty(Calibration& calibration, const HonestyCheck& check, bool inflate, const std::string& words);

/// The session simulated once at its own robot poses (the reference's replicate):
/// each view P_i = exp(eps_i) P_hat_i, eps_i ~ N(0, S_i) (left perturbation, ROS
/// order), P_hat_i what `fitted`'s X and Y predict (Y the loops' mean when it has
/// none). Each sample keeps its stated noise; its corners are dropped (they belong
/// to the real view).
SampleSet simulate_like(const SampleSet& samples, const Calibration& fitted, const std::vector<Matrix6d>& residual_covariances,
                        std::mt19937_64& rng);

}  // namespace handeye
