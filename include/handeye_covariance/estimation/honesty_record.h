// The honesty section of a calibration: what the split-half check (split_check.h,
// honesty_check) found on the session and applied, as the result file, the node and
// the summary carry it. Its fields are described once (core/fields.h).
#pragma once

#include <string>

#include "handeye_covariance/core/fields.h"
#include "handeye_covariance/core/lie.h"

namespace handeye {

/// The split-half check's verdict on a covariance, or that it did not run.
enum class Honesty { Honest, Overconfident, Underconfident, NotRun };
const char* to_string(Honesty honesty);  // "honest" / "overconfident" / "underconfident" / "not run"
/// The verdict named by to_string; throws HandEyeError(MalformedFile) naming the four.
Honesty from_string(const std::string& name, Honesty);

/// Overconfident beyond its band, the calibration's covariances (X's, Y's, their cross
/// block) are the model's times `inflation`, and the model's own X covariance is kept
/// here; otherwise inflation is 1.
struct HonestyRecord {
  Honesty verdict = Honesty::NotRun;
  std::string text;                // the plain verdict ("overconfident x1.6: sigma is about 1.3x too small"), or why not run
  int splits = 0, half_size = 0;   // the deciding look's halves, the smaller of this many samples
  int run_length = 1;              // which look decided: 1 random halves, k halves of runs of k consecutive samples
  double split_half_nees = 0.0;    // the middle 90% of the splits' mean NEES of X_a - X_b
  /// Simulated honest sessions at the same poses: how many, their mean NEES, its 5% and 95%.
  struct Reference {
    int sessions = 0;
    double mean = 0.0, low = 0.0, high = 0.0;
    template <class Self, class Visit>
    static void fields(Self& s, Visit&& visit) {
      visit("sessions", s.sessions);
      visit("mean", s.mean);
      visit("low", s.low);
      visit("high", s.high);
    }
  };
  Reference reference;
  double ratio = 1.0;              // split_half_nees / reference.mean
  double random_ratio = 1.0;       // the random halves' ratio
  /// The runs' look: halves of runs of `length` consecutive samples (0: not run) and its ratio.
  struct Runs {
    int length = 0;
    double ratio = 1.0;
    template <class Self, class Visit>
    static void fields(Self& s, Visit&& visit) {
      visit("length", s.length);
      visit("ratio", s.ratio);
    }
  };
  Runs runs;
  std::string runs_note;           // why the runs' look did not run
  double inflation = 1.0;          // applied to the covariances
  Matrix6d model_pose_covariance = Matrix6d::Zero();  // X's, as the noise model gave it

  bool ran() const { return verdict != Honesty::NotRun; }

  template <class Self, class Visit>
  static void fields(Self& s, Visit&& visit) {
    // Conditions inline: a reader evaluates each on the fields read before it.
    visit("verdict", s.verdict);
    visit("text", s.text);
    visit("splits", s.splits, Only{s.ran()});
    visit("half_size", s.half_size, Only{s.ran()});
    visit("run_length", s.run_length, Only{s.ran() && s.run_length > 1, true});  // the runs decided (absent: 1)
    visit("split_half_nees", s.split_half_nees, Only{s.ran()});
    visit("reference", s.reference, Only{s.ran()});
    visit("ratio", s.ratio, Only{s.ran()});
    visit("random_halves_ratio", s.random_ratio, Only{s.ran()});
    visit("runs", s.runs, Only{s.ran() && s.runs.length > 0, true});
    visit("runs_not_run", s.runs_note, Only{s.ran() && s.runs.length == 0 && !s.runs_note.empty(), true});
    visit("inflation", s.inflation, Only{s.ran()});
    visit("model_covariance", s.model_pose_covariance, Only{s.ran() && s.inflation > 1.0});  // the one above is inflated
  }
};

}  // namespace handeye
