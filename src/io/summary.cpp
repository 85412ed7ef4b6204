#include "handeye_covariance/io/summary.h"

#include <cmath>
#include <cstdarg>
#include <cstdio>

namespace handeye {
namespace io {

namespace {

constexpr double kDeg = 180.0 / M_PI;

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

}  // namespace

std::string human_summary(const Calibration& c, const ResultContext& context) {
  const Eigen::Isometry3d& X = c.T_parent_camera;
  const Eigen::Vector3d t = X.translation();
  Eigen::Quaterniond q(X.linear());
  if (q.w() < 0) q.coeffs() *= -1.0;
  // Fixed-axis roll, pitch, yaw (about parent x, then y, then z), as ROS uses.
  const Eigen::Vector3d ypr = X.linear().eulerAngles(2, 1, 0);
  const Eigen::Vector3d sigma_t = c.translation_covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  const Eigen::Vector3d sigma_R = c.rotation_covariance.diagonal().cwiseMax(0.0).cwiseSqrt();

  const std::string parent = name_or(context.parent, context.setup == Setup::EyeToHand ? "base" : "parent");
  const std::string child = name_or(context.child, "camera");
  std::string out;
  out += line("Hand-eye calibration%s: X = T_%s_%s (maps %s points into %s)",
              context.setup ? (std::string(" (") + to_string(*context.setup) + ")").c_str() : "",
              parent.c_str(), child.c_str(), child.c_str(), parent.c_str());
  out += line("  translation [m]       %+10.6f %+10.6f %+10.6f", t.x(), t.y(), t.z());
  out += line("    1 sigma [mm]        %10.3f %10.3f %10.3f", sigma_t.x() * 1e3, sigma_t.y() * 1e3, sigma_t.z() * 1e3);
  out += line("  rotation rpy [deg]    %+10.4f %+10.4f %+10.4f", ypr.z() * kDeg, ypr.y() * kDeg, ypr.x() * kDeg);
  out += line("    1 sigma [deg]       %10.4f %10.4f %10.4f   (about %s x, y, z)", sigma_R.x() * kDeg,
              sigma_R.y() * kDeg, sigma_R.z() * kDeg, parent.c_str());
  out += line("  quaternion [x y z w]  %+.8f %+.8f %+.8f %+.8f", q.x(), q.y(), q.z(), q.w());
  out += line("  worst axis 1 sigma    %.3f mm, %.4f deg", max_sigma(c.translation_covariance) * 1e3,
              max_sigma(c.rotation_covariance) * kDeg);
  if (c.samples_used > 0) {
    out += line("  data                  %d samples -> %d motions", c.samples_used, c.motions_used);
  } else {
    out += line("  data                  %d motions", c.motions_used);
  }
  if (c.noise_origin == NoiseOrigin::EstimatedFromResiduals) {
    out += line("  noise                 ESTIMATED from the residuals (no noise block given): "
                "camera rotation %.4f deg, translation %.3f mm (1 sigma per axis, robot taken as exact)",
                std::sqrt(c.noise.camera.rotation(0, 0)) * kDeg, std::sqrt(c.noise.camera.translation(0, 0)) * 1e3);
  } else {
    out += line("  noise                 given (the noise block, or the detections' covariances)");
  }
  out += line("  solver                rotation %d it (%s, chi2/dof %.2f), translation %d it (%s, chi2/dof %.2f)",
              c.rotation_stage.iterations, to_string(c.rotation_stage.stop_reason),
              c.rotation_stage.chi2 / std::max(1, c.rotation_stage.dof), c.translation_stage.iterations,
              to_string(c.translation_stage.stop_reason),
              c.translation_stage.chi2 / std::max(1, c.translation_stage.dof));
  for (const std::string& warning : c.warnings) out += "  WARNING: " + warning + "\n";
  return out;
}

}  // namespace io
}  // namespace handeye
