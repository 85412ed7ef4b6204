// Result, report, check and pose files, stored calibrations (result_file.h).
#include "handeye_covariance/io/result_file.h"

#include <algorithm>
#include <cmath>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/core/validation.h"
#include "handeye_covariance/estimation/shared_robot_error.h"
#include "handeye_covariance/io/check_text.h"
#include "handeye_covariance/io/files.h"
#include "handeye_covariance/io/honesty_text.h"
#include "handeye_covariance/io/noise_text.h"
#include "handeye_covariance/io/warning_text.h"
#include "sections.h"
#include "yaml_primitives.h"

namespace handeye {
namespace io {

using namespace detail;  // the shared readers and writers (yaml_primitives.h)
using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

// ---------------------------------------------------------------- results

ResultContext context_of(const SampleSet& samples) {
  ResultContext c;
  c.setup = samples.rig.setup;
  c.parent = samples.rig.camera_parent_frame();
  c.child = samples.rig.frames.camera;
  c.pattern_parent = samples.rig.pattern_parent_frame();
  c.pattern_child = samples.rig.frames.pattern;
  return c;
}

ResultContext context_of(const MotionSet&) { return {}; }

namespace {
/// The keys every result file has: frames, X, its covariance, the sample count
/// and easy_handeye's `transformation` block.
/// `covariance: {rotation, translation, pose}` of a pose.
void emit_pose_covariance(YAML::Emitter& out, const Matrix6d& covariance) {
  out << YAML::Key << "covariance" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "rotation" << YAML::Value;
  emit_covariance3(out, covariance.bottomRightCorner<3, 3>());
  out << YAML::Key << "translation" << YAML::Value;
  emit_covariance3(out, covariance.topLeftCorner<3, 3>());
  out << YAML::Key << "pose" << YAML::Value;
  const auto pose = to_row_major_6x6(covariance);
  emit_numbers(out, pose.data(), pose.size());
  out << YAML::EndMap;
}

void emit_result_head(YAML::Emitter& out, const PoseWithCovariance& X, int samples_used,
                      const ResultContext& context) {
  if (context.setup) out << YAML::Key << "setup" << YAML::Value << to_string(*context.setup);
  out << YAML::Key << "parent" << YAML::Value << context.parent;
  out << YAML::Key << "child" << YAML::Value << context.child;
  emit_pose(out, X.pose);
  emit_pose_covariance(out, X.covariance);
  out << YAML::Key << "samples_used" << YAML::Value << samples_used;

  Eigen::Quaterniond q(X.pose.linear());
  if (q.w() < 0) q.coeffs() *= -1.0;
  out << YAML::Key << "transformation" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "x" << YAML::Value << X.pose.translation().x();
  out << YAML::Key << "y" << YAML::Value << X.pose.translation().y();
  out << YAML::Key << "z" << YAML::Value << X.pose.translation().z();
  out << YAML::Key << "qx" << YAML::Value << q.x() << YAML::Key << "qy" << YAML::Value << q.y();
  out << YAML::Key << "qz" << YAML::Value << q.z() << YAML::Key << "qw" << YAML::Value << q.w();
  out << YAML::EndMap;
}
}  // namespace

std::string format_pose_file(const PoseWithCovariance& X, const ResultContext& context) {
  YAML::Emitter out;
  new_emitter(out) << YAML::BeginMap;
  emit_result_head(out, X, 0, context);
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

std::string format_report(const CalibrationReport& report, const ResultContext& context, const std::string& source) {
  // Humans read this file: mm and degrees, in ROS order (x, y, z, rx, ry, rz).
  const auto human = [](const Vector6d& sigma) {
    std::vector<double> v(6);
    for (int k = 0; k < 6; ++k) v[static_cast<std::size_t>(k)] = sigma(k) * (k < 3 ? kMillimetresPerMetre : kDegreesPerRadian);
    return v;
  };
  const auto emit_list = [](YAML::Emitter& out, const std::vector<double>& v) { emit_numbers(out, v.data(), v.size()); };
  YAML::Emitter out;
  new_emitter(out) << YAML::BeginMap;
  out << YAML::Key << "source" << YAML::Value << source;
  if (context.setup) out << YAML::Key << "setup" << YAML::Value << to_string(*context.setup);
  out << YAML::Key << "frames" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "parent" << YAML::Value
      << context.parent << YAML::Key << "camera" << YAML::Value << context.child << YAML::EndMap;
  out << YAML::Key << "method" << YAML::Value << to_string(report.calibration.method);
  out << YAML::Key << "advice_sigma" << YAML::Value << report.advice_sigma;
  out << YAML::Key << "object" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "working_distance_m"
      << YAML::Value << report.working_distance << YAML::Key << "sigma_mm" << YAML::Value << millimetres(report.object_sigma)
      << YAML::Key << "target_mm" << YAML::Value << millimetres(report.target_object_sigma) << YAML::Key << "reached"
      << YAML::Value << report.target_reached << YAML::EndMap;

  out << YAML::Key << "samples" << YAML::Value << YAML::BeginSeq;
  for (std::size_t i = 0; i < report.fits.size(); ++i) {
    const SampleFit& f = report.fits[i];
    const Calibration::Rejected* rejected = rejection_of(report.calibration, static_cast<int>(i));
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "index" << YAML::Value << i << YAML::Key << "residual_mm"
        << YAML::Value << millimetres(f.translation) << YAML::Key << "residual_deg" << YAML::Value
        << degrees(f.rotation) << YAML::Key << "sigma" << YAML::Value << f.sigmas << YAML::Key << "rejected"
        << YAML::Value << (rejected != nullptr);
    if (rejected) out << YAML::Key << "reason" << YAML::Value << rejected_text(*rejected);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;

  out << YAML::Key << "checks" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "units" << YAML::Value << "mm, mm, mm, deg, deg, deg (x, y, z, rx, ry, rz)";
  out << YAML::Key << "predicted_sigma" << YAML::Value;
  emit_list(out, human(report.predicted_sigma));
  out << YAML::Key << "leave_one_out_sigma" << YAML::Value;
  emit_list(out, human(report.leave_one_out_sigma));
  out << YAML::Key << "leave_one_out_solved" << YAML::Value << report.leave_one_out_solved;
  out << YAML::Key << "leave_one_out_failed" << YAML::Value << report.leave_one_out_failed;
  out << YAML::Key << "split_half_sigma" << YAML::Value;
  emit_list(out, human(report.split_half_sigma));
  out << YAML::Key << "split_half_splits" << YAML::Value << report.honesty.observed.splits;
  out << YAML::Key << "split_half_size" << YAML::Value << report.honesty.observed.half_size;
  if (report.honesty.observed.run_length > 1) out << YAML::Key << "split_half_runs" << YAML::Value << report.honesty.observed.run_length;
  out << YAML::Key << "split_half_nees" << YAML::Value << report.honesty.observed.mean_nees;
  out << YAML::Key << "split_half_nees_translation" << YAML::Value << report.honesty.observed.mean_nees_translation;
  out << YAML::Key << "split_half_nees_rotation" << YAML::Value << report.honesty.observed.mean_nees_rotation;
  // The calibrated check: the middle 90% of the splits against an honest covariance on these poses.
  const HonestyCheck& h = report.honesty;
  out << YAML::Key << "split_half_nees_middle" << YAML::Value << h.observed.trimmed_mean_nees;
  out << YAML::Key << "honest_nees" << YAML::Value << h.reference.mean;
  out << YAML::Key << "honest_nees_band" << YAML::Value << YAML::Flow << YAML::BeginSeq << h.reference.low << h.reference.high
      << YAML::EndSeq;
  out << YAML::Key << "honest_sessions" << YAML::Value << h.reference.replicates;
  out << YAML::Key << "honesty_ratio" << YAML::Value << h.ratio;
  out << YAML::Key << "honesty_random_halves_ratio" << YAML::Value << h.random_ratio;
  if (h.runs_length > 0) {
    out << YAML::Key << "honesty_runs" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "length" << YAML::Value
        << h.runs_length << YAML::Key << "ratio" << YAML::Value << h.runs_ratio << YAML::Key << "verdict" << YAML::Value
        << to_string(h.runs_verdict) << YAML::EndMap;
  }
  out << YAML::Key << "honesty" << YAML::Value << to_string(h.ran() ? h.verdict : Honesty::NotRun);
  const std::string words = honesty_text(h);
  out << YAML::Key << "honesty_text" << YAML::Value << (words.empty() ? std::string("not run") : words);
  if (!report.split_problem.empty()) out << YAML::Key << "split_half_problem" << YAML::Value << report.split_problem;
  out << YAML::EndMap;

  out << YAML::Key << "rotation_axes" << YAML::Value << YAML::BeginSeq;  // camera frame: x, y, z, angle (deg)
  for (const MotionAxis& m : report.rotation_axes) {
    emit_list(out, {m.axis.x(), m.axis.y(), m.axis.z(), degrees(m.angle)});
  }
  out << YAML::EndSeq;
  out << YAML::Key << "turning" << YAML::Value << YAML::BeginMap;  // eigen-decomposition of sum theta^2 a a^T, ascending
  out << YAML::Key << "eigenvalues_rad2" << YAML::Value;
  emit_list(out, {report.turning(0), report.turning(1), report.turning(2)});
  out << YAML::Key << "axes" << YAML::Value << YAML::BeginSeq;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d a = report.turning_axes.col(k);
    emit_list(out, {a.x(), a.y(), a.z()});
  }
  out << YAML::EndSeq << YAML::EndMap;

  out << YAML::Key << "advice" << YAML::Value << YAML::BeginSeq;
  for (const std::string& a : report.advice) out << a;
  out << YAML::EndSeq << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

std::string format_result(const Calibration& calibration, const ResultContext& context) {
  YAML::Emitter out;
  new_emitter(out) << YAML::BeginMap;
  emit_result_head(out, {calibration.T_parent_camera, calibration.pose_covariance}, calibration.samples_used, context);
  out << YAML::Key << "motions_used" << YAML::Value << calibration.motions_used;
  out << YAML::Key << "method" << YAML::Value << to_string(calibration.method);
  if (calibration.pattern) {  // Y with the same keys as X, and Cov(X, Y)
    out << YAML::Key << "pattern" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "parent" << YAML::Value << context.pattern_parent;
    out << YAML::Key << "child" << YAML::Value << context.pattern_child;
    emit_pose(out, calibration.pattern->pose);
    emit_pose_covariance(out, calibration.pattern->covariance);
    out << YAML::EndMap;
    out << YAML::Key << "cross_covariance" << YAML::Value;  // 6x6, X's ROS order in rows, Y's in columns
    const auto cross = to_row_major_6x6(calibration.cross_covariance);
    emit_numbers(out, cross.data(), cross.size());
  }
  if (calibration.corner_fit) {  // method corners: the reprojection fit, per image
    out << YAML::Key << "corners" << YAML::Value;
    emit_section(out, *calibration.corner_fit, false);
  }

  const bool samples = context.setup.has_value();
  out << YAML::Key << "noise" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "origin" << YAML::Value
      << to_string(calibration.noise_origin);
  out << YAML::Key << "model" << YAML::Value;
  emit_noise(out, calibration.noise, samples ? "effector" : "A", samples ? "pattern" : "B");
  const std::string how = noise_model_text(calibration);
  if (!how.empty()) out << YAML::Key << "how" << YAML::Value << how;
  if (!calibration.noise_components.empty()) {  // joint: each number the residuals estimated, with its 1 sigma
    out << YAML::Key << "estimated" << YAML::Value;
    emit_value(out, calibration.noise_components);
  }
  if (!calibration.noise_candidates.empty()) {  // joint: the noise models compared by BIC
    out << YAML::Key << "candidates" << YAML::Value;
    emit_value(out, calibration.noise_candidates);
  }
  if (const auto& m = calibration.residual_noise) {
    // The residual covariance of any view (joint_estimator.h residual_covariances):
    // S = camera_scale Sigma_P + camera + view_scale G(P) + D (Sigma_E + robot) D^T.
    out << YAML::Key << "residual_model" << YAML::Value;
    emit_section(out, *m, false);
  }
  out << YAML::EndMap;
  if (!calibration.turned.empty()) {  // a symmetric target: the views turned to agree with the motion
    out << YAML::Key << "turned_samples" << YAML::Value << YAML::Flow << calibration.turned;
  }
  if (const auto& h = calibration.honesty) {  // the calibrated split-half check (split_check.h)
    out << YAML::Key << "honesty" << YAML::Value;
    emit_section(out, *h, false);
  }
  if (const auto& e = calibration.shared_robot_error) {  // a robot error shared by nearby poses, used or said
    out << YAML::Key << "shared_robot_error" << YAML::Value;
    emit_section(out, *e, false);
  }
  if (const auto& p = calibration.prediction) {  // leave-one-out: how well it predicts a view it has not seen
    out << YAML::Key << "prediction" << YAML::Value;
    emit_value(out, *p);
  }
  if (calibration.method == Method::Joint) {  // which tests ran on the residuals, and what they chose
    out << YAML::Key << "residual_checks" << YAML::Value;
    emit_value(out, calibration.residual_checks);
    out << YAML::Key << "robust" << YAML::Value << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "loss" << YAML::Value << to_string(calibration.loss);
    out << YAML::Key << "covariance" << YAML::Value << to_string(calibration.covariance_kind);
    out << YAML::Key << "downweighted" << YAML::Value << calibration.downweighted;
    out << YAML::Key << "covariance_inflation" << YAML::Value << calibration.covariance_inflation;
    out << YAML::Key << "pattern_covariance_inflation" << YAML::Value << calibration.pattern_covariance_inflation;
    out << YAML::EndMap;
  }

  out << YAML::Key << "solver" << YAML::Value << YAML::BeginMap;
  for (const auto& [name, stage] : {std::pair<const char*, const StageDiagnostics*>{"rotation", &calibration.rotation_stage},
                                    {"translation", &calibration.translation_stage}}) {
    out << YAML::Key << name << YAML::Value;
    emit_value(out, *stage);
  }
  out << YAML::EndMap;
  out << YAML::Key << "warnings" << YAML::Value << YAML::Flow << warning_texts(calibration.warnings);
  out << YAML::Key << "rejected" << YAML::Value << YAML::BeginSeq;  // outliers left out, indices into the input
  for (const Calibration::Rejected& r : calibration.rejected) {
    out << YAML::Flow << YAML::BeginMap;
    emit_fields(out, r);
    out << YAML::Key << "reason" << YAML::Value << rejected_text(r) << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

namespace {
void flatten(const YAML::Node& node, const std::string& path, std::vector<std::pair<std::string, std::string>>& out) {
  if (node.IsMap()) {
    for (const auto& entry : node) flatten(entry.second, (path.empty() ? "" : path + ".") + entry.first.Scalar(), out);
  } else if (node.IsSequence() && std::all_of(node.begin(), node.end(), [](const YAML::Node& e) { return e.IsScalar(); })) {
    YAML::Emitter text;
    new_emitter(text) << YAML::Flow << node;
    out.emplace_back(path, text.c_str());
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) flatten(node[i], path + "[" + std::to_string(i) + "]", out);
  } else {
    out.emplace_back(path, node.IsScalar() ? node.Scalar() : std::string());
  }
}
}  // namespace

std::vector<std::pair<std::string, std::string>> result_entries(const std::string& result_text) {
  std::vector<std::pair<std::string, std::string>> entries;
  flatten(YAML::Load(result_text), "", entries);
  return entries;
}

std::string format_check(const CalibrationCheck& check, const std::string& calibration_path) {
  YAML::Emitter out;
  new_emitter(out) << YAML::BeginMap;
  const auto emit_6 = [&](const char* key, const Vector6d& v) {
    out << YAML::Key << key << YAML::Value;
    emit_numbers(out, v.data(), 6);
  };
  const auto emit_6x6 = [&](const char* key, const Matrix6d& m) {
    const auto rows = to_row_major_6x6(m);
    out << YAML::Key << key << YAML::Value;
    emit_numbers(out, rows.data(), rows.size());
  };
  out << YAML::Key << "calibration" << YAML::Value << calibration_path;
  out << YAML::Key << "verdict" << YAML::Value << (check.changed ? "changed" : "consistent");
  out << YAML::Key << "p_value" << YAML::Value << check.p_value;
  out << YAML::Key << "alpha" << YAML::Value << check.alpha;
  out << YAML::Key << "text" << YAML::Value << check_verdict(check);
  if (check.changed) {
    out << YAML::Key << "changed" << YAML::Value << to_string(*check.change.what);
    const EstimatedChange::Delta& main = check.change.reported();
    emit_6("change", main.value);  // ROS order, m and rad: t = t_saved + change_t, R = exp(change_R) R_saved
    emit_6x6("change_covariance", main.covariance);
    if (check.change.what == ChangedPose::Both) {
      emit_6("pattern_change", check.change.Y_change->value);
      emit_6x6("pattern_change_covariance", check.change.Y_change->covariance);
    }
  }
  out << YAML::Key << "statistic" << YAML::Value << check.statistic;  // max(T_X, T_Y)
  out << YAML::Key << "chi2" << YAML::Value << check.chi2;
  out << YAML::Key << "dof" << YAML::Value << check.dof;
  out << YAML::Key << "chi2_p_value" << YAML::Value << check.chi2_p_value;
  out << YAML::Key << "hypotheses" << YAML::Value << YAML::BeginSeq;
  for (const EstimatedChange* h : {&check.X_alone, &check.Y_alone, &check.both}) {
    if (!h->what) continue;  // both: not identified from one or two views
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "changed" << YAML::Value << to_string(*h->what) << YAML::Key << "chi2_drop"
        << YAML::Value << h->chi2_drop << YAML::Key << "dof" << YAML::Value << h->dof << YAML::Key << "residual_chi2"
        << YAML::Value << h->residual_chi2 << YAML::Key << "residual_p_value" << YAML::Value << h->residual_p_value
        << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "views" << YAML::Value << YAML::BeginSeq;  // humans read these: mm and degrees
  for (std::size_t i = 0; i < check.views.size(); ++i) {
    const CheckedView& v = check.views[i];
    const bool left_out = std::find(check.left_out.begin(), check.left_out.end(), static_cast<int>(i)) != check.left_out.end();
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "left_out" << YAML::Value << left_out << YAML::Key << "translation_mm" << YAML::Value << millimetres(v.translation_error)
        << YAML::Key << "predicted_translation_mm" << YAML::Value << millimetres(v.predicted_translation_sigma) << YAML::Key
        << "rotation_deg" << YAML::Value << degrees(v.rotation_error) << YAML::Key << "predicted_rotation_deg"
        << YAML::Value << degrees(v.predicted_rotation_sigma) << YAML::Key << "sigma" << YAML::Value << v.mahalanobis
        << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "advice" << YAML::Value << YAML::BeginSeq;
  for (const std::string& a : check_advice(check)) out << a;
  out << YAML::EndSeq << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

namespace {
/// `covariance: {pose: [36]}` (ROS order, wins when present) or
/// `{rotation: [9], translation: [9]}` (no cross block).
Matrix6d read_pose_covariance(const YAML::Node& covariance, const Location& at) {
  if (!covariance.IsMap()) {
    throw HandEyeError(ErrorCode::MalformedFile, "`covariance` must be a map", at.str(),
                       "write covariance: {pose: [36 numbers]} or {rotation: [9], translation: [9]}");
  }
  Matrix6d c;
  if (covariance["pose"]) {
    c = from_row_major_6x6(as_numbers<36>(covariance["pose"], at / "pose", "6x6 covariance, ROS order"));
  } else {
    c = read_covariance(covariance, at).as_pose_covariance();
  }
  check_covariance(c, at.str());
  return c;
}
}  // namespace

PoseFile parse_pose_file(const std::string& text, const std::string& source) {
  const YAML::Node root = load(text, source);
  const Location top{source, ""};
  PoseFile file;
  if (root["parent"] && root["parent"].IsScalar()) file.parent = root["parent"].Scalar();
  if (root["child"] && root["child"].IsScalar()) file.child = root["child"].Scalar();
  file.value.pose = read_pose(root, top);
  if (const YAML::Node covariance = root["covariance"]) {
    file.value.covariance = read_pose_covariance(covariance, top / "covariance");
    file.has_covariance = true;
  }
  return file;
}

PoseFile read_pose_file(const std::string& path) { return parse_pose_file(read_file(path), path); }

namespace {
namespace {
/// What a shared robot error read from a file must hold beyond its keys: used only where
/// chosen, covariances that are covariances, a model a check can predict with, the
/// per-view inflation >= 1, and views (when given) that are some.
void check_shared_error(const Calibration::SharedError& e, const YAML::Node& node, const Location& at) {
  if (e.used && (!e.fitted() || !e.chosen)) {
    throw HandEyeError(ErrorCode::MalformedFile,
                       std::string("the shared robot error is used but ") + (e.fitted() ? "not chosen" : "not fitted"),
                       (at / "used").str(),
                       "a model is used only where its fit chose it: write `used: false`, or save the calibration again");
  }
  if (!e.fitted() || !e.chosen) return;
  require_predictable(e, at.str());
  check_covariance(e.X.covariance, (at / "X" / "covariance").str());
  check_covariance(e.per_view_estimate_covariance, (at / "per_view_covariance_under_it").str());
  if (!e.used) return;
  check_covariance(e.per_view_X.covariance, (at / "per_view_X" / "covariance").str());
  check_covariance(e.per_view_pattern.covariance, (at / "per_view_pattern" / "covariance").str());
  if (e.per_view_inflation < 1.0) {
    throw HandEyeError(ErrorCode::MalformedFile, "the per-view model's inflation must be >= 1, got " + number_text(e.per_view_inflation),
                       (at / "per_view_inflation").str(), "write the factor its honesty check gave (1: none)");
  }
  if (!node["views"]) return;  // a file of an earlier version: a check predicts with the per-view model alone
  for (const char* key : {"per_view_pattern_covariance_under_it", "per_view_cross_covariance_under_it"}) {
    require(node, key, at, "a model with `views` carries what a check predicts them with: save the calibration again");
  }
  if (e.views.empty()) {
    throw HandEyeError(ErrorCode::MalformedFile, "`views` must be a list of the views the model was fitted on",
                       (at / "views").str(), "write one " + keys_of<Calibration::SharedError::View>() +
                                                 " per view (position: x, y, z in m; gain: 72 numbers, 12 x 6 row-major), "
                                                 "or save the calibration again");
  }
  check_covariance(e.per_view_estimate_pattern_covariance, (at / "per_view_pattern_covariance_under_it").str());
  check_covariance(per_view_estimate_joint_covariance(e), (at / "per_view_cross_covariance_under_it").str() + " (with the X and Y blocks)");
}
}  // namespace

CalibrationFile read_result_node(const YAML::Node& root, const Location& top) {
  CalibrationFile file;
  Calibration& c = file.calibration;
  c.method = Method::Joint;
  if (root["setup"]) file.context.setup = read_setup(root["setup"], top / "setup");
  if (root["parent"] && root["parent"].IsScalar()) file.context.parent = root["parent"].Scalar();
  if (root["child"] && root["child"].IsScalar()) file.context.child = root["child"].Scalar();
  c.T_parent_camera = read_pose(root, top);
  const std::string hint = "the result file needs `covariance: {rotation, translation, pose}`";
  set_pose_covariance(c, read_pose_covariance(require(root, "covariance", top, hint), top / "covariance"));
  if (root["samples_used"]) c.samples_used = as_integer(root["samples_used"], top / "samples_used", 0, 1e9, "samples_used");
  // The noise model the calibration used (samples results only).
  if (const YAML::Node noise = root["noise"];
      noise && noise.IsMap() && noise["model"] && noise["model"].IsMap() && noise["model"]["effector"]) {
    file.noise = read_noise(noise["model"], top / "noise" / "model", "effector", "pattern");
    c.noise = *file.noise;
    if (noise["origin"] && noise["origin"].IsScalar() && noise["origin"].Scalar() != "given") {
      c.noise_origin = NoiseOrigin::EstimatedFromResiduals;
    }
  }
  if (const YAML::Node pattern = root["pattern"]; pattern && pattern.IsMap()) {  // a joint result: Y and Cov(X, Y)
    const Location at = top / "pattern";
    PoseWithCovariance Y;
    Y.pose = read_pose(pattern, at);
    Y.covariance = read_pose_covariance(require(pattern, "covariance", at, hint), at / "covariance");
    c.pattern = Y;
    file.context.pattern_parent = pattern["parent"] && pattern["parent"].IsScalar() ? pattern["parent"].Scalar() : "";
    file.context.pattern_child = pattern["child"] && pattern["child"].IsScalar() ? pattern["child"].Scalar() : "";
    c.cross_covariance = from_row_major_6x6(as_numbers<36>(
        require(root, "cross_covariance", top, "a joint result with `pattern` has `cross_covariance` (36 numbers)"),
        top / "cross_covariance", "6x6 Cov(X, Y), X's ROS order in rows"));
  }
  if (const YAML::Node model = root["noise"] && root["noise"].IsMap() ? root["noise"]["residual_model"] : YAML::Node();
      model && model.IsMap()) {
    const Location at = top / "noise" / "residual_model";
    Calibration::ResidualNoise m;
    read_section(model, at, m);
    check_covariance(m.camera, (at / "camera").str());
    check_covariance(m.robot, (at / "robot").str());
    c.residual_noise = m;
  }
  if (const YAML::Node estimated = root["noise"] && root["noise"].IsMap() ? root["noise"]["estimated"] : YAML::Node();
      estimated && estimated.IsSequence()) {  // each estimated noise number with its 1 sigma: how well the noise is known
    read_value(estimated, top / "noise" / "estimated", c.noise_components);
  }
  if (const YAML::Node prediction = root["prediction"]; prediction && prediction.IsMap()) {
    const Location at = top / "prediction";
    Calibration::Prediction p;
    read_section(prediction, at, p);
    if (!(p.scale > 0.0) || !(p.dof > 0.0) || p.views < 0) {
      throw HandEyeError(ErrorCode::MalformedFile, "the prediction scale and dof must be positive", at.str(),
                         "`prediction` is " + keys_of<Calibration::Prediction>() + ": the leave-one-out of the calibration's views");
    }
    c.prediction = p;
  }
  // The shared robot error's block (format_result writes it): its numbers, X under
  // it, and where the calibration uses it, the per-view X, Y and covariances kept
  // beside it, about which a check predicts new views under the model (its `views`).
  if (const YAML::Node shared = root["shared_robot_error"]; shared && shared.IsMap()) {
    const Location at = top / "shared_robot_error";
    Calibration::SharedError e;
    read_section(shared, at, e);
    check_shared_error(e, shared, at);
    c.shared_robot_error = e;
  }
  if (const YAML::Node honesty = root["honesty"]; honesty && honesty.IsMap() && honesty["inflation"]) {
    const double inflation = as_finite(honesty["inflation"], top / "honesty" / "inflation", "NaN in the inflation",
                                       "the honesty check's inflation is a number >= 1");
    if (inflation > 1.0) {  // a check predicts with the inflated covariance it was saved with
      Calibration::Honesty h;
      h.inflation = inflation;
      h.verdict = Honesty::Overconfident;
      c.honesty = h;
    }
  }
  return file;
}
}  // namespace

CalibrationFile parse_result(const std::string& text, const std::string& source) {
  return read_result_node(load(text, source), Location{source, ""});
}

CalibrationFile read_result(const std::string& path) { return parse_result(read_file(path), path); }

bool is_calibration_of(const Rig& rig, const std::optional<Setup>& setup, const std::string& parent, const std::string& child) {
  const auto agree = [](const std::string& a, const std::string& b) { return a.empty() || b.empty() || a == b; };
  return (!setup || *setup == rig.setup) && agree(parent, rig.camera_parent_frame()) && agree(child, rig.frames.camera);
}

Calibration read_calibration_to_check(const std::string& path, const Rig& rig) {
  return calibration_to_check(read_result(path), rig, path);
}

Calibration calibration_to_check(const CalibrationFile& file, const Rig& rig, const std::string& path) {
  const ResultContext& c = file.context;
  if (!is_calibration_of(rig, c.setup, c.parent, c.child)) {
    const auto name = [](const std::optional<Setup>& setup, const std::string& parent, const std::string& child) {
      return "T_" + (parent.empty() ? std::string("?") : parent) + "_" + (child.empty() ? std::string("?") : child) + " (" +
             (setup ? to_string(*setup) : "setup not given") + ")";
    };
    throw HandEyeError(ErrorCode::MalformedFile,
                       "the saved calibration is " + name(c.setup, c.parent, c.child) + ", the new views are of " +
                           name(rig.setup, rig.camera_parent_frame(), rig.frames.camera),
                       path,
                       "check with views of the setup and frames the calibration was made with (the node: the node of its "
                       "frames, or set ~calibration_file; publish.launch: its robot_*_frame and tracking_base_frame "
                       "arguments rename the file's frames)");
  }
  return file.calibration;
}

StoredCalibration parse_stored_calibration(const std::string& text, const std::string& source) {
  const YAML::Node root = load(text, source);
  const Location top{source, ""};
  StoredCalibration stored;
  if (!root["covariance"] && !root["transformation"]) {
    throw HandEyeError(ErrorCode::MissingKey,
                       "not a calibration: neither a handeye_covariance result (`covariance`) nor easy_handeye's "
                       "(`transformation`)",
                       top.str(), "give the file /calibrate or `handeye solve --output` wrote, or easy_handeye's YAML");
  }
  // Ours has `covariance` (and easy_handeye's `transformation` block too); easy_handeye's has only the latter.
  if (root["covariance"]) {
    const CalibrationFile file = read_result_node(root, top);
    stored.setup = file.context.setup;
    stored.parent = file.context.parent;
    stored.child = file.context.child;
    stored.T_parent_camera = file.T_parent_camera();
    stored.has_covariance = true;
    stored.format = "handeye_covariance";
    return stored;
  }
  stored.format = "easy_handeye";
  const std::string hint = "easy_handeye's `transformation` is {x, y, z, qx, qy, qz, qw} in m";
  const YAML::Node transformation = root["transformation"];
  const Location at = top / "transformation";
  const auto number = [&](const char* key) {
    return as_finite(require(transformation, key, at, hint), at / key, std::string("NaN or Inf in `") + key + "`", hint);
  };
  const Eigen::Quaterniond q(number("qw"), number("qx"), number("qy"), number("qz"));
  const Vector3d t(number("x"), number("y"), number("z"));
  stored.T_parent_camera.pose =
      se3::make_pose(checked_unit_quaternion(q, (at / "qx..qw").str()).toRotationMatrix(), t);
  // The frames: under `parameters`, or at the top level in easy_handeye's older files.
  const bool nested = root["parameters"] && root["parameters"].IsMap();
  const YAML::Node parameters = nested ? root["parameters"] : root;
  const Location where = nested ? top / "parameters" : top;
  const auto text_of = [&](const char* key) {
    const YAML::Node node = parameters[key];
    return node && !node.IsNull() ? as_text(node, where / key) : std::string();
  };
  const YAML::Node eye_on_hand = parameters["eye_on_hand"];
  if (!eye_on_hand || !eye_on_hand.IsScalar()) {
    throw HandEyeError(ErrorCode::MissingKey, "an easy_handeye calibration without `eye_on_hand: true|false`",
                       where.str(), "add `eye_on_hand: true` (camera on the robot) or `false` under `parameters`");
  }
  bool on_hand = false;
  if (!YAML::convert<bool>::decode(eye_on_hand, on_hand)) {
    throw HandEyeError(ErrorCode::MalformedFile, "`eye_on_hand` must be true or false, not `" + eye_on_hand.Scalar() + "`",
                       (where / "eye_on_hand").str(), "write `eye_on_hand: true` or `eye_on_hand: false`");
  }
  stored.setup = setup_from_eye_on_hand(on_hand);
  stored.parent = text_of(on_hand ? "robot_effector_frame" : "robot_base_frame");
  stored.child = text_of("tracking_base_frame");
  return stored;
}

StoredCalibration read_stored_calibration(const std::string& path) {
  const std::string text = read_file(path);
  try {
    return parse_stored_calibration(text, path);
  } catch (const YAML::Exception& e) {  // a shape the readers did not foresee: still a named error, never a crash
    throw HandEyeError(ErrorCode::MalformedFile, std::string("unexpected YAML structure: ") + e.what(), path,
                       "compare the file with one /calibrate wrote (docs/file_formats.md)");
  }
}

}  // namespace io
}  // namespace handeye
