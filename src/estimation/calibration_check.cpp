#include "handeye_covariance/estimation/calibration_check.h"

#include <algorithm>
#include <functional>
#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/statistics.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/estimation/joint_estimator.h"
#include "handeye_covariance/estimation/outliers.h"
#include "handeye_covariance/estimation/shared_robot_error.h"

namespace handeye {

namespace {

/// Odds at which the check names X or Y without "or the other": 19 : 1 (95%).
constexpr double kNamingOddsBar = 19.0;
/// The largest canonical cosine between X's and Y's change directions above which
/// the views are said to barely tell the two apart.
constexpr double kAlikeOverlap = 0.95;
/// exp's argument cap for the naming odds (exp(709.8) is the largest double).
constexpr double kLargestOddsExponent = 690.0;

}  // namespace

const char* to_string(ChangedPose pose) {
  switch (pose) {
    case ChangedPose::X: return "X";
    case ChangedPose::Y: return "Y";
    case ChangedPose::Both: return "both";
  }
  return "X";
}

namespace {

double chi2_upper(double statistic, int dof) { return dof <= 0 ? 1.0 : chi2_upper_tail(dof, statistic); }

/// The GLS fit of a change in the columns `H` (whitened: L^-1 J for those parameters,
/// J = d e / d xi) to the whitened residual z: the change that removes z, -(H^T H)^-1 H^T z,
/// as the joint estimator's step (so the new pose is the saved one perturbed by value:
/// t + value_t, exp(value_R) R, pose_covariance.h), its covariance and the chi2 drop.
struct Fit {
  Eigen::VectorXd value;
  Eigen::MatrixXd covariance;
  double drop = 0.0;
};
Fit fit_change(const Eigen::MatrixXd& H, const Eigen::VectorXd& z) {
  const Eigen::MatrixXd information = H.transpose() * H;
  const Eigen::LDLT<Eigen::MatrixXd> solver(information);
  const Eigen::VectorXd g = H.transpose() * z;
  Fit fit;
  fit.value = -solver.solve(g);
  fit.covariance = solver.solve(Eigen::MatrixXd::Identity(information.rows(), information.cols()));
  fit.drop = -g.dot(fit.value);
  return fit;
}

/// An orthonormal basis of H's column space (H has full column rank here).
Eigen::MatrixXd basis(const Eigen::MatrixXd& H) {
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(H);
  return qr.householderQ() * Eigen::MatrixXd::Identity(H.rows(), H.cols());
}

/// One part of the views' noise whose size the calibration estimated: its share of
/// each view's covariance and the dof of its estimate (a variance estimated from nu dof
/// is the true one times chi2(nu) / nu). A part the calibration was given, or whose
/// estimate is exact, has dof 0 and is not drawn.
struct NoisePart {
  std::vector<Matrix6d> per_view;
  double dof = 0.0;
};

/// The calibration's residual model split into its estimated numbers (joint_estimator.h:
/// a camera axis, the camera's translation or rotation, the stated noise's scale, the
/// robot's noise, the view-following scale), each with its dof from its value and 1 sigma
/// (a sigma s estimated from nu dof has 1 sigma s / sqrt(2 nu); a scale c, c sqrt(2 / nu)).
/// What no number covers (the stated noise, a full camera matrix's correlations) is the
/// remainder, known.
std::vector<NoisePart> noise_parts(const SampleSet& views, const Calibration& calibration) {
  const Calibration::ResidualNoise& model = *calibration.residual_noise;
  Calibration::ResidualNoise zero = model;
  zero.camera_scale = 0.0, zero.camera.setZero(), zero.robot.setZero(), zero.view_scale = 0.0;
  Calibration only = calibration;
  only.residual_noise = zero;
  const std::vector<Matrix6d> base = residual_covariances(views, only);  // the stated robot noise alone
  std::vector<NoisePart> parts;
  for (const Calibration::NoiseComponent& c : calibration.noise_components) {
    if (!c.supported || c.value <= 0.0 || c.sigma <= 0.0) continue;
    Calibration::ResidualNoise m = zero;
    const std::string& name = c.name;
    const auto axes = [&](int from, int to) {
      for (int a = from; a < to; ++a) m.camera(a, a) = model.camera(a, a);
    };
    static const char* const axis_names[6] = {"camera x", "camera y", "camera z", "camera rx", "camera ry", "camera rz"};
    bool known = true;
    if (name == "stated camera noise scale") {
      m.camera_scale = model.camera_scale;
    } else if (name == "camera translation") {
      axes(0, 3);
    } else if (name == "camera rotation") {
      axes(3, 6);
    } else if (name == "robot translation") {
      m.robot.topLeftCorner<3, 3>() = model.robot.topLeftCorner<3, 3>();
    } else if (name == "robot rotation") {
      m.robot.bottomRightCorner<3, 3>() = model.robot.bottomRightCorner<3, 3>();
    } else if (name == "view-following image noise") {
      m.view_scale = model.view_scale;
    } else {
      known = false;
      for (int a = 0; a < 6; ++a) {
        if (name == axis_names[a]) axes(a, a + 1), known = true;
      }
    }
    if (!known) continue;  // a correlation: in the remainder
    const double ratio = c.value / c.sigma;
    NoisePart part;
    part.dof = c.unit.empty() ? 2.0 * ratio * ratio : 0.5 * ratio * ratio;
    only.residual_noise = m;
    const std::vector<Matrix6d> with = residual_covariances(views, only);
    for (std::size_t i = 0; i < with.size(); ++i) part.per_view.push_back(with[i] - base[i]);
    parts.push_back(std::move(part));
  }
  return parts;
}

/// The null distribution of max(|Qx^T z|^2, |Qy^T z|^2), z the whitened residual, when
/// nothing changed: z = L^-1 e with e ~ N(0, C_true), C_true the predicted C with each
/// estimated noise part scaled by its draw nu / chi2(nu) (the estimate's own error: what
/// makes a chi2 test on an estimated variance an F test). Only the projections onto the
/// two 6-dof subspaces matter: their span U (r <= 12) carries the draws. Seeded.
class NullDistribution {
 public:
  NullDistribution(const Eigen::MatrixXd& Qx, const Eigen::MatrixXd& Qy, const Eigen::MatrixXd& whiten_known,
                   std::vector<std::pair<Eigen::MatrixXd, double>> whitened_parts)
      : parts_(std::move(whitened_parts)) {
    Eigen::MatrixXd both(Qx.rows(), 12);
    both << Qx, Qy;
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(both, Eigen::ComputeThinU);
    int r = 0;
    const int most = static_cast<int>(svd.singularValues().size());  // 6 for one view
    while (r < most && svd.singularValues()(r) > 1e-8 * svd.singularValues()(0)) ++r;
    U_ = svd.matrixU().leftCols(r);
    ax_ = Qx.transpose() * U_, ay_ = Qy.transpose() * U_;
    known_ = U_.transpose() * whiten_known * U_;
    for (auto& [m, dof] : parts_) m = U_.transpose() * m * U_;
  }

  /// P(max >= t) by Monte-Carlo, sequentially (Besag and Clifford, "Sequential Monte Carlo
  /// p-values", Biometrika 78, 1991): drawing stops at the `null_exceedances`-th draw beyond t,
  /// with p = exceedances / draws; else after `null_draws`, with (beyond + 1) / (draws + 1),
  /// never 0. Either way a valid p-value; a large p costs a few thousand draws, not all of them,
  /// and a p near alpha or below is drawn as finely as before.
  double p_value(double t, const CheckOptions& options) const {
    std::mt19937_64 rng(options.seed);
    std::normal_distribution<double> normal(0.0, 1.0);
    const int r = static_cast<int>(U_.cols());
    const int per_scale = parts_.empty() ? options.null_draws : 10;  // z draws per drawn noise
    const int enough = options.null_exceedances;
    // The draws in blocks of columns, z in the order one at a time would draw them: one
    // matrix product a block instead of a vector product and its temporaries a draw.
    constexpr int kBlock = 256;
    Eigen::MatrixXd W(r, kBlock), S, Sx, Sy;
    int beyond = 0, draws = 0;
    while (draws < options.null_draws && beyond < enough) {
      Eigen::MatrixXd K = known_;
      for (const auto& [m, dof] : parts_) {
        std::chi_squared_distribution<double> chi2(dof);
        K += (dof / std::max(chi2(rng), 1e-12)) * m;
      }
      const Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (K + K.transpose()));
      int left = std::min(per_scale, options.null_draws - draws);  // draws under this K
      while (left > 0 && beyond < enough) {
        const int block = std::min(left, kBlock);
        for (int j = 0; j < block; ++j) {
          for (int a = 0; a < r; ++a) W(a, j) = normal(rng);
        }
        S.noalias() = llt.matrixL() * W.leftCols(block);
        Sx.noalias() = ax_ * S;
        Sy.noalias() = ay_ * S;
        for (int j = 0; j < block && beyond < enough; ++j, ++draws, --left) {
          if (std::max(Sx.col(j).squaredNorm(), Sy.col(j).squaredNorm()) >= t) ++beyond;
        }
      }
    }
    if (beyond >= enough) return static_cast<double>(beyond) / draws;
    return (beyond + 1.0) / (options.null_draws + 1.0);
  }

 private:
  Eigen::MatrixXd U_, ax_, ay_, known_;
  std::vector<std::pair<Eigen::MatrixXd, double>> parts_;
};

/// The new views' residual covariance under the shared robot error, beside their own
/// noise s S_i (shared_robot_error.h): about the per-view X and Y, whose error is
/// -H0 eps over the old views' errors eps, a new view's residual is e_i - J_i H0 eps, so
///   Cov = K_new + J P J^T - J M - (J M)^T,
/// K_new the kernel among the new views, P = H0 C H0^T the per-view estimate's covariance
/// under the model, and M's block i = H0 Cov(eps, e_i) = sum_j k(p_j, p_i) H0_j D_j E D_i^T
/// (E = diag(a I3, b I3)): the old views near a new one share its robot error, which the
/// per-view estimate took in. `D` each new view's D_i, `J` their stacked Jacobian.
Eigen::MatrixXd shared_error_prediction(const Calibration::SharedError& shared, const SampleSet& new_views,
                                        const std::vector<Matrix6d>& D, const Eigen::MatrixXd& J) {
  const int k = static_cast<int>(D.size());
  const double l = shared.length_scale;
  const auto kernel = [l](const Eigen::Vector3d& p, const Eigen::Vector3d& q) { return shared_error_kernel(p, q, l); };
  const Matrix6d E = shared_error_covariance(model_of(shared));
  Eigen::MatrixXd C = J * per_view_estimate_joint_covariance(shared) * J.transpose();
  Eigen::MatrixXd M(12, 6 * k);
  for (int i = 0; i < k; ++i) {
    const Eigen::Vector3d p = new_views.samples[static_cast<std::size_t>(i)].T_base_effector.translation();
    for (int m = 0; m < k; ++m) {
      const Eigen::Vector3d q = new_views.samples[static_cast<std::size_t>(m)].T_base_effector.translation();
      C.block<6, 6>(6 * i, 6 * m) += kernel(p, q) * D[static_cast<std::size_t>(i)] * E * D[static_cast<std::size_t>(m)].transpose();
    }
    Eigen::Matrix<double, 12, 6> G = Eigen::Matrix<double, 12, 6>::Zero();
    for (const Calibration::SharedError::View& old : shared.views) G += kernel(old.position, p) * old.gain;
    M.middleCols<6>(6 * i) = G * E * D[static_cast<std::size_t>(i)].transpose();
  }
  const Eigen::MatrixXd JM = J * M;
  C -= JM + JM.transpose();
  return C;
}

EstimatedChange::Delta delta_of(const Fit& fit, int offset) {
  EstimatedChange::Delta d;
  d.value = fit.value.segment<6>(offset);
  d.covariance = fit.covariance.block<6, 6>(offset, offset);
  d.covariance = 0.5 * (d.covariance + d.covariance.transpose());
  return d;
}

}  // namespace

void require_checkable(const Calibration& calibration) {
  if (calibration.pattern && calibration.residual_noise) return;
  throw HandEyeError(ErrorCode::NoiseUnidentifiable,
                     "the calibration carries no pattern pose Y or no noise model: a check predicts each new view from "
                     "X, Y and the noise their covariance was computed with",
                     "the calibration",
                     "save it again with this version (`handeye solve`, `handeye images`, the node's /save_calibration): "
                     "its result file has `pattern`, `cross_covariance` and `noise.residual_model`");
}

bool prediction_disagrees(const Calibration::Prediction& p) { return p.dof > 0.0 && p.scale > 1.0; }

std::optional<Calibration::Prediction> prediction_check(
    const SampleSet& samples, const std::function<Calibration(const SampleSet&)>& solve) {
  // From 4 views: 3 are the fewest that calibrate, and a 4-view calibration's model
  // prediction is the one most in need of it (test_calibration_check's
  // FalseAlarmsOfAFourViewCalibration: about 6% at alpha 1% without it).
  const std::size_t n = samples.samples.size();
  if (n < 4) return std::nullopt;
  std::vector<double> d2;  // each view's squared Mahalanobis length over 6
  for (std::size_t i = 0; i < n; ++i) {
    SampleSet others = samples;
    others.samples.erase(others.samples.begin() + static_cast<std::ptrdiff_t>(i));
    const SampleSet one{samples.rig, samples.noise, {samples.samples[i]}};
    Calibration c;
    try {
      c = solve(others);
    } catch (const HandEyeError&) {
      continue;  // too few turns without it: no prediction from the others
    }
    if (!c.pattern || !c.residual_noise) return std::nullopt;  // not a joint calibration
    const JointResidual r = joint_residual(samples.rig, one.samples[0], c.T_parent_camera, c.pattern->pose);
    const Matrix6d C = residual_covariances(one, c)[0] + r.jacobian * joint_covariance(c) * r.jacobian.transpose();
    const double d = r.error.dot(C.ldlt().solve(r.error)) / 6.0;
    if (std::isfinite(d)) d2.push_back(d);  // a degenerate left-out fit predicts nothing
  }
  if (d2.size() < 4) return std::nullopt;
  const double m = static_cast<double>(d2.size());
  double mean = 0.0, spread = 0.0;
  for (double v : d2) mean += v / m;
  for (double v : d2) spread += (v - mean) * (v - mean) / (m - 1.0);
  Calibration::Prediction p;
  p.views = static_cast<int>(d2.size());
  p.scale = mean;
  // The mean of m values of chi2(6) / 6 (variance 1 / 3) has 6 m dof; heavier tails fewer.
  // Its variance is spread / m; a scale s estimated from nu dof has variance 2 s^2 / nu.
  p.dof = std::min(6.0 * m, 2.0 * mean * mean * m / std::max(spread, 1e-12));
  return p;
}

namespace {

/// `shared`: the robot error shared by nearby poses that the calibration uses
/// (shared_robot_error.h), with the views it was fitted on, or null; `shared_inflation`
/// its own honesty check's factor.
// Over 150 lines: the views' predicted covariance, its whitening and the three hypotheses' fits share C's Cholesky factor and the whitened noise parts.
CalibrationCheck check_all(const Calibration& calibration, const SampleSet& views, const CheckOptions& options,
                           const Calibration::SharedError* shared, double shared_inflation) {
  require_checkable(calibration);
  const int k = static_cast<int>(views.samples.size());
  if (k == 0) {
    throw HandEyeError(ErrorCode::NoData, "no new view to check the calibration with", "the views",
                       "take a few views (5 is the figure the check is measured at) the calibration has not seen");
  }
  if (!(options.alpha > 0.0 && options.alpha < 1.0) || options.null_draws < 100 || options.null_exceedances < 10) {
    throw HandEyeError(ErrorCode::MalformedFile, "alpha must be in (0, 1), the null draws at least 100 and the exceedances that stop them at least 10", "check options",
                       "use alpha = 0.01 (a false alarm in 100 checks)");
  }
  const Eigen::Isometry3d& X = calibration.T_parent_camera;
  const Eigen::Isometry3d& Y = calibration.pattern->pose;
  // A symmetric target: each view's pose is one of two candidates 180 degrees apart;
  // the calibration predicts which (a wrong one is off by about pi, far beyond any noise).
  std::vector<int> turned;
  SampleSet decided = views;
  // Views without a stated noise take the calibration's, when it was given (an estimated
  // noise is in its residual model already).
  if (!decided.noise && calibration.noise_origin == NoiseOrigin::Given) decided.noise = calibration.noise;
  if (views.rig.symmetric_face) {
    const Eigen::Isometry3d F = views.rig.face_half_turn();
    for (std::size_t i = 0; i < decided.samples.size(); ++i) {
      PoseSample other = decided.samples[i];
      other.T_camera_pattern = other.T_camera_pattern * F;
      other.corners = nullptr;  // the corners' order belongs to the detected candidate
      const double as_detected = joint_residual(views.rig, decided.samples[i], X, Y).error.tail<3>().norm();
      const double as_turned = joint_residual(views.rig, other, X, Y).error.tail<3>().norm();
      if (as_turned < as_detected) {
        decided.samples[i] = other;
        turned.push_back(static_cast<int>(i));
      }
    }
  }
  double inflation = shared ? std::max(1.0, shared_inflation)
                            : calibration.honesty ? std::max(1.0, calibration.honesty->inflation) : 1.0;
  std::vector<Matrix6d> noise = residual_covariances(decided, calibration);
  // The estimated noise parts: the views' noise is the known remainder plus each part
  // times its true-over-estimated ratio g ~ nu / chi2(nu), whose mean nu / (nu - 2) the
  // prediction takes (a variance estimated from few dof is more often too small than
  // too large, for the inverse). nu is floored at kMinimumDof: below it the delta
  // method's dof says only that the number is poorly known, and an inverse chi2 of
  // under 5 dof has no variance.
  // A calibration whose own views, left out in turn, scatter more than it predicts
  // (prediction_disagrees) replaces all of that: the whole predicted covariance is scaled
  // by what its views showed, a scale known to its dof, and the honesty check's inflation
  // is not applied a second time. One whose views scatter less keeps its model: a scale
  // measured from a few views is not trusted to make the check stricter.
  constexpr double kMinimumDof = 5.0;
  const auto expected_ratio = [](double dof) { return dof / (dof - 2.0); };
  std::vector<NoisePart> parts;
  double prediction_scale = 1.0;
  // Under the shared robot error the leave-one-out scale (the per-view model's) does not apply.
  const bool use_prediction = !shared && calibration.prediction && prediction_disagrees(*calibration.prediction);
  if (use_prediction) {
    prediction_scale = calibration.prediction->scale;
    inflation = 1.0;
  } else {
    parts = noise_parts(decided, calibration);
    for (NoisePart& part : parts) part.dof = std::max(part.dof, kMinimumDof);
  }
  if (shared) {  // the per-view S_i times the model's s
    for (Matrix6d& S : noise) S *= shared->view_noise_scale;
    for (NoisePart& part : parts) {
      for (Matrix6d& m : part.per_view) m *= shared->view_noise_scale;
    }
  }

  const int n = 6 * k;
  Eigen::VectorXd e(n);
  Eigen::MatrixXd J(n, 12), C = Eigen::MatrixXd::Zero(n, n);
  std::vector<Matrix6d> D;  // each view's D_i = d P_hat_i / d xi_E (the robot error's pull on it)
  for (int i = 0; i < k; ++i) {
    const std::size_t v = static_cast<std::size_t>(i);
    const JointResidual r = joint_residual(views.rig, decided.samples[v], X, Y);
    e.segment<6>(6 * i) = r.error;
    J.middleRows<6>(6 * i) = r.jacobian;
    D.push_back(r.d_effector);
    Matrix6d S = noise[v];
    for (const NoisePart& part : parts) S += (expected_ratio(part.dof) - 1.0) * part.per_view[v];
    C.block<6, 6>(6 * i, 6 * i) = inflation * S;
  }
  if (shared) {
    C += inflation * shared_error_prediction(*shared, decided, D, J);
  } else {
    C += J * joint_covariance(calibration) * J.transpose();
  }
  C = 0.5 * (C + C.transpose());
  const Eigen::MatrixXd C_model = C;
  if (use_prediction) C *= prediction_scale * expected_ratio(std::max(calibration.prediction->dof, kMinimumDof));
  const Eigen::LLT<Eigen::MatrixXd> llt(C);
  if (llt.info() != Eigen::Success) {
    throw HandEyeError(ErrorCode::InvalidNoise,
                       "the new views' predicted residual covariance is not positive definite: neither the views nor the "
                       "calibration's noise model say how noisy a view is",
                       "the calibration's noise model",
                       "give the views' noise (a `noise:` block, or detections with their covariance), or solve the "
                       "calibration with its noise estimated (no `noise:` block) so that its model carries it");
  }
  const auto whiten = [&](const Eigen::MatrixXd& M) {
    return Eigen::MatrixXd(llt.matrixL().solve(Eigen::MatrixXd(llt.matrixL().solve(M).transpose())).transpose());
  };
  const Eigen::VectorXd z = llt.matrixL().solve(e);
  const Eigen::MatrixXd H = llt.matrixL().solve(J);
  // Whitened as z is: I = known + sum of E[g] part; the null draws g for each part.
  std::vector<std::pair<Eigen::MatrixXd, double>> whitened_parts;
  Eigen::MatrixXd known_white = Eigen::MatrixXd::Identity(n, n);
  for (const NoisePart& part : parts) {
    Eigen::MatrixXd block = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < k; ++i) block.block<6, 6>(6 * i, 6 * i) = inflation * part.per_view[static_cast<std::size_t>(i)];
    const Eigen::MatrixXd white = whiten(block);
    known_white -= expected_ratio(part.dof) * white;
    whitened_parts.emplace_back(white, part.dof);
  }
  if (use_prediction) {  // one part: all of C, scaled by the measured prediction
    const double dof = std::max(calibration.prediction->dof, kMinimumDof);
    const Eigen::MatrixXd white = whiten(prediction_scale * C_model);
    known_white -= expected_ratio(dof) * white;
    whitened_parts.emplace_back(white, dof);
  }

  CalibrationCheck check;
  check.turned = turned;
  check.alpha = options.alpha;
  check.dof = n;
  check.chi2 = z.squaredNorm();
  check.chi2_p_value = chi2_upper(check.chi2, n);
  for (int i = 0; i < k; ++i) {
    CheckedView v;
    v.residual = e.segment<6>(6 * i);
    v.predicted_covariance = C.block<6, 6>(6 * i, 6 * i);
    v.translation_error = v.residual.head<3>().norm();
    v.rotation_error = v.residual.tail<3>().norm();
    v.predicted_translation_sigma = std::sqrt(v.predicted_covariance.topLeftCorner<3, 3>().trace());
    v.predicted_rotation_sigma = std::sqrt(v.predicted_covariance.bottomRightCorner<3, 3>().trace());
    v.mahalanobis = std::sqrt(std::max(0.0, v.residual.dot(v.predicted_covariance.ldlt().solve(v.residual))));
    check.views.push_back(v);
  }

  // The three hypotheses. With one view X and Y cannot be told apart (J_X and J_Y span
  // the same 6 directions); the fits then share the drop and "both" is singular.
  const Eigen::MatrixXd Hx = H.leftCols<6>(), Hy = H.rightCols<6>();
  const Fit fx = fit_change(Hx, z), fy = fit_change(Hy, z);
  const bool x_larger = fx.drop >= fy.drop;  // the larger single change, the one a verdict names
  const Fit& larger = x_larger ? fx : fy;
  if (k > 2) {  // view i's own 6 numbers beside the change (with 2 views the 12 fit everything)
    Eigen::MatrixXd with_view(n, 12);
    with_view.leftCols<6>() = x_larger ? Hx : Hy;
    for (int i = 0; i < k; ++i) {
      Eigen::MatrixXd own = Eigen::MatrixXd::Zero(n, 6);
      own.middleRows<6>(6 * i).setIdentity();
      with_view.rightCols<6>() = llt.matrixL().solve(own);
      check.views[static_cast<std::size_t>(i)].chi2_beyond_the_change = fit_change(with_view, z).drop - larger.drop;
    }
  }
  const auto hypothesis = [&](ChangedPose what, const Fit& fit, int dof) {
    EstimatedChange c;
    c.what = what;
    c.chi2_drop = fit.drop;
    c.dof = dof;
    c.residual_chi2 = std::max(0.0, check.chi2 - fit.drop);
    c.residual_p_value = chi2_upper(c.residual_chi2, n - dof);
    return c;
  };
  check.X_alone = hypothesis(ChangedPose::X, fx, 6);
  check.X_alone.X_change = delta_of(fx, 0);
  check.Y_alone = hypothesis(ChangedPose::Y, fy, 6);
  check.Y_alone.Y_change = delta_of(fy, 0);
  const bool both_identified = n > 12;
  if (both_identified) {
    const Fit fxy = fit_change(H, z);
    check.both = hypothesis(ChangedPose::Both, fxy, 12);
    check.both.X_change = delta_of(fxy, 0);
    check.both.Y_change = delta_of(fxy, 6);
  }

  check.statistic = std::max(fx.drop, fy.drop);
  const Eigen::MatrixXd Qx = basis(Hx), Qy = basis(Hy);
  const Eigen::JacobiSVD<Eigen::MatrixXd> angles(Qx.transpose() * Qy);
  check.x_y_cosines = angles.singularValues().head<6>();
  check.x_y_overlap = check.x_y_cosines(0);
  check.p_value = NullDistribution(Qx, Qy, known_white, whitened_parts).p_value(check.statistic, options);
  check.changed = check.p_value < options.alpha;
  const EstimatedChange& single = x_larger ? check.X_alone : check.Y_alone;
  check.naming_odds = std::exp(std::min(0.5 * std::abs(fx.drop - fy.drop), kLargestOddsExponent));
  const bool second_explains = both_identified && check.both.chi2_drop - single.chi2_drop > chi2_quantile(6, 1.0 - options.alpha);
  check.change = second_explains ? check.both : single;

  // Beyond every null draw: the Monte-Carlo says only that p is below its resolution.
  check.p_below_resolution = check.p_value <= 1.0001 / (options.null_draws + 1.0);
  check.naming_uncertain = check.changed && check.change.what != ChangedPose::Both && check.naming_odds < kNamingOddsBar;
  using Finding = CalibrationCheck::Finding;
  if (check.changed) {
    check.findings.push_back(check.change.what == ChangedPose::Y ? Finding::TargetMoved : Finding::CameraMoved);
    if (check.change.residual_p_value < options.alpha) check.findings.push_back(Finding::ResidualBeyondChange);
  } else if (check.chi2_p_value < options.alpha) {
    check.findings.push_back(Finding::ScatterBeyondNoise);
  }
  if (check.naming_uncertain || (check.changed && check.x_y_overlap > kAlikeOverlap)) check.findings.push_back(Finding::XAndYAlike);
  // A noise model fitted from few views predicts too narrow (FalseAlarmsOfAFourViewCalibration:
  // about 6% at alpha 1% from 4 views); only the leave-one-out scale measures that.
  if (!shared && !calibration.prediction && !calibration.noise_components.empty()) check.findings.push_back(Finding::NoPrediction);
  if (k < 3) check.findings.push_back(Finding::FewViews);
  return check;
}

}  // namespace

CalibrationCheck check_calibration(const Calibration& used, const SampleSet& views, const CheckOptions& options) {
  // A calibration whose X is the shared robot error's GLS estimate is checked about the
  // per-view model's X and Y kept beside it, under the model: a new view shares the
  // robot error of the old poses near it, which the per-view estimate took in, and the
  // record's `views` (each old view's position and H0_j D_j) give that correlation
  // (shared_error_prediction). A record without them (a file of an earlier version) is
  // checked with the per-view model alone, its inflation and leave-one-out scale.
  const Calibration calibration = per_view_calibration(used);
  const Calibration::SharedError* shared =
      used.shared_robot_error && used.shared_robot_error->used && !used.shared_robot_error->views.empty()
          ? &*used.shared_robot_error
          : nullptr;
  if (shared) require_predictable(*shared, "the calibration's shared_robot_error");
  const double shared_inflation = used.honesty ? used.honesty->inflation : 1.0;
  CalibrationCheck check = check_all(calibration, views, options, shared, shared_inflation);
  // One wrong detection is not a moved camera: a view beyond the outlier gate alone
  // (outliers.h, chi2(6) 0.9999) whose leaving out leaves the others consistent is left
  // out and named, as the calibration leaves out its own; a real change moves every view.
  // Only when it stays beyond the gate once the change is fitted (chi2_beyond_the_change):
  // a real change that shows most in one view is explained there too, and leaving that
  // view out cost 0.4-1.3% of 5-sigma changes (handeye_check_study's left_out).
  if (!check.changed || views.samples.size() < 2) return check;
  std::size_t worst = 0;
  for (std::size_t i = 1; i < check.views.size(); ++i) {
    if (check.views[i].mahalanobis > check.views[worst].mahalanobis) worst = i;
  }
  const double gate = OutlierOptions{}.residual_gate;
  if (check.views[worst].mahalanobis * check.views[worst].mahalanobis <= gate) return check;
  if (views.samples.size() > 2 && check.views[worst].chi2_beyond_the_change <= gate) return check;
  SampleSet rest = views;
  rest.samples.erase(rest.samples.begin() + static_cast<std::ptrdiff_t>(worst));
  CalibrationCheck without = check_all(calibration, rest, options, shared, shared_inflation);
  if (without.changed) return check;
  without.views = check.views;  // the table keeps every view, the left-out one marked
  without.left_out = {static_cast<int>(worst)};
  without.findings.insert(without.findings.begin(), CalibrationCheck::Finding::LeftOutView);
  return without;
}

}  // namespace handeye
