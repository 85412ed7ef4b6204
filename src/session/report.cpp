#include "handeye_covariance/session/report.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/core/python_script.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/io/honesty_text.h"
#include "handeye_covariance/io/summary.h"
#include "handeye_covariance/io/warning_text.h"
#include "handeye_covariance/io/yaml_io.h"


namespace handeye {

namespace {

const char* const kAxisNames[6] = {"x", "y", "z", "rx", "ry", "rz"};

/// "1.8 mm" or "0.12 deg" for ROS axis k's value (m or rad).
std::string axis_value(int k, double value) {
  return k < 3 ? number_text(millimetres(value), 2) + " mm" : number_text(degrees(value), 2) + " deg";
}

/// "1009", "12", "4.9", "0.31": whole numbers from 10 on (no "1e+03" for people).
std::string readable(double value) {
  return std::abs(value) >= 10.0 ? std::to_string(std::llround(value)) : number_text(value, 2);
}

/// The sigmas beyond which a sample is called out: the options' threshold, scaled
/// as the outlier gate scales (outliers.h residual_scale) by the kept samples. When
/// every residual is larger than the detections' stated noise says (real detectors
/// understate it), a session whose samples are all alike would otherwise have them
/// all called out.
double advice_threshold(const CalibrationReport& r, const ReportOptions& options) {
  std::vector<double> squared;
  for (std::size_t i = 0; i < r.fits.size(); ++i) {
    if (!rejection_of(r.calibration, static_cast<int>(i))) squared.push_back(r.fits[i].sigmas * r.fits[i].sigmas);
  }
  return options.advice_sigma * std::sqrt(residual_scale(squared));
}

void leave_one_out(const CalibrationSession& session, const SessionSnapshot& kept, CalibrationReport& r) {
  const Eigen::Isometry3d& X = r.calibration.T_parent_camera;
  std::vector<Vector6d> d;
  for (std::size_t skip = 0; skip < kept.samples.samples.size(); ++skip) {
    SessionSnapshot without = kept;
    without.samples.samples.erase(without.samples.samples.begin() + static_cast<std::ptrdiff_t>(skip));
    try {
      d.push_back(pose_error(session.calibrate_decided(without).T_parent_camera, X));
    } catch (const HandEyeError&) {
      ++r.leave_one_out_failed;
    }
  }
  r.leave_one_out_solved = static_cast<int>(d.size());
  r.leave_one_out_sigma = jackknife_sigma(d);
}

void split_half(const CalibrationSession& session, const SessionSnapshot& kept, const ReportOptions& options,
                CalibrationReport& r) {
  if (options.splits <= 0) {
    r.split_problem = "left out (splits: 0)";
    return;
  }
  HonestyOptions honesty = session.settings().honesty;
  honesty.splits = options.splits;
  honesty.replicates = options.reference_sessions;
  if (options.run_length >= 0) honesty.run_length = options.run_length;
  honesty.seed = options.seed;
  try {
    // The reference simulates from the calibration's X, Y and noise model (an
    // inflation, when the calibration carries one, does not enter it).
    r.honesty = session.honesty_check(kept, r.calibration, honesty);
  } catch (const HandEyeError& e) {
    r.split_problem = e.what();
    return;
  }
  // The calibration records the verdict unless its /calibrate ran the check already
  // (the same seed and splits: the same figures), and, where it uses the shared robot
  // error's model, the per-view model's own check beside it (a check of new views
  // predicts about the per-view X and Y).
  if (!r.calibration.honesty || !r.calibration.honesty->ran()) {
    record_honesty(r.calibration, r.honesty, session.settings().inflate_when_overconfident, io::honesty_text(r.honesty));
    session.check_per_view(kept, r.calibration, honesty);
  }
  if (r.honesty.observed.splits == 0) r.split_problem = "no split could be solved: " + r.honesty.observed.first_failure;
}

void rotation_axes(const SampleSet& kept, const ReportOptions& options, CalibrationReport& r) {
  // M from every pair; the figure gets at most max_rotation_axes of them, evenly spread.
  const std::size_t n = kept.samples.size();
  const std::size_t pairs = n * (n - std::min<std::size_t>(n, 1)) / 2;
  const std::size_t most = std::max<std::size_t>(1, options.max_rotation_axes);
  const std::size_t stride = std::max<std::size_t>(1, (pairs + most - 1) / most);
  std::size_t pair = 0;
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a + 1; b < n; ++b, ++pair) {
      const PoseSample& i = kept.samples[a];
      const PoseSample& j = kept.samples[b];
      // B = P_i P_j^-1: the camera-side motion of AX = XB, its axis in camera i's frame.
      const Eigen::Vector3d w = so3::log(i.T_camera_pattern.linear() * j.T_camera_pattern.linear().transpose());
      const double angle = w.norm();
      M += w * w.transpose();
      if (angle < 1e-9 || pair % stride != 0) continue;
      r.rotation_axes.push_back({w / angle, angle});
    }
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(M);
  r.turning = eig.eigenvalues().cwiseMax(0.0);
  r.turning_axes = eig.eigenvectors();
}

void advise(const ReportOptions& options, CalibrationReport& r) {
  std::vector<std::string>& advice = r.advice;
  // Samples far off, worst first: rejected or not, the operator should remove them.
  std::vector<int> off;
  for (int i = 0; i < static_cast<int>(r.fits.size()); ++i) {
    if (r.fits[static_cast<std::size_t>(i)].sigmas > r.advice_sigma) off.push_back(i);
  }
  std::sort(off.begin(), off.end(), [&](int a, int b) { return r.fits[a].sigmas > r.fits[b].sigmas; });
  for (int i : off) {
    const SampleFit& f = r.fits[static_cast<std::size_t>(i)];
    const Calibration::Rejected* rejected = rejection_of(r.calibration, i);
    std::string text = "sample " + std::to_string(i) + " is " + readable(f.sigmas) + " sigma off (" +
                       readable(millimetres(f.translation)) + " mm, " + readable(degrees(f.rotation)) + " deg): remove it";
    text += rejected
                ? " (X already leaves it out: " + io::rejected_text(*rejected) + ")"
                : " (X still uses it; the panel's Remove selected or /remove_sample " + std::to_string(i) + ")";
    advice.push_back(text);
  }
  // Directions the motions hardly turned about.
  if (r.turning(2) > 0.0 && r.turning(0) < options.weak_axis_share * r.turning(2)) {
    advice.push_back("little rotation about " + camera_axis_name(r.turning_axes.col(0)) + " (" +
                     number_text(100.0 * r.turning(0) / r.turning(2), 2) +
                     "% of the best-turned direction): add views turned about it");
  }
  // The checks against the predicted sigma.
  for (int k = 0; k < 6; ++k) {
    const double predicted = r.predicted_sigma(k);
    if (!(predicted > 0.0)) continue;
    const double loo = r.leave_one_out_sigma(k) / predicted, split = r.split_half_sigma(k) / predicted;
    const double worst = std::max(loo, split);
    if (worst > options.ratio_advice) {
      advice.push_back(std::string("X's ") + kAxisNames[k] + " moves " + number_text(worst, 2) +
                       " times its predicted 1 sigma (" + axis_value(k, predicted) + ") under " +
                       (loo >= split ? "leave-one-out" : "split-half") +
                       ": the covariance is overconfident there; look for systematic errors (camera intrinsics, "
                       "robot kinematics, a loose mount) or calibrate with robust: on");
    }
  }
  const HonestyCheck& h = r.honesty;
  if (h.ran() && h.verdict != Honesty::Honest) {
    const std::string figures = "split-half NEES " + number_text(h.observed.trimmed_mean_nees, 3) + " against " +
                                number_text(h.reference.mean, 3) + " (5-95% " + number_text(h.reference.low, 3) + " to " +
                                number_text(h.reference.high, 3) + ") for an honest covariance on these poses";
    if (h.verdict == Honesty::Overconfident) {
      const bool inflated = r.calibration.honesty && r.calibration.honesty->inflation > 1.0;
      advice.push_back("the covariance is " + io::honesty_text(h) + " (" + figures + "): the noise model does not explain this session" +
                       (inflated ? "; the calibration's covariance is inflated by that factor" : "") +
                       "; look for a systematic error (camera intrinsics, robot kinematics, a loose mount)");
    } else {
      advice.push_back("the covariance is " + io::honesty_text(h) + " (" + figures + "): it errs on the safe side; the stated noise may "
                       "be too large");
    }
  }
  if (!r.split_problem.empty() && options.splits > 0) {
    advice.push_back("no split-half check: " + r.split_problem);
  }
  if (r.target_object_sigma > 0.0 && r.object_sigma > r.target_object_sigma) {
    advice.push_back("an object at " + number_text(r.working_distance, 2) + " m is known to " +
                     number_text(millimetres(r.object_sigma), 2) + " mm (1 sigma, worst axis), the target is " +
                     number_text(millimetres(r.target_object_sigma), 2) +
                     " mm: take more samples at the suggested poses (the panel's Suggest pose, or handeye suggest)");
  } else if (!r.target_not_reached.empty()) {
    advice.push_back(r.target_not_reached);
  }
  for (const Warning& w : r.calibration.warnings) {
    if (w.kind != Warning::Kind::OutliersRejected) advice.push_back("the estimator warns: " + io::warning_text(w));  // said above
  }
  if (advice.empty()) {
    advice.push_back("nothing to mend: every sample is within " + number_text(r.advice_sigma, 3) +
                     " sigma, the motions turn about every axis, and leave-one-out and split-half agree with the "
                     "predicted 1 sigma");
  }
}

}  // namespace

ReportFiles write_report(const std::string& directory, const CalibrationReport& report, const SampleSet& samples,
                         const std::string& source) {
  const std::string dir = directory.empty() ? std::string(".") : directory;
  const io::ResultContext context = io::context_of(samples);
  io::write_file_atomically(dir + "/calibration.yaml", io::format_result(report.calibration, context));
  io::write_file_atomically(dir + "/report.yaml", io::format_report(report, context, source));
  ReportFiles files;
  files.directory = dir;
  // The figures are matplotlib's (scripts/report.py).
  const std::string problem = run_python_script(HANDEYE_REPORT_SCRIPT, {dir});
  if (!problem.empty()) {
    files.problem = problem + " (needs Debian's python3-matplotlib): the YAML files stand, the figures and the page are missing";
  } else {
    files.html = dir + "/report.html";
  }
  return files;
}

Vector6d jackknife_sigma(const std::vector<Vector6d>& leave_one_out) {
  if (leave_one_out.size() < 3) return Vector6d::Zero();
  const double n = static_cast<double>(leave_one_out.size());
  Vector6d mean = Vector6d::Zero(), sum = Vector6d::Zero();
  for (const Vector6d& d : leave_one_out) mean += d / n;
  for (const Vector6d& d : leave_one_out) sum += (d - mean).cwiseAbs2();
  return ((n - 1.0) / n * sum).cwiseSqrt();
}

std::string camera_axis_name(const Eigen::Vector3d& direction) {
  const Eigen::Vector3d u = direction.normalized();
  const char* names[3] = {"the camera's x (image right)", "the camera's y (image down)",
                          "the camera's z (optical axis)"};
  for (int k = 0; k < 3; ++k) {
    if (std::abs(u(k)) > 0.9) return names[k];
  }
  const Eigen::Vector3d v = u.x() < 0.0 ? Eigen::Vector3d(-u) : u;
  char text[96];
  std::snprintf(text, sizeof text, "the camera-frame direction (%.2f, %.2f, %.2f)", v.x(), v.y(), v.z());
  return text;
}

CalibrationReport make_report(const CalibrationSession& session, const SessionSnapshot& snapshot,
                              const ReportOptions& options) {
  return make_report(session, snapshot, session.calibrate_modelled(snapshot), options);
}

CalibrationReport make_report(const CalibrationSession& session, const SessionSnapshot& snapshot,
                              Calibration calibration, const ReportOptions& options) {
  CalibrationReport r;
  r.calibration = std::move(calibration);
  const SampleSet as_decided = session.decided(snapshot.samples, r.calibration);  // a symmetric target's views as turned
  r.fits = sample_fits(as_decided, r.calibration);
  r.advice_sigma = advice_threshold(r, options);
  const SessionSnapshot kept{snapshot.generation, without_rejected(as_decided, r.calibration)};
  // The split-half check first: it may inflate the calibration's covariance, the one predicted below.
  split_half(session, kept, options, r);
  r.predicted_sigma = r.calibration.pose_covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  if (r.honesty.observed.splits > 0) {  // the splits' per-axis spread against the predicted sigma
    Vector6d mean_square = Vector6d::Zero();
    for (std::size_t s = 0; s < r.honesty.observed.differences.size(); ++s) {
      const Vector6d z = r.honesty.observed.differences[s].cwiseQuotient(r.honesty.observed.difference_sigmas[s].cwiseMax(1e-300));
      mean_square += z.cwiseAbs2() / static_cast<double>(r.honesty.observed.differences.size());
    }
    // The halves' covariances are the model's: scaled as the calibration's was, when inflated.
    const double inflation = r.calibration.honesty ? r.calibration.honesty->inflation : 1.0;
    r.split_half_sigma = r.predicted_sigma.cwiseProduct(mean_square.cwiseSqrt()) / std::sqrt(inflation);
  }
  leave_one_out(session, kept, r);
  rotation_axes(kept.samples, options, r);
  r.working_distance = session.settings().suggest.working_distance;
  r.target_object_sigma = session.settings().target_object_sigma;
  const TargetProgress progress = target_progress(r.calibration, r.target_object_sigma, r.working_distance);
  r.object_sigma = progress.object_sigma;
  r.target_reached = progress.reached;
  r.target_not_reached = progress.why_not;
  advise(options, r);
  return r;
}

}  // namespace handeye
