#include "handeye_covariance/core/validation.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>

namespace handeye {

namespace {
double orthonormality_error(const Eigen::Matrix3d& R) { return (R.transpose() * R - Eigen::Matrix3d::Identity()).norm(); }
bool is_proper_rotation(double orthonormality, double det) { return orthonormality <= 1e-6 && std::abs(det - 1.0) <= 1e-6; }
}  // namespace

bool is_proper_pose(const Eigen::Isometry3d& pose) {
  return pose.matrix().allFinite() && is_proper_rotation(orthonormality_error(pose.linear()), pose.linear().determinant());
}

void check_pose(const Eigen::Isometry3d& pose, const std::string& where) {
  if (!pose.matrix().allFinite()) {
    throw HandEyeError(ErrorCode::NonFinite, "pose contains NaN or Inf", where,
                       "drop this sample or fix the source that produced it");
  }
  const Eigen::Matrix3d& R = pose.linear();
  const double orthonormality = orthonormality_error(R);
  const double det = R.determinant();
  if (!is_proper_rotation(orthonormality, det)) {
    throw HandEyeError(ErrorCode::RotationNotOrthonormal,
                       "rotation is not orthonormal (|R^T R - I| = " + number_text(orthonormality, 6) +
                           ", det = " + number_text(det, 6) + ")",
                       where, "pass a proper rotation matrix (re-orthonormalise it, or check the units and the row/column order)");
  }
}

namespace {
template <int N>
void check_square_covariance(const Eigen::Matrix<double, N, N>& covariance, const std::string& where) {
  if (!covariance.allFinite()) {
    throw HandEyeError(ErrorCode::NonFinite, "covariance contains NaN or Inf", where,
                       "give " + std::to_string(N * N) + " finite numbers, row-major, in rad^2 or m^2");
  }
  const double scale = covariance.cwiseAbs().maxCoeff();
  if ((covariance - covariance.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) {
    throw HandEyeError(ErrorCode::InvalidNoise, "covariance is not symmetric", where,
                       "give a symmetric " + std::to_string(N) + "x" + std::to_string(N) + " matrix, row-major");
  }
  // Cholesky of C + t I succeeds exactly when C's smallest eigenvalue is above -t:
  // the common case in a fraction of an eigen solver's time (the estimators check
  // every sample's noise on every solve); the solver only for the message.
  const double tolerance = 1e-12 * std::max(scale, 1e-300);
  using Matrix = Eigen::Matrix<double, N, N>;
  if (Eigen::LLT<Matrix>(covariance + tolerance * Matrix::Identity()).info() == Eigen::Success) return;
  const Eigen::SelfAdjointEigenSolver<Matrix> eig(covariance, Eigen::EigenvaluesOnly);
  if (eig.eigenvalues().minCoeff() < -tolerance) {
    throw HandEyeError(ErrorCode::InvalidNoise,
                       "covariance is not positive semi-definite (smallest eigenvalue " +
                           number_text(eig.eigenvalues().minCoeff(), 6) + ")",
                       where, "variances go on the diagonal and must be >= 0 (they are sigma^2, not sigma)");
  }
}
}  // namespace

void check_covariance(const Eigen::Matrix3d& covariance, const std::string& where) {
  check_square_covariance<3>(covariance, where);
}

void check_covariance(const Matrix6d& covariance, const std::string& where) {
  check_square_covariance<6>(covariance, where);
}

void check_covariance(const Matrix12d& covariance, const std::string& where) {
  check_square_covariance<12>(covariance, where);
}

void check_covariance(const DecoupledCovariance& covariance, const std::string& where) {
  check_covariance(covariance.rotation, where + ".rotation");
  check_covariance(covariance.translation, where + ".translation");
}

void check_covariance(const PoseNoise& covariance, const std::string& where) {
  check_covariance(covariance.rotation, where + ".rotation");
  check_covariance(covariance.translation, where + ".translation");
  if (!covariance.has_cross_block()) return;
  if (!covariance.translation_rotation.allFinite()) {
    throw HandEyeError(ErrorCode::NonFinite, "covariance contains NaN or Inf", where + ".translation_rotation",
                       "drop this sample or fix the source that produced it");
  }
  // The 6x6 as correlations (unit diagonal), so that m^2 and rad^2 do not set the
  // tolerance: PSD there is PSD of the covariance.
  const Matrix6d C = covariance.as_pose_covariance();
  const Vector6d d = C.diagonal();
  if (!(d.array() > 0.0).all()) {
    throw HandEyeError(ErrorCode::InvalidNoise, "a cross term pairs with a zero variance", where,
                       "a pose axis without variance cannot correlate with another; zero its cross terms");
  }
  const Vector6d s = d.cwiseSqrt().cwiseInverse();
  const Matrix6d correlation = s.asDiagonal() * C * s.asDiagonal();
  if (Eigen::LLT<Matrix6d>(correlation + 1e-9 * Matrix6d::Identity()).info() == Eigen::Success) return;  // as above
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(correlation, Eigen::EigenvaluesOnly);
  if (eig.eigenvalues().minCoeff() < -1e-9) {
    throw HandEyeError(ErrorCode::InvalidNoise,
                       "the rotation-translation cross block is larger than the variances allow (the 6x6 is not "
                       "positive semi-definite; smallest correlation eigenvalue " +
                           number_text(eig.eigenvalues().minCoeff(), 4) + ")",
                       where, "check the cross block's units (m rad) and that it is E[xi_t xi_R^T] of the same pose");
  }
}

Eigen::Quaterniond checked_unit_quaternion(const Eigen::Quaterniond& q, const std::string& where) {
  if (!q.coeffs().allFinite()) {
    throw HandEyeError(ErrorCode::NonFinite, "quaternion contains NaN or Inf", where,
                       "drop this sample or fix the source that produced it");
  }
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > 1e-3) {
    throw HandEyeError(ErrorCode::QuaternionNotUnit,
                       "quaternion norm is " + number_text(norm, 6) + ", not 1",
                       where, "give a unit quaternion in the order [qx, qy, qz, qw]");
  }
  return q.normalized();
}

}  // namespace handeye
