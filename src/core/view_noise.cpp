#include "handeye_covariance/core/view_noise.h"

#include <Eigen/Cholesky>
#include <cmath>

namespace handeye {

std::vector<Eigen::Vector3d> face_points(const Eigen::Isometry3d& T_pattern_face, const Eigen::Vector2d& extent) {
  // {-a, a} spreads as a uniform spread over a side L does when a^2 = L^2 / 12.
  const Eigen::Vector2d a = extent / std::sqrt(12.0);
  std::vector<Eigen::Vector3d> points;
  for (const double sx : {-1.0, 1.0}) {
    for (const double sy : {-1.0, 1.0}) points.push_back(T_pattern_face * Eigen::Vector3d(sx * a.x(), sy * a.y(), 0.0));
  }
  return points;
}

std::vector<Eigen::Vector3d> view_points(const Rig& rig) {
  const bool known = (rig.face_size.array() > 0.0).all();
  return face_points(rig.T_pattern_face, known ? rig.face_size : Eigen::Vector2d(0.2, 0.2));
}

Matrix6d planar_view_information(const Eigen::Isometry3d& T_camera_pattern, const std::vector<Eigen::Vector3d>& points) {
  Matrix6d information = Matrix6d::Zero();
  for (const Eigen::Vector3d& q : points) {
    const Eigen::Vector3d r = T_camera_pattern.linear() * q;  // the point about the camera, before the translation
    const Eigen::Vector3d p = r + T_camera_pattern.translation();
    if (!(p.z() > 0.0)) return Matrix6d::Zero();
    // u = (x/z, y/z): du = a . dp, b . dp with a = (1, 0, -x/z) / z, b = (0, 1, -y/z) / z.
    // Under the left perturbation R = exp(xi) R_hat, t = t_hat + dt the point moves by
    // dt + xi x (R q), so each row of J is (a, r x a) (a . (xi x r) = (r x a) . xi).
    const double w = 1.0 / p.z();
    for (const Eigen::Vector3d& a : {Eigen::Vector3d(w, 0.0, -p.x() * w * w), Eigen::Vector3d(0.0, w, -p.y() * w * w)}) {
      Vector6d row;
      row << a, r.cross(a);
      information.noalias() += row * row.transpose();
    }
  }
  return information;
}

Matrix6d planar_view_covariance(const Eigen::Isometry3d& T_camera_pattern, const std::vector<Eigen::Vector3d>& points) {
  const Matrix6d information = planar_view_information(T_camera_pattern, points);
  if (information.isZero(0.0)) return Matrix6d::Zero();
  const Eigen::LDLT<Matrix6d> ldlt(information);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 1e-9 * information.diagonal().maxCoeff()).all()) {
    return Matrix6d::Zero();
  }
  const Matrix6d covariance = ldlt.solve(Matrix6d::Identity());
  return 0.5 * (covariance + covariance.transpose());
}

}  // namespace handeye
