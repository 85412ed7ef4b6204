#include "handeye_covariance/corners/corner_calibration.h"

#include <ceres/autodiff_cost_function.h>
#include <ceres/autodiff_manifold.h>
#include <ceres/jet.h>
#include <ceres/covariance.h>
#include <ceres/normal_prior.h>
#include <ceres/problem.h>
#include <ceres/rotation.h>
#include <ceres/solver.h>

#include <boost/math/distributions/chi_squared.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/units.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

// The least robot variance per axis, (0.1 um)^2 and (0.1 urad)^2, where the
// residuals support none (or a stated noise has a zero axis): the prior needs a
// finite weight, and what it keeps must not show in X's covariance. At (1 um)^2 it
// did: one image's pose is known to about a micrometre from corners at 0.01 px,
// and an exact robot held there made X's covariance cautious (NEES 4.2-4.8 instead
// of 6; test_corner_calibration, BENCHMARKS.md's AprilTag board).
constexpr double kRobotVarianceFloor = 1e-14;

// A pose as Ceres holds it: (tx, ty, tz, qw, qx, qy, qz), Ceres's quaternion order.
using PoseBlock = std::array<double, 7>;

PoseBlock pose_block(const Isometry3d& T) {
  const Eigen::Quaterniond q(T.rotation());
  return {T.translation().x(), T.translation().y(), T.translation().z(), q.w(), q.x(), q.y(), q.z()};
}

Isometry3d pose_of(const PoseBlock& b) {
  Isometry3d T = Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(b[3], b[4], b[5], b[6]).normalized().toRotationMatrix();
  T.translation() = Vector3d(b[0], b[1], b[2]);
  return T;
}

// The package's perturbation of a pose, on Ceres's 7-number pose: tangent
// (xi_t, xi_R) in ROS order, T (+) xi = (exp([xi_R]) R, t + xi_t), a left
// perturbation in the parent frame (pose_covariance.h). Ceres's own
// QuaternionManifold is also a left product but with exp(delta) of angle
// 2 |delta|, which would halve the tangent and quarter the covariance.
struct LeftPosePlus {
  template <typename T>
  bool Plus(const T* x, const T* delta, T* x_plus_delta) const {
    for (int k = 0; k < 3; ++k) x_plus_delta[k] = x[k] + delta[k];
    T q_delta[4];
    ceres::AngleAxisToQuaternion(delta + 3, q_delta);
    ceres::QuaternionProduct(q_delta, x + 3, x_plus_delta + 3);
    return true;
  }
  template <typename T>
  bool Minus(const T* y, const T* x, T* y_minus_x) const {
    for (int k = 0; k < 3; ++k) y_minus_x[k] = y[k] - x[k];
    const T x_inverse[4] = {x[3], -x[4], -x[5], -x[6]};
    T q_delta[4];
    ceres::QuaternionProduct(y + 3, x_inverse, q_delta);
    ceres::QuaternionToAngleAxis(q_delta, y_minus_x + 3);
    return true;
  }
};
using PoseManifold = ceres::AutoDiffManifold<LeftPosePlus, 7, 6>;

// OpenCV's distortion model (k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4), as
// cv::projectPoints applies it without the tilt; missing coefficients are 0.
template <typename T>
void distort(const T& x, const T& y, const T& k1, const T& k2, const std::array<double, 12>& d, T& xd, T& yd) {
  const T r2 = x * x + y * y;
  const T r4 = r2 * r2;
  const T r6 = r4 * r2;
  const T radial = (T(1.0) + k1 * r2 + k2 * r4 + d[4] * r6) / (T(1.0) + d[5] * r2 + d[6] * r4 + d[7] * r6);
  xd = x * radial + 2.0 * d[2] * x * y + d[3] * (r2 + 2.0 * x * x) + d[8] * r2 + d[9] * r4;
  yd = y * radial + d[2] * (r2 + 2.0 * y * y) + 2.0 * d[3] * x * y + d[10] * r2 + d[11] * r4;
}

// What every image's cost needs of the camera and the setup.
struct Projection {
  std::array<double, 6> intrinsics{};   // fx, fy, cx, cy, k1, k2 (used when they are fixed)
  double skew = 0.0;
  std::array<double, 12> distortion{};  // OpenCV's order; k1, k2 are taken from the intrinsics
  bool eye_in_hand = true;
};

// One image's corners, whitened by the corner-noise model: each block b of
// coordinates (8 for an AprilTag's corners under the edge-fit model, 2 for one
// corner) gets L_b^-1 (u_hat - u) / sigma, with C_b = L_b L_b^T.
struct ImageCorners {
  std::vector<Vector3d> object;
  std::vector<Vector2d> image;
  std::vector<int> block_start, block_size;  // in coordinates (2 per corner)
  std::vector<Eigen::MatrixXd> whitening;    // L_b^-1
  PoseBlock robot;                           // E_i as measured
};

// The camera's pose of the pattern, P = X^-1 V Y (q_P, t_P; Ceres's quaternion
// order), V = E^-1 eye-in-hand and E eye-to-hand, with E = exp(xi_E) E_measured
// (xi_E = `robot`, or none when null).
template <typename T>
void pattern_in_camera(const PoseBlock& E, bool eye_in_hand, const T* x, const T* y, const T* robot, T* q_P, T* t_P) {
  T q_E[4], t_E[3];
  for (int k = 0; k < 4; ++k) q_E[k] = T(E[3 + k]);
  for (int k = 0; k < 3; ++k) t_E[k] = T(E[k]);
  if (robot != nullptr) {
    T q_delta[4];
    ceres::AngleAxisToQuaternion(robot + 3, q_delta);
    const T q_measured[4] = {q_E[0], q_E[1], q_E[2], q_E[3]};
    ceres::QuaternionProduct(q_delta, q_measured, q_E);
    for (int k = 0; k < 3; ++k) t_E[k] += robot[k];
  }
  T q_V[4], t_V[3];
  if (eye_in_hand) {
    q_V[0] = q_E[0];
    for (int k = 1; k < 4; ++k) q_V[k] = -q_E[k];
    ceres::UnitQuaternionRotatePoint(q_V, t_E, t_V);
    for (int k = 0; k < 3; ++k) t_V[k] = -t_V[k];
  } else {
    for (int k = 0; k < 4; ++k) q_V[k] = q_E[k];
    for (int k = 0; k < 3; ++k) t_V[k] = t_E[k];
  }
  const T q_X_inverse[4] = {x[3], -x[4], -x[5], -x[6]};
  T q_VY[4];
  ceres::QuaternionProduct(q_V, y + 3, q_VY);
  ceres::QuaternionProduct(q_X_inverse, q_VY, q_P);
  T Vt_Y[3];
  ceres::UnitQuaternionRotatePoint(q_V, y, Vt_Y);
  const T d[3] = {Vt_Y[0] + t_V[0] - x[0], Vt_Y[1] + t_V[1] - x[1], Vt_Y[2] + t_V[2] - x[2]};
  ceres::UnitQuaternionRotatePoint(q_X_inverse, d, t_P);
}

// The pixel of pattern point o seen at (R_P row-major, t_P), through the camera's
// (fx, fy, cx, cy, k1, k2) and the rest of `c`'s distortion.
template <typename T, typename O>
void project_point(const Projection& c, const T* k, const T* R_P, const T* t_P, const O* o, T* uv) {
  const T p[3] = {R_P[0] * o[0] + R_P[1] * o[1] + R_P[2] * o[2] + t_P[0], R_P[3] * o[0] + R_P[4] * o[1] + R_P[5] * o[2] + t_P[1],
                  R_P[6] * o[0] + R_P[7] * o[1] + R_P[8] * o[2] + t_P[2]};
  T xd, yd;
  distort<T>(p[0] / p[2], p[1] / p[2], k[4], k[5], c.distortion, xd, yd);
  uv[0] = k[0] * xd + c.skew * yd + k[2];
  uv[1] = k[1] * yd + k[3];
}

// The reprojection cost of one image. Parameter blocks: X (7), Y (7), then the
// robot pose's perturbation xi_E (6) when kRobot, then the intrinsics (6) when
// kIntrinsics. The camera sees the pattern at P = X^-1 V Y, V = E^-1 eye-in-hand
// and E eye-to-hand, with E = exp(xi_E) E_measured.
template <bool kRobot, bool kIntrinsics>
class ImageCost {
 public:
  ImageCost(const ImageCorners* corners, const Projection* projection, const double* inverse_sigma)
      : corners_(corners), projection_(projection), inverse_sigma_(inverse_sigma) {}

  template <typename T>
  bool operator()(const T* x, const T* y, T* residuals) const {
    static_assert(!kRobot && !kIntrinsics, "two parameter blocks: X and Y only");
    return evaluate<T>(x, y, nullptr, nullptr, residuals);
  }
  template <typename T>
  bool operator()(const T* x, const T* y, const T* third, T* residuals) const {
    static_assert(kRobot != kIntrinsics, "three parameter blocks: X, Y and one of robot or intrinsics");
    return kRobot ? evaluate<T>(x, y, third, nullptr, residuals) : evaluate<T>(x, y, nullptr, third, residuals);
  }
  template <typename T>
  bool operator()(const T* x, const T* y, const T* robot, const T* intrinsics, T* residuals) const {
    static_assert(kRobot && kIntrinsics, "four parameter blocks");
    return evaluate<T>(x, y, robot, intrinsics, residuals);
  }

 private:
  template <typename T>
  bool evaluate(const T* x, const T* y, const T* robot, const T* intrinsics, T* residuals) const {
    T q_P[4], t_P[3], R_P[9];
    pattern_in_camera<T>(corners_->robot, projection_->eye_in_hand, x, y, robot, q_P, t_P);
    ceres::QuaternionToRotation(q_P, R_P);  // row-major

    const Projection& c = *projection_;
    T k[6];
    for (int i = 0; i < 6; ++i) k[i] = intrinsics ? intrinsics[i] : T(c.intrinsics[i]);
    const ImageCorners& image = *corners_;
    T difference[kMaxCornerBlock];
    for (std::size_t b = 0; b < image.block_start.size(); ++b) {
      const int start = image.block_start[b], size = image.block_size[b];
      for (int i = 0; i < size / 2; ++i) {
        const int corner = start / 2 + i;
        T uv[2];
        project_point<T, double>(c, k, R_P, t_P, image.object[corner].data(), uv);
        difference[2 * i] = uv[0] - image.image[corner].x();
        difference[2 * i + 1] = uv[1] - image.image[corner].y();
      }
      const Eigen::MatrixXd& W = image.whitening[b];
      for (int r = 0; r < size; ++r) {
        T sum = T(0.0);
        for (int k = 0; k <= r; ++k) sum += W(r, k) * difference[k];  // L^-1 is lower-triangular
        residuals[start + r] = sum * (*inverse_sigma_);
      }
    }
    return true;
  }

  const ImageCorners* corners_;
  const Projection* projection_;
  const double* inverse_sigma_;  // 1 / sigma, updated between the noise rounds
};

template <bool kRobot, bool kIntrinsics>
ceres::CostFunction* typed_image_cost(const ImageCorners* corners, const Projection* projection, const double* inverse_sigma) {
  using Cost = ImageCost<kRobot, kIntrinsics>;
  const int m = static_cast<int>(2 * corners->image.size());
  if constexpr (!kRobot && !kIntrinsics) {
    return new ceres::AutoDiffCostFunction<Cost, ceres::DYNAMIC, 7, 7>(new Cost(corners, projection, inverse_sigma), m);
  } else if constexpr (kRobot && kIntrinsics) {
    return new ceres::AutoDiffCostFunction<Cost, ceres::DYNAMIC, 7, 7, 6, 6>(new Cost(corners, projection, inverse_sigma),
                                                                              m);
  } else {
    return new ceres::AutoDiffCostFunction<Cost, ceres::DYNAMIC, 7, 7, 6>(new Cost(corners, projection, inverse_sigma), m);
  }
}

// The cost of one image with what is free (the robot pose, the intrinsics).
ceres::CostFunction* image_cost(bool robot, bool intrinsics, const ImageCorners* corners, const Projection* projection,
                                const double* inverse_sigma) {
  if (robot && intrinsics) return typed_image_cost<true, true>(corners, projection, inverse_sigma);
  if (robot) return typed_image_cost<true, false>(corners, projection, inverse_sigma);
  if (intrinsics) return typed_image_cost<false, true>(corners, projection, inverse_sigma);
  return typed_image_cost<false, false>(corners, projection, inverse_sigma);
}

ImageCorners image_corners(const CornerView& view, std::size_t index) {
  const PointCorrespondences& points = view.points;
  const std::string where = "corner view " + std::to_string(index) + (view.name.empty() ? "" : " (" + view.name + ")");
  check_corners(points, where);
  const int m = static_cast<int>(2 * points.image.size());
  const int block = points.corner_covariance.size() == 0 ? 2 : points.blocks;
  ImageCorners out;
  out.object = points.object;
  out.image = points.image;
  out.robot = pose_block(view.T_base_effector);
  for (int start = 0; start < m; start += block) {
    Eigen::MatrixXd C = points.corner_covariance.size() == 0
                            ? Eigen::MatrixXd::Identity(block, block)
                            : Eigen::MatrixXd(points.corner_covariance.block(start, start, block, block));
    const Eigen::LLT<Eigen::MatrixXd> llt(C);  // positive definite: check_corners
    out.block_start.push_back(start);
    out.block_size.push_back(block);
    out.whitening.push_back(llt.matrixL().solve(Eigen::MatrixXd::Identity(block, block)));
  }
  return out;
}

Projection projection_of(const CameraModel& camera, const Rig& rig) {
  check_camera_model(camera, "the corner calibration's camera");
  Projection p;
  p.intrinsics = {camera.K(0, 0), camera.K(1, 1), camera.K(0, 2), camera.K(1, 2),
                  camera.distortion.size() > 0 ? camera.distortion[0] : 0.0,
                  camera.distortion.size() > 1 ? camera.distortion[1] : 0.0};
  p.skew = camera.K(0, 1);
  for (std::size_t k = 0; k < camera.distortion.size() && k < p.distortion.size(); ++k) p.distortion[k] = camera.distortion[k];
  if (camera.distortion.size() == 14 && (camera.distortion[12] != 0.0 || camera.distortion[13] != 0.0)) {
    throw HandEyeError(ErrorCode::MalformedFile, "the camera's distortion has a tilted sensor (tau_x, tau_y)",
                       "the corner calibration's camera", "use --method poses for a tilted-sensor camera model");
  }
  p.eye_in_hand = rig.eye_in_hand();
  return p;
}

}  // namespace

IntrinsicsVector intrinsics_of(const CameraModel& camera) {
  IntrinsicsVector k;
  k << camera.K(0, 0), camera.K(1, 1), camera.K(0, 2), camera.K(1, 2), camera.distortion.size() > 0 ? camera.distortion[0] : 0.0,
      camera.distortion.size() > 1 ? camera.distortion[1] : 0.0;
  return k;
}

namespace {

// Bartlett's test of equal variances over the groups the per-image weighting
// would use (each image with at least min_dof, and the others pooled as one):
// (N ln s_p^2 - sum nu_g ln s_g^2) / C ~ chi2(k - 1), N = sum nu_g,
// C = 1 + (sum 1 / nu_g - 1 / N) / (3 (k - 1)). It is sensitive to heavy tails
// within an image too, which the per-image weighting then absorbs as noise.
// The images with under min_dof degrees of freedom, which share one sigma: their
// summed RSS and dof.
std::pair<double, double> pooled_few(const std::vector<double>& rss, const std::vector<ImageReprojection>& images,
                                     double min_dof) {
  std::pair<double, double> few{0.0, 0.0};
  for (std::size_t i = 0; i < rss.size(); ++i) {
    if (images[i].dof < min_dof) few = {few.first + rss[i], few.second + std::max(0.0, images[i].dof)};
  }
  return few;
}

HomogeneityTest homogeneity_test(const std::vector<double>& rss, const std::vector<ImageReprojection>& images,
                                 double level, double min_dof) {
  std::vector<std::pair<double, double>> groups;  // (rss, nu)
  for (std::size_t i = 0; i < rss.size(); ++i) {
    if (images[i].dof >= min_dof) groups.emplace_back(rss[i], images[i].dof);
  }
  if (const auto few = pooled_few(rss, images, min_dof); few.second >= 1.0) groups.push_back(few);
  double N = 0.0, pooled = 0.0, weighted_log = 0.0, inverse = 0.0;
  int k = 0;
  for (const auto& [group_rss, nu] : groups) {
    if (!(group_rss > 0.0)) continue;
    ++k;
    N += nu;
    pooled += group_rss;
    weighted_log += nu * std::log(group_rss / nu);
    inverse += 1.0 / nu;
  }
  HomogeneityTest test;
  if (k < 2) return test;
  test.dof = k - 1;
  const double C = 1.0 + (inverse - 1.0 / N) / (3.0 * (k - 1));
  test.chi2 = (N * std::log(pooled / N) - weighted_log) / C;
  test.bound = boost::math::quantile(boost::math::chi_squared(k - 1), level);
  test.passed = test.chi2 <= test.bound;
  return test;
}


// The target's geometry as a consider parameter (header: "Target geometry"). The
// whitened corner residuals' Jacobian by every target point's 3-d offset, D (m x
// 3N), against the fit's own J (every row, the priors too; columns `blocks` in
// tangent space, the shared ones first), H = J^T J: the fit ignores the offsets,
// so its estimate moves by S delta, S = H^-1 J^T D, and their variance tau^2 adds
// tau^2 S S^T to its covariance. tau^2 from the residuals r (MINQUE on the fit's
// projection M = I - J H^-1 J^T): E[r^T r] = s nu + tau^2 t1, E[|D^T r|^2] =
// s t1 + tau^2 t2, with t1 = tr(D^T M D), t2 = |D^T M D|_F^2 and s the corners'
// variance scale (1 when the pixel sigma is given).
struct TargetPointTerm {
  double variance = 0.0;   // tau^2, m^2 per axis
  double corner_scale = 1.0;  // s: the share of the corners' residual variance that is theirs
  Eigen::MatrixXd covariance;  // of the first `shared` tangent coordinates: (s J_c^T J_c + J_p^T J_p) sandwiched, + tau^2 S S^T
  int points = 0;          // N
};

TargetPointTerm target_point_term(ceres::Problem& problem, const std::vector<double*>& blocks, int shared,
                                  const std::vector<ceres::ResidualBlockId>& residual_blocks, int m,
                                  const std::vector<ImageCorners>& images, const std::vector<double>& inverse_sigma,
                                  const Projection& projection, const double* x, const double* y,
                                  const std::vector<std::array<double, 6>>* robot, const double* k,
                                  double given_variance, bool sigma_estimated, double dof) {
  TargetPointTerm out;
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = blocks;
  evaluate.residual_blocks = residual_blocks;
  std::vector<double> residuals;
  ceres::CRSMatrix crs;
  problem.Evaluate(evaluate, nullptr, &residuals, nullptr, &crs);
  using RowSparse = Eigen::SparseMatrix<double, Eigen::RowMajor>;
  const Eigen::Map<const RowSparse> J(crs.num_rows, crs.num_cols, static_cast<Eigen::Index>(crs.values.size()),
                                      crs.rows.data(), crs.cols.data(), crs.values.data());
  // The target's points, by their coordinates (every image's come from one target).
  std::map<std::array<double, 3>, int> index;
  for (const ImageCorners& image : images) {
    for (const Vector3d& o : image.object) index.emplace(std::array<double, 3>{o.x(), o.y(), o.z()}, 0);
  }
  for (auto& [point, i] : index) i = out.points++;
  using Jet = ceres::Jet<double, 3>;
  std::vector<Eigen::Triplet<double>> entries;
  int row = 0;
  for (std::size_t i = 0; i < images.size(); ++i) {
    const ImageCorners& image = images[i];
    double q_P[4], t_P[3], R_P[9];
    pattern_in_camera<double>(image.robot, projection.eye_in_hand, x, y, robot ? (*robot)[i].data() : nullptr, q_P, t_P);
    ceres::QuaternionToRotation(q_P, R_P);
    Jet R[9], t[3], intrinsics[6];
    for (int a = 0; a < 9; ++a) R[a] = Jet(R_P[a]);
    for (int a = 0; a < 3; ++a) t[a] = Jet(t_P[a]);
    for (int a = 0; a < 6; ++a) intrinsics[a] = Jet(k ? k[a] : projection.intrinsics[a]);
    for (std::size_t b = 0; b < image.block_start.size(); ++b) {
      const int start = image.block_start[b], size = image.block_size[b];
      Eigen::MatrixXd du(size, 3 * (size / 2));  // the block's pixels by its points' offsets
      du.setZero();
      for (int c = 0; c < size / 2; ++c) {
        const Vector3d& o = image.object[start / 2 + c];
        const Jet point[3] = {Jet(o.x(), 0), Jet(o.y(), 1), Jet(o.z(), 2)};
        Jet uv[2];
        project_point<Jet, Jet>(projection, intrinsics, R, t, point, uv);
        du.block<1, 3>(2 * c, 3 * c) = uv[0].v.transpose();
        du.block<1, 3>(2 * c + 1, 3 * c) = uv[1].v.transpose();
      }
      Eigen::MatrixXd whitened = image.whitening[b] * du;  // L^-1 is lower-triangular
      whitened *= inverse_sigma[i];
      for (int c = 0; c < size / 2; ++c) {
        const Vector3d& o = image.object[start / 2 + c];
        const int column = 3 * index.at({o.x(), o.y(), o.z()});
        for (int r = 0; r < size; ++r)
          for (int a = 0; a < 3; ++a) {
            if (whitened(r, 3 * c + a) != 0.0) entries.emplace_back(row + start + r, column + a, whitened(r, 3 * c + a));
          }
      }
    }
    row += static_cast<int>(2 * image.image.size());
  }
  Eigen::SparseMatrix<double> D(m, 3 * out.points);
  D.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SparseMatrix<double> H = Eigen::SparseMatrix<double>(J.transpose() * J);
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(H);
  if (ldlt.info() != Eigen::Success) {
    throw HandEyeError(ErrorCode::PoorlyConstrained, "the fit's information cannot be factored for the target's error",
                       "corner calibration", "add views from more varied robot poses, or give --target-error-mm 0");
  }
  const Eigen::SparseMatrix<double> Jc = J.topRows(m), Jp = J.bottomRows(J.rows() - m);  // corners, priors
  const Eigen::MatrixXd G = Eigen::MatrixXd(Eigen::SparseMatrix<double>(Jc.transpose() * D));
  const Eigen::MatrixXd S = ldlt.solve(G);
  // t1 = tr(D^T M_cc D) and t2 = |D^T M_cc D|_F^2 with D^T M_cc D = A - G^T S, A = D^T D
  // (block-diagonal, one block per tag or point), without forming the 3N x 3N.
  const Eigen::SparseMatrix<double> A = D.transpose() * D;
  const double t1 = A.diagonal().sum() - G.cwiseProduct(S).sum();
  const Eigen::MatrixXd GA = G * A;
  const double t2 = A.squaredNorm() - 2.0 * GA.cwiseProduct(S).sum() +
                    (G * G.transpose()).cwiseProduct(S * S.transpose()).sum();
  // The prior rows' share (M_cc is not idempotent when priors are fitted): u = |J_p S|^2
  // of D's, w = |J_c H^-1 J_p^T|^2 = tr(C) - |C|_F^2, C = J_p H^-1 J_p^T (one solve per
  // prior row; H = J_c^T J_c + J_p^T J_p), of the corners'.
  double u = 0.0, w = 0.0;
  if (Jp.rows() > 0) {
    u = Eigen::MatrixXd(Jp * S).squaredNorm();
    const Eigen::MatrixXd C = Jp * ldlt.solve(Eigen::MatrixXd(Jp.transpose()));
    w = C.trace() - C.squaredNorm();
  }
  const Eigen::Map<const Eigen::VectorXd> r(residuals.data(), m);
  const double rss = r.squaredNorm(), q = (D.transpose() * r).squaredNorm();
  // E[r^T r] = s (nu - w) + w + tau^2 (t1 - u),  E[|D^T r|^2] = s (t1 - u) + u + tau^2 t2.
  if (given_variance >= 0.0) {
    out.variance = given_variance;
  } else if (sigma_estimated) {
    const double a = dof - w, b = t1 - u, determinant = a * t2 - b * b;
    if (determinant > 0.0) out.variance = (a * (q - u) - b * (rss - w)) / determinant;
  } else if (t2 > 0.0) {
    out.variance = (q - t1) / t2;
  }
  out.variance = std::isfinite(out.variance) ? std::max(0.0, out.variance) : 0.0;
  // With the pixel sigma estimated, the corners' residual variance held the
  // target's share too: s of it is theirs.
  if (sigma_estimated && dof - w > 0.0) {
    out.corner_scale = std::clamp((rss - w - out.variance * (t1 - u)) / (dof - w), 0.1, 1.0);
  }
  Eigen::MatrixXd unit = Eigen::MatrixXd::Zero(J.cols(), shared);
  unit.topRows(shared).setIdentity();
  const Eigen::MatrixXd Z = ldlt.solve(unit);  // H^-1's first `shared` columns
  const Eigen::MatrixXd JZ = Jc * Z;
  out.covariance = Z.topRows(shared) - (1.0 - out.corner_scale) * JZ.transpose() * JZ +
                   out.variance * S.topRows(shared) * S.topRows(shared).transpose();
  return out;
}

}  // namespace

CornerResiduals corner_residuals(const Rig& rig, const CameraModel& camera, const std::vector<CornerView>& views,
                                 const Isometry3d& X, const Isometry3d& Y) {
  const Projection projection = projection_of(camera, rig);
  std::vector<ImageCorners> images;
  images.reserve(views.size());
  for (std::size_t i = 0; i < views.size(); ++i) images.push_back(image_corners(views[i], i));
  PoseBlock x = pose_block(X), y = pose_block(Y);
  const double inverse_sigma = 1.0;
  ceres::Problem problem;
  problem.AddParameterBlock(x.data(), 7, new PoseManifold);
  problem.AddParameterBlock(y.data(), 7, new PoseManifold);
  for (const ImageCorners& image : images) {
    problem.AddResidualBlock(image_cost(false, false, &image, &projection, &inverse_sigma), nullptr, x.data(), y.data());
  }
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = {x.data(), y.data()};
  std::vector<double> residuals;
  ceres::CRSMatrix jacobian;  // in the tangent spaces of the manifolds
  problem.Evaluate(evaluate, nullptr, &residuals, nullptr, &jacobian);
  CornerResiduals out;
  out.whitened = Eigen::Map<const Eigen::VectorXd>(residuals.data(), static_cast<Eigen::Index>(residuals.size()));
  out.jacobian.setZero(jacobian.num_rows, 12);
  for (int r = 0; r < jacobian.num_rows; ++r) {
    for (int e = jacobian.rows[r]; e < jacobian.rows[r + 1]; ++e) out.jacobian(r, jacobian.cols[e]) = jacobian.values[e];
  }
  return out;
}

// Over 150 lines: one Ceres problem whose blocks, priors and per-round pixel sigmas share some twenty locals; its stages are commented.
CornerCalibration calibrate_corners(const Rig& rig, const CameraModel& camera, const std::vector<CornerView>& views,
                                    const Isometry3d& X0, const Isometry3d& Y0, const CornerOptions& options) {
  if (views.size() < 3) {
    throw HandEyeError(ErrorCode::NoData, "only " + std::to_string(views.size()) + " views with corners, need at least 3",
                       "corner calibration", "take more images of the target from different robot poses");
  }
  if (!std::isfinite(options.target_point_sigma)) {
    throw HandEyeError(ErrorCode::InvalidNoise, "target point sigma " + number_text(options.target_point_sigma) + " m",
                       "corner calibration options", "give the target points' 1 sigma in m, 0 for an exact target, "
                       "or a negative number to estimate it");
  }
  if (!(options.pixel_sigma >= 0.0) || !std::isfinite(options.pixel_sigma)) {
    throw HandEyeError(ErrorCode::InvalidNoise, "pixel sigma " + number_text(options.pixel_sigma) + " px",
                       "corner calibration options", "give a positive pixel sigma, or 0 to estimate it");
  }
  // The robot poses' prior: as given, or (estimated) isotropic per translation and
  // rotation, started at the given one's mean variances or 1 mm / 0.1 deg.
  Matrix6d robot_covariance = Matrix6d::Zero();
  if (options.robot_covariance) {
    Eigen::LLT<Matrix6d> llt(*options.robot_covariance);
    if (!options.robot_covariance->allFinite() || llt.info() != Eigen::Success) {
      throw HandEyeError(ErrorCode::InvalidNoise, "the robot pose covariance is not positive definite",
                         "corner calibration options", "give the robot's 6x6 pose noise (ROS order, m^2 and rad^2)");
    }
    robot_covariance = *options.robot_covariance;
  }
  Eigen::Vector2d robot_variance(1e-6, std::pow(radians(0.1), 2));  // m^2, rad^2 (estimated)
  if (options.estimate_robot_noise) {
    if (options.robot_covariance) {
      robot_variance << robot_covariance.diagonal().head<3>().mean(), robot_covariance.diagonal().tail<3>().mean();
    }
    robot_covariance.setZero();
    robot_covariance.diagonal() << Vector3d::Constant(robot_variance[0]), Vector3d::Constant(robot_variance[1]);
  }
  const Projection projection = projection_of(camera, rig);
  std::vector<ImageCorners> images;
  images.reserve(views.size());
  int m = 0;
  for (std::size_t i = 0; i < views.size(); ++i) {
    images.push_back(image_corners(views[i], i));
    m += static_cast<int>(2 * images.back().image.size());
  }
  const bool robot_free = options.robot_covariance.has_value() || options.estimate_robot_noise;
  const bool intrinsics_free = options.refine_intrinsics;

  PoseBlock x = pose_block(X0), y = pose_block(Y0);
  std::vector<std::array<double, 6>> robot(views.size(), std::array<double, 6>{});
  IntrinsicsVector k0 = intrinsics_of(camera), k = k0;
  // Sigma for the first round: as given, or 1 px, re-estimated after every round
  // (it weighs the corners against the priors; alone it only scales the covariance).
  double sigma = options.pixel_sigma > 0.0 ? options.pixel_sigma : 1.0;
  // Each image's 1 / sigma in its cost: all the same, unless the images' noise differs.
  std::vector<double> inverse_sigma(views.size(), 1.0 / sigma);

  ceres::Problem::Options problem_options;
  problem_options.enable_fast_removal = true;  // the robot priors are replaced as their noise is estimated
  ceres::Problem problem(problem_options);
  problem.AddParameterBlock(x.data(), 7, new PoseManifold);
  problem.AddParameterBlock(y.data(), 7, new PoseManifold);
  if (intrinsics_free) problem.AddParameterBlock(k.data(), 6);
  // Image i's parameter blocks, in ImageCost's order.
  const auto blocks_of = [&](std::size_t i) {
    std::vector<double*> blocks = {x.data(), y.data()};
    if (robot_free) blocks.push_back(robot[i].data());
    if (intrinsics_free) blocks.push_back(k.data());
    return blocks;
  };
  std::vector<ceres::ResidualBlockId> image_blocks;
  for (std::size_t i = 0; i < views.size(); ++i) {
    image_blocks.push_back(problem.AddResidualBlock(
        image_cost(robot_free, intrinsics_free, &images[i], &projection, &inverse_sigma[i]), nullptr, blocks_of(i)));
  }
  // The robot poses' priors, xi_E,i ~ N(0, robot_covariance): NormalPrior with A = L^-1.
  std::vector<ceres::ResidualBlockId> robot_priors;
  const auto set_robot_priors = [&] {
    const ceres::Matrix A = Eigen::LLT<Matrix6d>(robot_covariance).matrixL().solve(Matrix6d::Identity());
    for (ceres::ResidualBlockId id : robot_priors) problem.RemoveResidualBlock(id);
    robot_priors.clear();
    for (auto& r : robot) {
      robot_priors.push_back(problem.AddResidualBlock(new ceres::NormalPrior(A, Eigen::VectorXd::Zero(6)), nullptr, r.data()));
    }
  };
  if (robot_free) set_robot_priors();
  Vector6d prior_sigma;
  ceres::ResidualBlockId intrinsics_prior = nullptr;
  if (intrinsics_free) {
    const double width = camera.width > 0 ? camera.width : 2.0 * camera.K(0, 2);
    prior_sigma << options.focal_prior * k0[0], options.focal_prior * k0[1], options.centre_prior * width,
        options.centre_prior * width, options.distortion_prior, options.distortion_prior;
    const ceres::Matrix A = prior_sigma.cwiseInverse().asDiagonal();
    intrinsics_prior = problem.AddResidualBlock(new ceres::NormalPrior(A, k0), nullptr, k.data());
  }

  ceres::Solver::Options solver;
  solver.max_num_iterations = options.max_iterations;
  solver.linear_solver_type = robot_free ? ceres::DENSE_SCHUR : ceres::DENSE_QR;
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  solver.function_tolerance = 1e-12;
  solver.gradient_tolerance = 1e-14;
  solver.parameter_tolerance = 1e-12;
  if (robot_free) {
    auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
    for (auto& r : robot) ordering->AddElementToGroup(r.data(), 0);
    ordering->AddElementToGroup(x.data(), 1);
    ordering->AddElementToGroup(y.data(), 1);
    if (intrinsics_free) ordering->AddElementToGroup(k.data(), 1);
    solver.linear_solver_ordering = ordering;
  }

  CornerCalibration result;
  result.pixel_sigma_estimated = options.pixel_sigma == 0.0;
  result.robot_noise_estimated = options.estimate_robot_noise;
  // One sigma moves the solution only through the priors' weight against the
  // corners; each image's own sigma moves it always.
  bool per_image = result.pixel_sigma_estimated && options.robust == JointOptions::Robust::On;
  const bool may_test = result.pixel_sigma_estimated && options.robust == JointOptions::Robust::Auto;
  bool sigma_rounds = (result.pixel_sigma_estimated && (robot_free || intrinsics_free)) || options.estimate_robot_noise ||
                      per_image;
  int rounds = sigma_rounds || may_test ? std::max(1, options.max_noise_rounds) : 1;
  Eigen::MatrixXd xy_covariance;  // unit: the whitening's sigma
  double corner_rss = 0.0;        // px^2 per unit sigma^2, at the solution
  double weighted_chi2 = 0.0;     // sum r^T C^-1 r / sigma_i^2, each image at its sigma
  double absorbed = 0.0;          // what the fit absorbs of the corners
  std::vector<Eigen::Vector2d> history;  // the robot's log variances, since the last extrapolation
  std::array<bool, 2> robot_at_bound = {false, false};
  for (int round = 0; round < rounds; ++round) {
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    result.iterations += static_cast<int>(summary.iterations.size());
    result.noise_rounds = round + 1;
    if (!summary.IsSolutionUsable() || summary.termination_type == ceres::NO_CONVERGENCE) {
      throw HandEyeError(ErrorCode::NotConverged, "Ceres stopped: " + summary.message, "corner calibration",
                         "check the start (the pose-level estimate) and the images' corners");
    }
    // The covariance of what the fit moves: (X, Y), each robot pose and the intrinsics.
    ceres::Covariance::Options covariance_options;
    covariance_options.num_threads = 1;
    ceres::Covariance covariance(covariance_options);
    std::vector<std::pair<const double*, const double*>> pairs = {
        {x.data(), x.data()}, {x.data(), y.data()}, {y.data(), y.data()}};
    if (robot_free && sigma_rounds) for (const auto& r : robot) pairs.emplace_back(r.data(), r.data());
    if (intrinsics_free) pairs.emplace_back(k.data(), k.data());
    if (!covariance.Compute(pairs, &problem)) {
      throw HandEyeError(ErrorCode::PoorlyConstrained, "the information of X and the pattern pose cannot be inverted",
                         "corner calibration", "add views from more varied robot poses");
    }
    xy_covariance.resize(12, 12);
    covariance.GetCovarianceMatrixInTangentSpace({x.data(), y.data()}, xy_covariance.data());
    xy_covariance.transposeInPlace();  // Ceres writes row-major; symmetric up to rounding
    if (intrinsics_free) {
      Eigen::Matrix<double, 6, 6, Eigen::RowMajor> K_covariance;
      covariance.GetCovarianceBlock(k.data(), k.data(), K_covariance.data());
      result.intrinsics_covariance = K_covariance;
    }
    // The fit's degrees of freedom for the corners: every parameter minus the share
    // each prior holds, tr(Sigma_post A^T A) of its rows (the hat matrix's trace).
    absorbed = 12.0;
    if (intrinsics_free) {
      absorbed += 6.0 - (result.intrinsics_covariance.diagonal().array() / prior_sigma.array().square()).sum();
    }
    // Variance components (Forstner): each prior group's squared residuals over its
    // redundancy, its rows' count minus the share the fit takes of them.
    Eigen::Vector2d robot_squares = Eigen::Vector2d::Zero(), robot_share = Eigen::Vector2d::Zero();
    std::vector<double> robot_absorbed(views.size(), 0.0);  // image i's robot pose's share of the corners
    const double shared_absorbed = absorbed;                 // (X, Y) and the intrinsics: shared by rows
    if (robot_free && sigma_rounds) {
      const Matrix6d information = robot_covariance.inverse();
      for (std::size_t i = 0; i < robot.size(); ++i) {
        const auto& r = robot[i];
        Eigen::Matrix<double, 6, 6, Eigen::RowMajor> block;
        covariance.GetCovarianceBlockInTangentSpace(r.data(), r.data(), block.data());
        const Matrix6d held = Matrix6d(block) * information;
        robot_absorbed[i] = 6.0 - held.trace();
        absorbed += robot_absorbed[i];
        robot_share += Eigen::Vector2d(held.topLeftCorner<3, 3>().trace(), held.bottomRightCorner<3, 3>().trace());
        const Eigen::Map<const Vector6d> xi(r.data());
        robot_squares += Eigen::Vector2d(xi.head<3>().squaredNorm(), xi.tail<3>().squaredNorm());
      }
    }
    corner_rss = 0.0;
    double unweighted = 0.0;
    result.images.clear();
    std::vector<double> image_rss(views.size());
    weighted_chi2 = 0.0;
    for (std::size_t i = 0; i < views.size(); ++i) {
      // The image's residuals at the solution, per unit sigma (the whitening alone),
      // and the plain pixel errors.
      Eigen::VectorXd r(2 * images[i].image.size());
      problem.EvaluateResidualBlock(image_blocks[i], false, nullptr, r.data(), nullptr);
      r /= inverse_sigma[i];
      image_rss[i] = r.squaredNorm();
      corner_rss += image_rss[i];
      weighted_chi2 += image_rss[i] * inverse_sigma[i] * inverse_sigma[i];
      // The plain pixel errors: the whitening undone, block by block.
      double image_unweighted = 0.0;
      for (std::size_t b = 0; b < images[i].block_start.size(); ++b) {
        const int start = images[i].block_start[b], size = images[i].block_size[b];
        const Eigen::VectorXd plain =
            images[i].whitening[b].triangularView<Eigen::Lower>().solve(r.segment(start, size));
        image_unweighted += plain.squaredNorm();
      }
      unweighted += image_unweighted;
      const double rows = static_cast<double>(r.size());
      result.images.push_back({views[i].name, static_cast<int>(images[i].image.size()),
                               std::sqrt(image_unweighted / rows), 1.0 / inverse_sigma[i],
                               rows - shared_absorbed * rows / m - robot_absorbed[i]});
    }
    result.rms_px = std::sqrt(unweighted / m);
    const double dof = m - absorbed;
    result.degrees_of_freedom = static_cast<int>(std::lround(dof));
    bool settled = true;
    if (options.estimate_robot_noise) {
      const double rows = 3.0 * static_cast<double>(views.size());
      const double floor = kRobotVarianceFloor;
      Eigen::Vector2d estimate = robot_variance;
      for (int c = 0; c < 2; ++c) {
        if (robot_at_bound[c]) continue;
        const double redundancy = rows - robot_share[c];  // robot_share[c] = sum tr(Sigma_post,cc) / variance_c
        // Under one row's worth of redundancy the residuals hold nothing of it: the
        // estimate creeps towards 0 ever more slowly; it is put there.
        if (redundancy < 1.0) {
          robot_at_bound[c] = true;
          estimate[c] = floor;
          settled = false;
          continue;
        }
        estimate[c] = std::max(floor, robot_squares[c] / redundancy);
        settled = settled && std::abs(std::sqrt(estimate[c] / robot_variance[c]) - 1.0) < 1e-3;
      }
      // Where the two are told apart by few images, the fixed point creeps along a
      // ridge (translation up, rotation down) at a steady rate: every third step
      // jumps to the limit of that geometric sequence (Aitken's delta-squared on the
      // log variances, with the rate they share).
      history.push_back(estimate.array().log().matrix());
      if (!settled && history.size() == 3) {
        const Eigen::Vector2d d1 = history[1] - history[0], d2 = history[2] - history[1];
        const double rate = d1.squaredNorm() > 0.0 ? std::clamp(d2.dot(d1) / d1.squaredNorm(), 0.0, 0.95) : 0.0;
        const Eigen::Vector2d jumped = (history[2] + rate / (1.0 - rate) * d2).array().exp().max(floor).matrix();
        for (int c = 0; c < 2; ++c) {
          if (!robot_at_bound[c]) estimate[c] = jumped[c];
        }
        history.clear();
      }
      robot_variance = estimate;
      robot_covariance.setZero();
      robot_covariance.diagonal() << Vector3d::Constant(robot_variance[0]), Vector3d::Constant(robot_variance[1]);
      result.robot_sigma = robot_variance.cwiseSqrt();
      result.robot_at_bound = {robot_at_bound[0], robot_at_bound[1]};
    }
    if (!result.pixel_sigma_estimated) {
      if (settled) break;
      set_robot_priors();
      continue;
    }
    if (dof <= 0.0) {
      throw HandEyeError(ErrorCode::NoiseUnidentifiable,
                         "the corners leave " + number_text(dof) + " degrees of freedom for the pixel noise",
                         "corner calibration", "give the pixel sigma, or more corners");
    }
    if (!per_image) {
      const double estimate = std::sqrt(corner_rss / dof);
      settled = settled && std::abs(estimate / sigma - 1.0) < 1e-3;
      if (sigma_rounds && !settled && round + 1 < rounds) {
        sigma = estimate;
        std::fill(inverse_sigma.begin(), inverse_sigma.end(), 1.0 / sigma);
        if (options.estimate_robot_noise) set_robot_priors();
        continue;
      }
      // The one-sigma fit is final: do the images share that sigma?
      if (may_test) {
        result.homogeneity = homogeneity_test(image_rss, result.images, options.homogeneity_level, options.min_image_dof);
        per_image = !result.homogeneity->passed;
      }
      if (!per_image) {
        // Without a prior at stake the solution does not depend on sigma: the
        // covariance scales with it. With one, it is the last solve's, at its sigma
        // (settled: within 0.1% of the estimate; else the rounds ran out).
        if (!sigma_rounds) {
          xy_covariance *= (estimate * estimate) / (sigma * sigma);
          sigma = estimate;
        }
        for (ImageReprojection& image : result.images) image.sigma_px = sigma;
        weighted_chi2 = corner_rss / (sigma * sigma);
        break;
      }
      // The images' own sigmas move the solution: alternate from here, with rounds of their own.
      sigma_rounds = true;
      settled = false;
      rounds = std::max(rounds, round + 1 + std::max(1, options.max_noise_rounds));
    }
    // Each image its own sigma; those with few dof share theirs.
    double pooled_dof = 0.0;
    for (const ImageReprojection& image : result.images) pooled_dof += image.dof;
    const double pooled = std::sqrt(corner_rss / std::max(pooled_dof, 1.0));
    const auto [few_rss, few_dof] = pooled_few(image_rss, result.images, options.min_image_dof);
    // A weight 1 / s^2 from nu dof is too large on average by nu / (nu - 2) (the mean
    // of an inverse chi2): each variance is taken as RSS / (nu - 2), so the
    // information of the weighting is not overstated.
    for (std::size_t i = 0; i < views.size(); ++i) {
      const double nu = result.images[i].dof;
      double s_i = nu >= options.min_image_dof ? std::sqrt(image_rss[i] / (nu - 2.0))
                                               : (few_dof > 3.0 ? std::sqrt(few_rss / (few_dof - 2.0)) : pooled);
      s_i = std::max(s_i, 0.1 * pooled);  // an image that fits perfectly is not infinitely certain
      settled = settled && std::abs(s_i * inverse_sigma[i] - 1.0) < 1e-3;
      inverse_sigma[i] = 1.0 / s_i;
    }
    sigma = pooled;
    if (settled) break;
    if (options.estimate_robot_noise) set_robot_priors();
  }
  // The target's geometry: what its points' errors, shared by every image, add to
  // the covariance (consider parameters; target_point_term).
  if (options.target_point_sigma != 0.0) {
    if (!per_image) std::fill(inverse_sigma.begin(), inverse_sigma.end(), 1.0 / sigma);  // the final weighting
    // The whitened residuals' expected sum without a target error: the fit's dof, less
    // 2 for each sigma taken as RSS / (nu - 2) from its own residuals (per image).
    double expected_rss = m - absorbed;
    if (per_image) {
      double few_dof = 0.0;
      for (const ImageReprojection& image : result.images) {
        if (image.dof >= options.min_image_dof) expected_rss -= 2.0;
        else few_dof += std::max(0.0, image.dof);
      }
      if (few_dof > 3.0) expected_rss -= 2.0;
    }
    std::vector<double*> parameters = {x.data(), y.data()};
    if (intrinsics_free) parameters.push_back(k.data());
    const int shared = static_cast<int>(6 * parameters.size());
    if (robot_free) for (auto& r : robot) parameters.push_back(r.data());
    std::vector<ceres::ResidualBlockId> rows = image_blocks;
    rows.insert(rows.end(), robot_priors.begin(), robot_priors.end());
    if (intrinsics_prior != nullptr) rows.push_back(intrinsics_prior);
    const TargetPointTerm term = target_point_term(
        problem, parameters, shared, rows, m, images, inverse_sigma, projection, x.data(), y.data(),
        robot_free ? &robot : nullptr, intrinsics_free ? k.data() : nullptr,
        options.target_point_sigma > 0.0 ? options.target_point_sigma * options.target_point_sigma : -1.0,
        result.pixel_sigma_estimated, expected_rss);
    result.target_point_sigma = std::sqrt(term.variance);
    result.target_point_sigma_estimated = options.target_point_sigma < 0.0;
    if (term.variance > 0.0) {
      const Matrix6d before = xy_covariance.topLeftCorner<6, 6>();
      xy_covariance = term.covariance.topLeftCorner(12, 12);
      if (intrinsics_free) result.intrinsics_covariance = term.covariance.block<6, 6>(12, 12);
      result.target_inflation << std::sqrt(xy_covariance.topLeftCorner<3, 3>().trace() / before.topLeftCorner<3, 3>().trace()),
          std::sqrt(xy_covariance.block<3, 3>(3, 3).trace() / before.bottomRightCorner<3, 3>().trace());
      // The pixel noise without the target's share.
      const double scale = std::sqrt(term.corner_scale);
      sigma *= scale;
      for (ImageReprojection& image : result.images) image.sigma_px *= scale;
    }
  }
  result.pixel_sigma = sigma;
  result.chi2 = weighted_chi2;
  result.per_image_sigma = per_image;
  result.X = pose_of(x);
  result.Y = pose_of(y);
  result.covariance = 0.5 * (xy_covariance + xy_covariance.transpose());
  if (intrinsics_free) result.intrinsics = k;
  return result;
}

namespace {

bool same_camera(const CameraModel& a, const CameraModel& b) {
  return a.K == b.K && a.distortion == b.distortion && a.width == b.width && a.height == b.height;
}

}  // namespace

CornerMethodResult refine_with_corners(const SampleSet& samples, const Calibration& pose_level, CornerOptions options) {
  if (!pose_level.pattern) {
    throw HandEyeError(ErrorCode::MalformedFile, "the pose-level estimate has no pattern pose to start from",
                       "corner calibration", "start from the joint estimator (method joint), not pairs");
  }
  std::vector<bool> rejected(samples.samples.size(), false);
  for (const Calibration::Rejected& r : pose_level.rejected) rejected.at(static_cast<std::size_t>(r.index)) = true;
  std::vector<CornerView> views;
  const CameraModel* camera = nullptr;
  for (std::size_t i = 0; i < samples.samples.size(); ++i) {
    if (rejected[i]) continue;
    const std::shared_ptr<const TargetCorners>& corners = samples.samples[i].corners;
    if (!corners) {
      throw HandEyeError(ErrorCode::MalformedFile, "sample " + std::to_string(i) + " has no corners", "method corners",
                         "every sample needs the corners its pose was detected from: use the package's target detector "
                         "(or images), remove that sample, or use method joint");
    }
    if (camera == nullptr) camera = &corners->camera;
    if (!same_camera(*camera, corners->camera)) {
      throw HandEyeError(ErrorCode::MalformedFile, "sample " + std::to_string(i) + "'s corners come from another camera "
                         "(CameraInfo) than the first sample's", "method corners",
                         "calibrate one camera at a time, with one camera calibration");
    }
    views.push_back({samples.samples[i].T_base_effector, corners->points,
                     corners->source.empty() ? "sample " + std::to_string(i) : corners->source});
  }
  if (camera == nullptr) {
    throw HandEyeError(ErrorCode::NoData, "no sample is left to refine", "method corners", "take more samples");
  }
  if (!options.robot_covariance && !options.estimate_robot_noise) {
    const bool stated = samples.noise && !samples.noise->robot.as_pose_covariance().isZero(0.0);
    bool trusted = stated;
    for (const Calibration::ResidualCheck& check : pose_level.residual_checks) trusted = trusted && check.passed;
    Matrix6d R = pose_level.noise.robot.as_pose_covariance();
    if (!R.isZero(0.0)) {
      for (int k = 0; k < 6; ++k) R(k, k) = std::max(R(k, k), kRobotVarianceFloor);
      options.robot_covariance = R;
    }
    options.estimate_robot_noise = !trusted && views.size() >= 6;
  }
  Calibration::CornerFit fit;
  if (options.estimate_robot_noise) {
    fit.robot_poses = Calibration::CornerFit::RobotPoses::Estimated;
  } else if (options.robot_covariance) {
    const Vector6d s = options.robot_covariance->diagonal().cwiseSqrt();
    fit.robot_poses = Calibration::CornerFit::RobotPoses::Prior;
    fit.robot_prior_sigma = {s.head<3>().maxCoeff(), s.tail<3>().maxCoeff()};
  }
  CornerMethodResult out;
  out.fit = calibrate_corners(samples.rig, *camera, views, pose_level.T_parent_camera, pose_level.pattern->pose, options);
  const CornerCalibration& f = out.fit;
  Calibration& c = out.calibration;
  c = pose_level;
  c.method = Method::Corners;
  c.T_parent_camera = f.X;
  set_pose_covariance(c, f.covariance.topLeftCorner<6, 6>());
  c.pattern = PoseWithCovariance{f.Y, f.covariance.bottomRightCorner<6, 6>()};
  c.cross_covariance = f.covariance.topRightCorner<6, 6>();
  c.samples_used = static_cast<int>(views.size());
  c.noise_components.clear();
  c.residual_checks.clear();
  c.warnings.clear();  // the pose-level fit's
  c.loss = Loss::Squared;
  c.covariance_kind = CovarianceKind::Information;
  c.downweighted = 0;
  c.covariance_inflation = c.pattern_covariance_inflation = 1.0;
  c.noise_origin = f.pixel_sigma_estimated ? NoiseOrigin::EstimatedFromResiduals : NoiseOrigin::Given;
  if (f.robot_noise_estimated) fit.robot_sigma = f.robot_sigma;  // robot_poses Estimated
  c.noise_model.reset();  // the corner fit says it (io::noise_model_text)
  c.rotation_stage.iterations = c.translation_stage.iterations = f.iterations;
  c.rotation_stage.stop_reason = c.translation_stage.stop_reason = StopReason::CostChangeBelowTolerance;
  c.rotation_stage.dof = c.translation_stage.dof = f.degrees_of_freedom;
  c.rotation_stage.chi2 = c.translation_stage.chi2 = f.chi2;
  fit.pixel_sigma = f.pixel_sigma;
  fit.pixel_sigma_estimated = f.pixel_sigma_estimated;
  fit.rms_px = f.rms_px;
  // As the pose-level components count only off their bound: a robot noise the corners
  // held at its floor (both parts) is one they did not support.
  fit.robot_noise_estimated = f.robot_noise_estimated && !(f.robot_at_bound[0] && f.robot_at_bound[1]);
  fit.target_point_sigma = f.target_point_sigma;
  fit.target_point_sigma_estimated = f.target_point_sigma_estimated;
  fit.target_inflation = f.target_inflation;
  for (const ImageReprojection& image : f.images) {
    fit.corners += image.points;
    fit.images.push_back({image.name, image.points, image.rms_px, image.sigma_px});
  }
  fit.per_image_sigma = f.per_image_sigma;
  if (f.homogeneity) {
    const HomogeneityTest& h = *f.homogeneity;
    fit.homogeneity_tested = true, fit.homogeneity_passed = h.passed;
    fit.homogeneity_chi2 = h.chi2, fit.homogeneity_bound = h.bound, fit.homogeneity_dof = h.dof;
  }
  if (f.intrinsics) {
    Calibration::CornerFit::Intrinsics& refined = fit.intrinsics.emplace();
    Eigen::Vector2d* entries[] = {&refined.fx, &refined.fy, &refined.cx, &refined.cy, &refined.k1, &refined.k2};
    for (int k = 0; k < 6; ++k) {
      *entries[k] = {(*f.intrinsics)[k], std::sqrt(std::max(0.0, f.intrinsics_covariance(k, k)))};
    }
  }
  c.corner_fit = fit;
  return out;
}

CornerRefiner corner_refiner(CornerOptions options) {
  return [options](const SampleSet& samples, const Calibration& pose_level, JointOptions::Robust robust) {
    CornerOptions with = options;
    with.robust = robust;
    return refine_with_corners(samples, pose_level, with).calibration;
  };
}

}  // namespace handeye
