#include "handeye_covariance/core/ellipsoid.h"

#include <Eigen/Eigenvalues>

#include "handeye_covariance/core/validation.h"

namespace handeye {

Ellipsoid ellipsoid_from_covariance(const Eigen::Matrix3d& covariance, double sigmas) {
  check_covariance(covariance, "covariance to draw");
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(covariance);
  Ellipsoid e;
  // Eigen sorts ascending; draw the largest axis first.
  for (int i = 0; i < 3; ++i) {
    e.radii(i) = sigmas * std::sqrt(std::max(0.0, eig.eigenvalues()(2 - i)));
    e.axes.col(i) = eig.eigenvectors().col(2 - i);
  }
  if (e.axes.determinant() < 0) e.axes.col(2) *= -1.0;  // right-handed
  return e;
}

Eigen::Matrix3d axis_tip_covariance(const Eigen::Matrix3d& rotation_covariance, const Eigen::Vector3d& axis,
                                    double length) {
  const Eigen::Matrix3d lever = so3::hat(length * axis.normalized());
  return lever * rotation_covariance * lever.transpose();
}

}  // namespace handeye
