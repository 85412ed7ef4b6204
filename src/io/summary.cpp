#include "handeye_covariance/io/summary.h"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/io/honesty_text.h"
#include "handeye_covariance/io/noise_text.h"
#include "handeye_covariance/io/warning_text.h"

namespace handeye {
namespace io {

namespace {


std::string line(const char* format, ...) __attribute__((format(printf, 1, 2)));
std::string line(const char* format, ...) {
  char buffer[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buffer, sizeof buffer, format, args);
  va_end(args);
  return std::string(buffer) + "\n";
}

std::string name_or(const std::string& name, const char* fallback) {
  return name.empty() ? fallback : name;
}

/// Translation and rotation with 1 sigma per axis (parent frame), as both summaries print them.
std::string pose_lines(const Eigen::Isometry3d& T, const Matrix6d& covariance, const std::string& parent) {
  const Eigen::Vector3d t = T.translation();
  // Fixed-axis roll, pitch, yaw (about parent x, then y, then z), as ROS uses.
  const Eigen::Vector3d ypr = T.linear().eulerAngles(2, 1, 0);
  const Eigen::Vector3d sigma_t = covariance.topLeftCorner<3, 3>().diagonal().cwiseMax(0.0).cwiseSqrt();
  const Eigen::Vector3d sigma_R = covariance.bottomRightCorner<3, 3>().diagonal().cwiseMax(0.0).cwiseSqrt();
  std::string out;
  out += line("  translation [m]       %+10.6f %+10.6f %+10.6f", t.x(), t.y(), t.z());
  out += line("    1 sigma [mm]        %10.3f %10.3f %10.3f", millimetres(sigma_t.x()), millimetres(sigma_t.y()), millimetres(sigma_t.z()));
  out += line("  rotation rpy [deg]    %+10.4f %+10.4f %+10.4f", ypr.z() * kDegreesPerRadian, ypr.y() * kDegreesPerRadian, ypr.x() * kDegreesPerRadian);
  out += line("    1 sigma [deg]       %10.4f %10.4f %10.4f   (about %s x, y, z)", sigma_R.x() * kDegreesPerRadian,
              sigma_R.y() * kDegreesPerRadian, sigma_R.z() * kDegreesPerRadian, parent.c_str());
  Eigen::Quaterniond q(T.linear());
  if (q.w() < 0) q.coeffs() *= -1.0;
  out += line("  quaternion [x y z w]  %+.8f %+.8f %+.8f %+.8f", q.x(), q.y(), q.z(), q.w());
  out += line("  worst axis 1 sigma    %.3f mm, %.4f deg", millimetres(max_sigma(covariance.topLeftCorner<3, 3>())),
              max_sigma(covariance.bottomRightCorner<3, 3>()) * kDegreesPerRadian);
  return out;
}

/// "robot 3%, calibration 45%, detection 52%" of a total variance.
std::string shares(double robot, double calibration, double detection) {
  const double total = std::max(1e-300, robot + calibration + detection);
  return line("robot %.0f%%, calibration (X) %.0f%%, detection %.0f%%", 100.0 * robot / total,
              100.0 * calibration / total, 100.0 * detection / total);
}

}  // namespace

std::string object_summary(const ObjectPose& object, const std::string& base, const std::string& object_frame,
                           const std::vector<Eigen::Vector3d>& points) {
  std::string out = line("Object pose T_%s_%s (maps %s points into %s):", base.c_str(), object_frame.c_str(),
                         object_frame.c_str(), base.c_str());
  out += pose_lines(object.T_base_object.pose, object.T_base_object.covariance, base);
  const auto position_variance = [](const Matrix6d& c) { return c.topLeftCorner<3, 3>().trace(); };
  out += "  position variance     " + shares(position_variance(object.from_robot), position_variance(object.from_calibration),
                                           position_variance(object.from_detection));
  for (const Eigen::Vector3d& p : points) {
    const PointInBase point = point_in_base(object, p);
    out += line("  point [%g %g %g] m on the object: at [%+.6f %+.6f %+.6f] m in %s, worst axis 1 sigma %.3f mm",
                p.x(), p.y(), p.z(), point.position.x(), point.position.y(), point.position.z(), base.c_str(),
                millimetres(max_sigma(point.covariance)));
    out += "    its variance        " + shares(point.from_robot.trace(), point.from_calibration.trace(),
                                               point.from_detection.trace());
  }
  return out;
}

std::string one_line_summary(const Calibration& c, const std::string& parent, const std::string& child) {
  std::string line = "X = T_" + parent + "_" + child + " from " + std::to_string(c.samples_used) +
                     " samples; worst-axis 1 sigma " + number_text(millimetres(max_sigma(c.translation_covariance))) +
                     " mm, " + number_text(degrees(max_sigma(c.rotation_covariance))) + " deg";
  if (c.shared_robot_error && c.shared_robot_error->used) {
    line += "; with a robot error shared by nearby poses (" + number_text(millimetres(c.shared_robot_error->translation_sigma)) +
            " mm, " + number_text(degrees(c.shared_robot_error->rotation_sigma)) + " deg over " +
            number_text(c.shared_robot_error->length_scale, 2) + " m)";
  }
  if (c.honesty && c.honesty->ran()) line += "; " + c.honesty->text;
  return line;
}

std::string shared_error_state(const std::optional<Calibration::SharedError>& e) {
  if (!e) return "off";
  return !e->not_fitted.empty() ? "not fitted: " + e->not_fitted
         : e->used              ? "used"
         : e->chosen            ? "advice"
                                : "not preferred";
}

std::string human_summary(const Calibration& c, const ResultContext& context) {
  const std::string parent = name_or(context.parent, context.setup == Setup::EyeToHand ? "base" : "parent");
  const std::string child = name_or(context.child, "camera");
  std::string out;
  if (c.honesty && c.honesty->inflation > 1.0) {  // first: what the covariance below is
    const Calibration::Honesty& h = *c.honesty;
    out += line("OVERCONFIDENT noise model on this session: split-half NEES %s against %s for an honest covariance on "
                "these poses; the covariances below are the model's x%s (the model's alone: --no-inflation)",
                number_text(h.split_half_nees, 3).c_str(), number_text(h.reference.mean, 3).c_str(),
                number_text(h.inflation, 3).c_str());
  }
  out += line("Hand-eye calibration%s: X = T_%s_%s (maps %s points into %s)",
              context.setup ? (std::string(" (") + to_string(*context.setup) + ")").c_str() : "",
              parent.c_str(), child.c_str(), child.c_str(), parent.c_str());
  out += pose_lines(c.T_parent_camera, c.pose_covariance, parent);
  if (c.pattern) {
    const std::string pattern_parent = name_or(context.pattern_parent, "world");
    const std::string pattern = name_or(context.pattern_child, "pattern");
    out += line("Pattern pose Y = T_%s_%s, estimated with X:", pattern_parent.c_str(), pattern.c_str());
    out += pose_lines(c.pattern->pose, c.pattern->covariance, pattern_parent);
  }
  if (c.method == Method::Joint) {
    out += line("  data                  %d samples (joint estimator: X and the pattern pose from the poses)", c.samples_used);
  } else if (c.method == Method::Corners && c.corner_fit) {
    out += line("  data                  %d images, %d corners (corner estimator: X and the pattern pose from every "
                "corner's reprojection error)",
                c.samples_used, c.corner_fit->corners);
  } else if (c.samples_used > 0) {
    out += line("  data                  %d samples -> %d motions (pairs estimator)", c.samples_used, c.motions_used);
  } else {
    out += line("  data                  %d motions", c.motions_used);
  }
  const auto sigmas = [](const Eigen::Matrix3d& C, double unit) {
    const Eigen::Vector3d s = C.diagonal().cwiseMax(0.0).cwiseSqrt() * unit;
    return line("%.4f %.4f %.4f", s.x(), s.y(), s.z());
  };
  if (c.method == Method::Corners) {
    out += "  noise                 " + noise_model_text(c) + "\n";
    if (c.corner_fit) {
      std::string worst;
      double worst_rms = -1.0;
      for (const Calibration::CornerFit::Image& image : c.corner_fit->images) {
        if (image.rms_px > worst_rms) worst_rms = image.rms_px, worst = image.name;
      }
      out += line("  reprojection          RMS %.3f px over every corner; worst image %s at %.3f px", c.corner_fit->rms_px,
                  worst.c_str(), worst_rms);
      if (!c.corner_fit->pixel_noise.empty()) out += "  pixel noise           " + c.corner_fit->pixel_noise + "\n";
      if (!c.corner_fit->target_points.empty()) out += "  target points         " + c.corner_fit->target_points + "\n";
    }
  } else if (c.noise_origin == NoiseOrigin::EstimatedFromResiduals) {
    std::string estimated = "  noise                 ESTIMATED from the residuals (no noise block given); camera 1 sigma x y z [mm] " +
                            sigmas(c.noise.camera.translation, kMillimetresPerMetre);
    estimated.pop_back();
    out += estimated + ", [deg] " + sigmas(c.noise.camera.rotation, kDegreesPerRadian);
    if (const std::string how = noise_model_text(c); !how.empty()) out += "                        (" + how + ")\n";
  } else if (!c.noise_components.empty()) {
    out += line("  noise                 given, too small for the residuals: the missing part ESTIMATED");
    out += "                        (" + noise_model_text(c) + ")\n";
  } else {
    out += line("  noise                 given (the noise block, or the detections' covariances)");
  }
  if (c.method == Method::Joint) {
    std::string checks;
    for (const Calibration::ResidualCheck& check : c.residual_checks) {
      checks += (checks.empty() ? "" : "; ") + check.test + " " + number_text(check.statistic, 3) + " (bound " +
                number_text(check.bound, 3) + (check.passed ? ", passed)" : ", FAILED)");
    }
    if (!checks.empty()) out += "  residual checks       " + checks + "\n";
    out += c.covariance_kind == CovarianceKind::Sandwich
               ? line("  covariance            ROBUST: Huber loss (%d sample(s) down-weighted), sandwich x%.2f", c.downweighted,
                      c.covariance_inflation)
           : c.covariance_kind == CovarianceKind::SharedRobotError
               ? line("  covariance            a robot error shared by nearby poses: generalised least squares x%.3f (X), "
                      "x%.3f (pattern)", c.covariance_inflation, c.pattern_covariance_inflation)
               : line("  covariance            inverse information x%.3f (X), x%.3f (pattern)", c.covariance_inflation,
                      c.pattern_covariance_inflation);
  }
  if (c.honesty) out += honesty_lines(*c.honesty);
  if (c.shared_robot_error) out += shared_error_lines(*c.shared_robot_error, c);
  if (c.method == Method::Joint || c.method == Method::Corners) {
    out += line("  solver                %d it (%s, chi2/dof %.2f over %d dof)", c.rotation_stage.iterations,
                to_string(c.rotation_stage.stop_reason), c.rotation_stage.chi2 / std::max(1, c.rotation_stage.dof),
                c.rotation_stage.dof);
  } else {
    out += line("  solver                rotation %d it (%s, chi2/dof %.2f), translation %d it (%s, chi2/dof %.2f)",
                c.rotation_stage.iterations, to_string(c.rotation_stage.stop_reason),
                c.rotation_stage.chi2 / std::max(1, c.rotation_stage.dof), c.translation_stage.iterations,
                to_string(c.translation_stage.stop_reason),
                c.translation_stage.chi2 / std::max(1, c.translation_stage.dof));
  }
  for (const Warning& warning : c.warnings) out += "  WARNING: " + warning_text(warning) + "\n";
  for (const auto& r : c.rejected) out += "  rejected samples[" + std::to_string(r.index) + "]: " + rejected_text(r) + "\n";
  return out;
}

std::string honesty_lines(const Calibration::Honesty& h) {
  if (!h.ran()) return "  honesty check         not run: " + h.text + "\n";
  std::string out = "  honesty check         " + h.text + " (split-half NEES " + number_text(h.split_half_nees, 3) +
                    " against " + number_text(h.reference.mean, 3) + " for an honest covariance on these poses; ratio " +
                    number_text(h.ratio, 3) + ")\n";
  const std::string halves = h.run_length > 1 ? "halves of runs of " + std::to_string(h.run_length) +
                                                     " consecutive samples, at least " + std::to_string(h.half_size)
                                               : "halves of " + std::to_string(h.half_size);
  out += "                        " + std::to_string(h.splits) + " random splits into " + halves +
         " (middle 90%); reference: " + std::to_string(h.reference.sessions) + " simulated sessions at the same robot poses, 5-95% " +
         number_text(h.reference.low, 3) + " to " + number_text(h.reference.high, 3) + "\n";
  if (h.runs.length > 0) {
    out += "                        the other look: " +
           (h.run_length > 1 ? "random halves, ratio " + number_text(h.random_ratio, 3)
                             : "halves of runs of " + std::to_string(h.runs.length) + " consecutive samples, ratio " +
                                   number_text(h.runs.ratio, 3)) +
           " (the worse look decides)\n";
  } else if (!h.runs_note.empty()) {
    out += "                        no runs look: " + h.runs_note + "\n";
  }
  return out;
}

std::string shared_error_lines(const Calibration::SharedError& e, const Calibration& c) {
  if (!e.not_fitted.empty()) return "  shared robot error    not fitted: " + e.not_fitted + "\n";
  if (!e.chosen) {
    return line("  shared robot error    not preferred: the per-view noise explains the residuals (BIC gain %.1f)",
                e.bic_gain);
  }
  // The per-view model's X covariance: the calibration's, or, when the model is in
  // use, the one it replaced.
  const Matrix6d& per_view = e.used ? e.per_view_X.covariance : c.pose_covariance;
  double ratio = 0.0;  // the largest of sigma_X under the model over the per-view model's, per axis
  for (int k = 0; k < 6; ++k) {
    if (per_view(k, k) > 0.0) {
      ratio = std::max(ratio, std::sqrt(std::max(e.per_view_estimate_covariance(k, k), 0.0) / per_view(k, k)));
    }
  }
  if (e.used) {
    const Vector6d step = pose_error(e.X.pose, e.per_view_X.pose);
    std::string out = line("  shared robot error    used: the likelihood prefers an error shared by nearby poses (BIC gain "
                           "%.1f: %.2f mm and %.3f deg per axis over %.2f m)",
                           e.bic_gain, millimetres(e.translation_sigma), degrees(e.rotation_sigma), e.length_scale);
    out += line("                        X and its covariance above are its generalised least squares (x%.3f for its "
                "fitted numbers); the per-view model's X is [%.3f %.3f %.3f] mm [%.4f %.4f %.4f] deg from it (step "
                "NEES %.1f)",
                e.covariance_inflation, -millimetres(step(0)), -millimetres(step(1)), -millimetres(step(2)), -degrees(step(3)),
                -degrees(step(4)), -degrees(step(5)), e.step_nees);
    if (ratio > 1.0) {
      out += line("                        under it the per-view model's sigma_X is up to %.1fx too small", ratio);
    }
    if (!e.per_view_honesty.empty()) {
      out += "                        the per-view model's own honesty check: " + e.per_view_honesty +
             " (a check of new views predicts about its X and Y, under the shared error)\n";
    }
    return out;
  }
  const Vector6d step = pose_error(e.X.pose, c.T_parent_camera);
  std::string out = line("  shared robot error    the likelihood prefers an error shared by nearby poses (BIC gain %.1f: "
                         "%.2f mm and %.3f deg per axis over %.2f m)",
                         e.bic_gain, millimetres(e.translation_sigma), degrees(e.rotation_sigma), e.length_scale);
  out += ratio > 1.0 ? line("                        under it sigma_X above is up to %.1fx too small", ratio)
                     : line("                        under it sigma_X above covers it (at most %.2f of it on any axis)", ratio);
  out += line("                        and X would move by [%.3f %.3f %.3f] mm [%.4f %.4f %.4f] deg (step NEES %.1f); "
              "advice only: X and its covariance above are the per-view model's",
              millimetres(step(0)), millimetres(step(1)), millimetres(step(2)), degrees(step(3)), degrees(step(4)), degrees(step(5)),
              e.step_nees);
  return out;
}

std::string report_summary(const CalibrationReport& report) {
  const auto row = [](const char* name, const Vector6d& sigma, const std::string& note) {
    char line[200];
    std::snprintf(line, sizeof line, "    %-15s %7.3f %7.3f %7.3f   %7.4f %7.4f %7.4f%s\n", name, millimetres(sigma(0)),
                  millimetres(sigma(1)), millimetres(sigma(2)), degrees(sigma(3)), degrees(sigma(4)),
                  degrees(sigma(5)), note.c_str());
    return std::string(line);
  };
  std::string out = "  1 sigma of X          x [mm]  y [mm]  z [mm]   rx [deg] ry [deg] rz [deg]\n";
  out += row("predicted", report.predicted_sigma, "");
  // Where X is the shared robot error's GLS estimate, the leave-one-out solves are the
  // per-view estimator's: their spread cannot see an error the samples share.
  const bool shared = report.calibration.shared_robot_error && report.calibration.shared_robot_error->used;
  out += row("leave-one-out", report.leave_one_out_sigma,
             "   (" + std::to_string(report.leave_one_out_solved) + " solves" +
                 (report.leave_one_out_failed ? ", " + std::to_string(report.leave_one_out_failed) + " failed" : "") +
                 (shared ? "; the per-view estimator's" : "") + ")");
  if (report.honesty.observed.splits > 0) {
    const HonestyCheck& h = report.honesty;
    out += row("split-half", report.split_half_sigma,
               "   (" + std::to_string(h.observed.splits) + " splits, NEES " + number_text(h.observed.trimmed_mean_nees, 3) +
                   (h.ran() ? "; honest here " + number_text(h.reference.mean, 3) + ": " + honesty_text(h) : "") + ")");
  } else {
    out += "    split-half      " + report.split_problem + "\n";
  }
  out += "  advice\n";
  for (const std::string& a : report.advice) out += "    - " + a + "\n";
  return out;
}

std::string check_summary(const CalibrationCheck& check) {
  std::string text = std::string(check.changed ? "CHANGED: " : "") + check_verdict(check) + "\n";
  text += line("  %zu new views: chi2 %.1f on %d dof (p = %.2g); the best change of X alone explains %.1f, of Y "
               "alone %.1f",
                 check.views.size(), check.chi2, check.dof, check.chi2_p_value, check.X_alone.chi2_drop,
                 check.Y_alone.chi2_drop);
  text += "  view   error mm  (1 sigma mm)   error deg  (1 sigma deg)   sigma\n";
  for (std::size_t i = 0; i < check.views.size(); ++i) {
    const CheckedView& v = check.views[i];
    const bool left_out = std::find(check.left_out.begin(), check.left_out.end(), static_cast<int>(i)) != check.left_out.end();
    text += line("  %4zu   %8.3f  (%8.3f)     %8.4f  (%8.4f)      %5.2f%s", i, millimetres(v.translation_error),
                 millimetres(v.predicted_translation_sigma), degrees(v.rotation_error),
                 degrees(v.predicted_rotation_sigma), v.mahalanobis, left_out ? "  left out" : "");
  }
  text += "  (1 sigma: the error's RMS the calibration predicts for that view, its own noise and X's and Y's "
          "uncertainty; sigma: the view's Mahalanobis length, about 2.3 on average when nothing changed)\n";
  for (const std::string& a : check_advice(check)) text += "  advice: " + a + "\n";
  return text;
}

}  // namespace io
}  // namespace handeye
