// Targets that look the same turned by 180 degrees (a chessboard of 9 x 7 inner
// corners): each view's pose is one of two candidates, P or P * F, decided from the
// robot's motion (estimation/symmetric_views.h).
//
//  - The target's half turn (core/target.h).
//  - The pairs' synchronisation and the refinement on simulated pose sessions with
//    planted turns and wrong detections: a wrong early label does not lock in.
//  - The real sessions of ../shared/realdata (read from there, never copied), each
//    view's detected pose turned at random: every turn decided back, X unchanged.
//  - Rendered sessions of a symmetric board with its in-plane roll over the full
//    circle (the detector's candidate then arbitrary): decided right, X honest.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/estimation/outliers.h"
#include "handeye_covariance/estimation/solve.h"
#include "handeye_covariance/estimation/symmetric_views.h"
#include "handeye_covariance/images/image_folder.h"
#include "handeye_covariance/images/pooled_detector.h"
#include "handeye_covariance/io/warning_text.h"
#include "handeye_covariance/io/yaml_io.h"
#include "realdata.h"
#include "handeye_covariance/session/calibration_session.h"
#include "handeye_covariance/simulation/pattern_renderer.h"
#include "test_helpers.h"

namespace handeye {
namespace {

namespace fs = std::filesystem;

using test::realdata;

/// The decided labels against the planted ones, up to the global turn (which
/// moves Y only): the number that agree with the nearer of the two readings.
int agreeing(const std::vector<bool>& decided, const std::vector<bool>& planted) {
  int same = 0;
  for (std::size_t i = 0; i < planted.size(); ++i) same += decided[i] == planted[i] ? 1 : 0;
  return std::max(same, static_cast<int>(planted.size()) - same);
}

/// Why a view was left out, in the words a user reads (io::rejected_text).
std::string reason(const TurnDecision& d, const TurnDecision::Undecided& u) {
  return io::rejected_text(undecided_rejection(d, u));
}

std::string reasons(const TurnDecision& d) {
  std::string text;
  for (const TurnDecision::Undecided& u : d.undecided) text += "\n  view " + std::to_string(u.index) + ": " + reason(d, u);
  return text;
}

/// A detection of the other candidate: P F, with the covariance a detector gives
/// in that frame (its origin a lever arm away: compose_jacobian_left(P, F)).
PoseSample turned(const PoseSample& sample, const Eigen::Isometry3d& F, const std::optional<MeasurementNoise>& global) {
  PoseSample out = sample;
  out.T_camera_pattern = sample.T_camera_pattern * F;
  if (const std::optional<MeasurementNoise>& stated = sample.noise ? sample.noise : global) {
    const Matrix6d J = compose_jacobian_left(sample.T_camera_pattern, F);
    out.noise = *stated;
    out.noise->camera = PoseNoise::from_pose_covariance(J * stated->camera.as_pose_covariance() * J.transpose());
  }
  return out;
}

/// Each view turned with probability 1/2.
SampleSet planted_turns(const SampleSet& samples, const Eigen::Isometry3d& F, Rng& rng, std::vector<bool>& planted) {
  SampleSet out = samples;
  std::bernoulli_distribution coin(0.5);
  planted.assign(samples.samples.size(), false);
  for (std::size_t i = 0; i < out.samples.size(); ++i) {
    planted[i] = coin(rng);
    if (planted[i]) out.samples[i] = turned(samples.samples[i], F, samples.noise);
  }
  return out;
}

/// The session as `handeye images` and the node calibrate it (test_images): the
/// detector's covariances, the missing noise estimated, outlier rejection on.
Calibration calibrate_in_a_session(const SampleSet& set) {
  SessionSettings settings = session_settings(set);
  settings.session_file.clear();
  CalibrationSession session(settings);
  session.replace(set.samples, "samples");
  return session.calibrate(session.snapshot());
}

// ------------------------------------------------------------------ the target

TEST(HalfTurn, ASymmetricChessboardsTurnMapsItsCornersOntoEachOther) {
  EXPECT_TRUE(is_half_turn_symmetric(make_target(ChessboardTarget{9, 7, 0.025})));
  EXPECT_TRUE(is_half_turn_symmetric(make_target(ChessboardTarget{8, 6, 0.025})));
  EXPECT_FALSE(is_half_turn_symmetric(make_target(ChessboardTarget{9, 6, 0.025})));
  EXPECT_FALSE(is_half_turn_symmetric(make_target(CharucoTarget{8, 6, 0.03, 0.022, "DICT_5X5_100"})));
  EXPECT_FALSE(is_half_turn_symmetric(make_target(single_tag_layout(0, 0.1))));
  EXPECT_TRUE(half_turn(make_target(ChessboardTarget{9, 6, 0.025})).isApprox(Eigen::Isometry3d::Identity()));

  const ChessboardTarget board{9, 7, 0.025};
  const Target target = make_target(board);
  const Eigen::Isometry3d F = half_turn(target);
  EXPECT_TRUE((F * F).isApprox(Eigen::Isometry3d::Identity(), 1e-15));
  EXPECT_NEAR(Eigen::AngleAxisd(F.linear()).angle(), M_PI, 1e-12);
  // About the face's normal through its centre: the centre stays, the normal too.
  const Eigen::Isometry3d face = target_face(target);
  EXPECT_LT((F * face.translation() - face.translation()).norm(), 1e-15);
  EXPECT_LT((F.linear() * face.linear().col(2) - face.linear().col(2)).norm(), 1e-15);
  // Corner (c, r) <-> (columns - 1 - c, rows - 1 - r), row-major: k <-> n - 1 - k (to
  // rounding: the decision moves a turned view's corners onto the target's own).
  const int n = board.columns * board.rows;
  std::vector<Eigen::Vector3d> corners;
  for (int r = 0; r < board.rows; ++r)
    for (int c = 0; c < board.columns; ++c) corners.emplace_back(c * board.square, r * board.square, 0.0);
  for (int k = 0; k < n; ++k) EXPECT_LT((F * corners[k] - corners[n - 1 - k]).norm(), 1e-15) << k;
  // Any target's face turn, for the tests that plant the ambiguity.
  const Target tag = make_target(single_tag_layout(10, 0.048));
  EXPECT_TRUE(half_turn(tag).isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_TRUE((face_half_turn(tag) * face_half_turn(tag)).isApprox(Eigen::Isometry3d::Identity(), 1e-12));
}

// ------------------------------------------------------- simulated pose sessions

struct PoseCase {
  SimulatedSession truth;
  SampleSet planted;          // the detected poses, some turned, two wrong
  std::vector<bool> turned;   // which were turned
  std::vector<int> wrong;     // the wrong detections
};

/// 20 views of a session with the detector's noise (test::sim_noise), each turned
/// by F at random, and two wrong detections: a pose 40 mm and 3 degrees off.
PoseCase pose_case(Setup setup, std::uint64_t seed, const Eigen::Isometry3d& F) {
  Rng rng(seed);
  PoseCase c;
  c.truth = simulate_session(rng, setup, typical_X(setup), 20, test::sim_noise());
  c.planted = planted_turns(c.truth.samples, F, rng, c.turned);
  c.wrong = {5, 13};
  for (int w : c.wrong) {
    Vector6d off;
    off << 0.04, -0.02, 0.01, 0.03, 0.04, -0.02;
    c.planted.samples[w].T_camera_pattern = test::apply(c.planted.samples[w].T_camera_pattern, off);
  }
  return c;
}

bool is_wrong(const PoseCase& c, int i) { return std::find(c.wrong.begin(), c.wrong.end(), i) != c.wrong.end(); }

TEST(HalfTurn, PairsSynchroniseThePlantedTurnsPastWrongDetections) {
  const Eigen::Isometry3d F = half_turn(make_target(ChessboardTarget{9, 7, 0.025}));
  for (const handeye::Setup setup : {handeye::Setup::EyeInHand, handeye::Setup::EyeToHand}) {
    for (std::uint64_t seed = 1; seed <= 10; ++seed) {
      const PoseCase c = pose_case(setup, seed, F);
      const TurnSynchronisation s = synchronise_half_turns(c.planted, F);
      std::vector<bool> decided, planted;
      for (std::size_t i = 0; i < c.turned.size(); ++i) {
        if (is_wrong(c, static_cast<int>(i))) continue;
        decided.push_back(s.turned[i]);
        planted.push_back(c.turned[i]);
      }
      EXPECT_EQ(agreeing(decided, planted), static_cast<int>(planted.size())) << to_string(setup) << " seed " << seed;
      // The wrong detections' pairs fit neither hypothesis; the rest decide.
      EXPECT_GE(s.misfit_pairs, 18) << seed;
      EXPECT_GT(s.decisive_pairs, s.pairs / 2) << seed;
      if (seed == 1) {
        std::printf("%s: %d pairs, %d decisive, %d undecidable, %d fit neither; robust sigma %.4f deg, %.3f mm\n",
                    to_string(setup), s.pairs, s.decisive_pairs, s.undecidable_pairs, s.misfit_pairs,
                    s.angle_sigma * 180 / M_PI, s.pitch_sigma * 1e3);
      }
    }
  }
}

TEST(HalfTurn, TheFitDecidesEveryViewAndNamesTheWrongDetections) {
  const Eigen::Isometry3d F = half_turn(make_target(ChessboardTarget{9, 7, 0.025}));
  for (const handeye::Setup setup : {handeye::Setup::EyeInHand, handeye::Setup::EyeToHand}) {
    for (std::uint64_t seed = 1; seed <= 10; ++seed) {
      const PoseCase c = pose_case(setup, seed, F);
      const TurnDecision d = decide_half_turns(c.planted, F);
      ASSERT_EQ(d.undecided.size(), c.wrong.size()) << reasons(d);
      for (std::size_t k = 0; k < c.wrong.size(); ++k) {
        EXPECT_EQ(d.undecided[k].index, c.wrong[k]);
        EXPECT_FALSE(d.undecided[k].both_fit) << reason(d, d.undecided[k]);
      }
      std::vector<bool> decided, planted;
      for (int i : d.kept) {
        decided.push_back(d.turned[i]);
        planted.push_back(c.turned[i]);
      }
      EXPECT_EQ(agreeing(decided, planted), static_cast<int>(planted.size())) << seed;
      EXPECT_LE(2 * d.turned_count, static_cast<int>(d.kept.size()));  // normalised
      // The decided samples are the truth's views (or all turned: Y moves, X does not).
      const Calibration x = estimate(d.samples, Method::Joint);
      const Vector6d e = test::pose_perturbation(x.T_parent_camera, c.truth.X);
      EXPECT_LT(e.dot(x.pose_covariance.ldlt().solve(e)), 30.0) << seed;  // chi2(6) 99.999%: 33
      if (seed == 1) std::printf("%s: %d rounds, gate %.2f sigma%s\n", to_string(setup), d.rounds, d.gate_sigmas, reasons(d).c_str());
    }
  }
}

// A wrong early choice must not lock in: the refinement started from labels of
// which 5 of 18 are wrong (and the two wrong detections), or from every label as
// detected (about half wrong), decides every view right.
TEST(HalfTurn, WrongStartingLabelsDoNotLockIn) {
  const Eigen::Isometry3d F = half_turn(make_target(ChessboardTarget{9, 7, 0.025}));
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const PoseCase c = pose_case(Setup::EyeInHand, seed, F);
    std::vector<bool> start = c.turned;
    for (int i : {0, 3, 8, 11, 17}) start[i] = !start[i];
    const TurnDecision d = refine_half_turns(c.planted, F, start);
    EXPECT_EQ(d.undecided.size(), 2u) << reasons(d);
    std::vector<bool> decided, planted;
    for (int i : d.kept) {
      decided.push_back(d.turned[i]);
      planted.push_back(c.turned[i]);
    }
    EXPECT_EQ(agreeing(decided, planted), static_cast<int>(planted.size())) << seed;
    EXPECT_EQ(d.kept.size(), 18u) << seed;
    // Every label as detected (about half of them wrong): still decided right.
    const TurnDecision all_as_detected = refine_half_turns(c.planted, F, std::vector<bool>(20, false));
    decided.clear(), planted.clear();
    for (int i : all_as_detected.kept) {
      decided.push_back(all_as_detected.turned[i]);
      planted.push_back(c.turned[i]);
    }
    EXPECT_EQ(all_as_detected.kept.size(), 18u) << seed << reasons(all_as_detected);
    EXPECT_EQ(agreeing(decided, planted), static_cast<int>(planted.size())) << seed;
  }
}

// A view decided turned carries what a detection of that candidate would: its
// covariance moved to the turned frame's origin (and back, exactly, for a planted
// turn), its corners in the turned frame on the target's own points and ids.
TEST(HalfTurn, ATurnedViewsNoiseAndCornersFollowItsFrame) {
  const ChessboardTarget board{9, 7, 0.025};
  const Eigen::Isometry3d F = half_turn(make_target(board));
  Rng rng(7);
  const SimulatedSession truth = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 12, test::sim_noise());
  auto corners = std::make_shared<TargetCorners>();
  for (int r = 0; r < board.rows; ++r) {
    for (int c = 0; c < board.columns; ++c) {
      corners->points.object.emplace_back(c * board.square, r * board.square, 0.0);
      corners->points.image.emplace_back(10.0 * c, 10.0 * r);  // not looked at here
      corners->points.ids.push_back(r * board.columns + c);
    }
  }
  SampleSet detected = truth.samples;
  for (PoseSample& s : detected.samples) s.corners = corners;
  SampleSet planted = detected;
  planted.samples[0] = turned(detected.samples[0], F, detected.noise);
  const TurnDecision d = decide_half_turns(planted, F);
  ASSERT_TRUE(d.undecided.empty()) << reasons(d);
  ASSERT_EQ(d.kept.size(), detected.samples.size());
  EXPECT_EQ(d.turned_count, 1);
  ASSERT_TRUE(d.turned[0]);
  const PoseSample& back = d.samples.samples[0];
  EXPECT_LT(test::pose_perturbation(back.T_camera_pattern, detected.samples[0].T_camera_pattern).norm(), 1e-15);
  const Matrix6d given = detected.noise->camera.as_pose_covariance(), now = back.noise->camera.as_pose_covariance();
  EXPECT_LT((now - given).norm(), 1e-12 * given.norm());
  // The planted view's own covariance was moved: its translation error grew by the
  // rotation error over the lever arm to the opposite corner (0.2 x 0.15 m away).
  EXPECT_GT(planted.samples[0].noise->camera.translation.trace(), 1.01 * detected.noise->camera.translation.trace());
  // Its corners: the planted view's were left as detected, so turning back maps
  // corner k onto the target's corner n - 1 - k, coordinates and id exact.
  const int n = board.columns * board.rows;
  ASSERT_TRUE(back.corners);
  for (int k = 0; k < n; ++k) {
    EXPECT_EQ(back.corners->points.object[k], corners->points.object[n - 1 - k]) << k;
    EXPECT_EQ(back.corners->points.ids[k], n - 1 - k) << k;
  }
  EXPECT_EQ(d.samples.samples[1].corners, corners);  // a view as detected keeps its own
}

TEST(HalfTurn, RefusesByName) {
  const PoseCase c = pose_case(Setup::EyeInHand, 1, half_turn(make_target(ChessboardTarget{9, 7, 0.025})));
  const auto code_of = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const HandEyeError& e) {
      return e.code();
    }
    return ErrorCode::NoData;  // "accepted"
  };
  const Eigen::Isometry3d quarter = se3::make_pose(so3::exp(Eigen::Vector3d(0, 0, M_PI / 2)), Eigen::Vector3d::Zero());
  EXPECT_EQ(code_of([&] { decide_half_turns(c.planted, quarter); }), ErrorCode::InvalidLayout);
  EXPECT_EQ(code_of([&] { refine_half_turns(c.planted, half_turn(make_target(ChessboardTarget{9, 7, 0.025})), {true}); }),
            ErrorCode::WrongLength);
  SampleSet bad = c.planted;
  bad.samples[2].T_camera_pattern.translation().x() = NAN;
  EXPECT_EQ(code_of([&] { decide_half_turns(bad, half_turn(make_target(ChessboardTarget{9, 7, 0.025}))); }),
            ErrorCode::NonFinite);
  // A target without the ambiguity: every sample as it is, no solve.
  const TurnDecision d = decide_half_turns(c.planted, Eigen::Isometry3d::Identity());
  EXPECT_EQ(d.kept.size(), c.planted.samples.size());
  EXPECT_EQ(d.turned_count, 0);
}

// ------------------------------------------------------------------ real sessions

struct RealCase {
  const char* name;
  fs::path dir;
  Setup setup;
  Target target;
};

// Every real session, each view's detected pose turned by the target face's half
// turn at random (the ambiguity planted, whether or not the target has it): every
// turn is decided back, none left out, and X from the decided samples is X from
// the detected ones (outlier rejection on, as the node) to 1e-6 of its sigma.
TEST(HalfTurn, RealSessionsWithPlantedTurnsAreDecidedBack) {
  const fs::path root = realdata();
  ASSERT_TRUE(fs::exists(root / "visp-franka")) << "the real data is not at " << root
                                                 << ": put shared/realdata beside the repository, or set HANDEYE_REALDATA";
  const RealCase cases[] = {
      {"visp-franka eye-to-hand AprilTag", root / "visp-franka" / "data-eye-to-hand", Setup::EyeToHand,
       make_target(single_tag_layout(10, 0.048))},
      {"visp-franka eye-in-hand chessboard 9 x 6", root / "visp-franka" / "data-eye-in-hand", Setup::EyeInHand,
       io::parse_target("{type: chessboard, inner_corners: [9, 6], square: 0.0236}", "chessboard.yaml")},
      {"rwhe-kuka kuka_2 chessboard 24 x 17", root / "rwhe-kuka" / "kuka_2", Setup::EyeInHand,
       io::read_target((root / "rwhe-kuka" / "kuka_2" / "target.yaml").string())},
      {"rwhe-kuka kuka_3 ChArUco 12 x 9", root / "rwhe-kuka" / "kuka_3", Setup::EyeInHand,
       io::read_target((root / "rwhe-kuka" / "kuka_3" / "target.yaml").string())},
  };
  Rng rng(2024);
  for (const RealCase& c : cases) {
    ASSERT_TRUE(fs::exists(c.dir)) << c.dir;
    Rig rig{c.setup, {"base", "effector", "camera", "pattern"}};
    rig.T_pattern_face = target_face(c.target);
    rig.face_size = target_face_size(c.target);
    const images::ImageSession found = images::detect_images(images::pair_images_with_poses(c.dir, c.dir),
                                                             images::read_camera((c.dir / "camera_info.yaml").string()),
                                                             c.target, rig);
    const SampleSet& detected = found.samples;
    const int n = static_cast<int>(detected.samples.size());
    EXPECT_EQ(n, static_cast<int>(found.images.size())) << c.name << ": every image is detected";
    const Eigen::Isometry3d F = face_half_turn(c.target);
    std::vector<bool> planted;
    const SampleSet with_turns = planted_turns(detected, F, rng, planted);
    const int planted_count = static_cast<int>(std::count(planted.begin(), planted.end(), true));
    const TurnDecision d = decide_half_turns(with_turns, F);
    EXPECT_TRUE(d.undecided.empty()) << c.name << reasons(d);
    std::vector<bool> decided, planted_kept;
    for (int i : d.kept) {
      decided.push_back(d.turned[i]);
      planted_kept.push_back(planted[i]);
    }
    const int back = agreeing(decided, planted_kept);
    EXPECT_EQ(back, static_cast<int>(d.kept.size())) << c.name;
    // X: the decided samples against the detected ones, as the node calibrates them.
    // When the normalisation kept the planted turns' complement, the decided views
    // are the detected ones all turned (Y turned, X not): compared with the same.
    bool global_turn = back == static_cast<int>(d.kept.size()) && !d.kept.empty();
    for (int i : d.kept) global_turn = global_turn && d.turned[i] != planted[i];
    SampleSet reference = detected;
    if (global_turn) {
      for (PoseSample& s : reference.samples) s = turned(s, F, reference.noise);
    }
    const Calibration original = calibrate_in_a_session(detected), same_reading = calibrate_in_a_session(reference),
                      from_decided = calibrate_in_a_session(d.samples);
    const Vector6d sigma = original.pose_covariance.diagonal().cwiseSqrt();
    const auto in_sigmas = [&](const Calibration& a, const Calibration& b) {
      return (pose_error(a.T_parent_camera, b.T_parent_camera).array().abs() / sigma.array()).maxCoeff();
    };
    const double worst = in_sigmas(from_decided, same_reading), turn_alone = in_sigmas(same_reading, original);
    EXPECT_LT(worst, 1e-6) << c.name;
    // The session's path (handeye solve, images, bag, the node): a samples set of a
    // symmetric target is decided the same, the turned views listed, X the same.
    SampleSet symmetric = with_turns;
    symmetric.rig.symmetric_face = true;
    const Calibration via_session = calibrate_in_a_session(symmetric);
    std::vector<bool> session_turned(static_cast<std::size_t>(n), false);
    for (int i : via_session.turned) session_turned[static_cast<std::size_t>(i)] = true;
    EXPECT_EQ(session_turned, d.turned) << c.name;
    EXPECT_LT(in_sigmas(via_session, same_reading), 1e-6) << c.name;
    ASSERT_EQ(via_session.warnings.back().kind, Warning::Kind::SymmetricTarget);
    EXPECT_EQ(via_session.warnings.back().count, d.turned_count);
    EXPECT_EQ(via_session.warnings.back().views, n);
    // A global turn moves Y, and X only within the estimator's own tolerance (its
    // noise rounds stop once a step would move X by under 0.1 sigma).
    EXPECT_LT(turn_alone, 0.1) << c.name;
    double nearest_wrong = INFINITY;  // the wrong candidate nearest its prediction, in sigmas
    for (int i : d.kept) {
      nearest_wrong = std::min(nearest_wrong, std::max(d.candidates[i].as_given_sigmas, d.candidates[i].turned_sigmas));
    }
    std::printf("[%s] %d views, %d planted turns, %d decided back (%d turned after normalising), %zu undecided, "
                "%d rounds, gate %.2f sigma, nearest wrong candidate %.0f sigma; X from the decided samples - X from "
                "the detected%s: max %.2g sigma (a global turn alone: %.2g sigma)%s\n",
                c.name, n, planted_count, back, d.turned_count, d.undecided.size(), d.rounds, d.gate_sigmas, nearest_wrong,
                global_turn ? " all turned" : "", worst, turn_alone, reasons(d).c_str());
  }
}

// ------------------------------------------------------------- rendered sessions

struct RenderedTally {
  int views = 0, detected = 0, kept = 0, right = 0, left_out = 0, misnamed = 0, detector_turned = 0, sessions = 0;
  double nees = 0.0;
  double near_squared = 0.0, far_squared = 0.0;  // the kept views' nearer candidate, squared sigmas: < 0.8 m, > 1.2 m
  int near = 0, far = 0;
  std::vector<std::string> reasons;
};

/// One rendered session: `views` views of the board from 0.4 to 1.5 m, any
/// in-plane roll, detected with the pooled pixel sigma; the turns decided and
/// judged against the truth, and X's NEES with the decided samples.
void rendered_session(const Target& target, const PatternRenderer& renderer, Setup setup, int views, std::uint64_t seed,
                      RenderedTally& tally) {
  Rng rng(seed);
  ViewpointOptions geometry;
  geometry.min_distance = 0.4;
  geometry.max_distance = 1.5;
  geometry.max_roll = M_PI;  // the whole circle: which end OpenCV starts at is arbitrary
  const SimulatedSession truth = simulate_session(rng, setup, typical_X(setup), views, MeasurementNoise{}, geometry);
  const Eigen::Isometry3d T_face_pattern = target_face(target).inverse(), F = half_turn(target);
  images::PooledDetector detector(target);
  for (const PoseSample& s : truth.samples.samples) {
    detector.add(renderer.render(s.T_camera_pattern * T_face_pattern, rng), renderer.camera());
  }
  SampleSet set;
  set.rig = truth.samples.rig;
  set.rig.T_pattern_face = target_face(target);
  set.rig.face_size = target_face_size(target);
  std::vector<Eigen::Isometry3d> true_pose;
  for (std::size_t i = 0; i < truth.samples.samples.size(); ++i) {
    ++tally.views;
    const std::optional<PatternPose> pose = detector.pooled(i);
    if (!pose) continue;
    ++tally.detected;
    PoseSample sample;
    sample.T_base_effector = truth.samples.samples[i].T_base_effector;
    sample.T_camera_pattern = pose->T_camera_pattern;
    sample.noise = MeasurementNoise{PoseNoise{}, PoseNoise::from_pose_covariance(pose->covariance)};
    set.samples.push_back(sample);
    true_pose.push_back(truth.samples.samples[i].T_camera_pattern * T_face_pattern);
    const Eigen::Isometry3d& P = pose->T_camera_pattern;
    tally.detector_turned += test::pose_perturbation(P, true_pose.back() * F).norm() <
                                     test::pose_perturbation(P, true_pose.back()).norm()
                                 ? 1
                                 : 0;
  }
  const TurnDecision d = decide_half_turns(set, F);
  // Each kept view as decided: the truth, or the truth turned; the session's global
  // turn is the majority reading (it moves Y only).
  int as_truth = 0;
  std::vector<bool> is_truth;
  for (std::size_t k = 0; k < d.kept.size(); ++k) {
    const Eigen::Isometry3d& P = d.samples.samples[k].T_camera_pattern;
    const Eigen::Isometry3d& T = true_pose[d.kept[k]];
    is_truth.push_back(test::pose_perturbation(P, T).norm() < test::pose_perturbation(P, T * F).norm());
    as_truth += is_truth.back() ? 1 : 0;
  }
  for (int i : d.kept) {
    const double squared = std::pow(std::min(d.candidates[i].as_given_sigmas, d.candidates[i].turned_sigmas), 2);
    const double distance = true_pose[i].translation().norm();
    if (distance < 0.8) tally.near_squared += squared, ++tally.near;
    if (distance > 1.2) tally.far_squared += squared, ++tally.far;
  }
  tally.kept += static_cast<int>(d.kept.size());
  tally.right += std::max(as_truth, static_cast<int>(d.kept.size()) - as_truth);
  tally.left_out += static_cast<int>(d.undecided.size());
  for (const TurnDecision::Undecided& u : d.undecided) {
    // Named for what its two distances say: both within the gate, or neither.
    const TurnDecision::Candidates& c = d.candidates.at(static_cast<std::size_t>(u.index));
    const bool both = c.as_given_sigmas <= d.gate_sigmas && c.turned_sigmas <= d.gate_sigmas;
    const bool neither = c.as_given_sigmas > d.gate_sigmas && c.turned_sigmas > d.gate_sigmas;
    if (!(u.both_fit ? both : neither)) ++tally.misnamed;
    tally.reasons.push_back("seed " + std::to_string(seed) + " view " + std::to_string(u.index) + ": " + reason(d, u));
  }
  const Calibration c = calibrate_in_a_session(d.samples);
  const Vector6d e = test::pose_perturbation(c.T_parent_camera, truth.X);
  tally.nees += e.dot(c.pose_covariance.ldlt().solve(e));
  ++tally.sessions;
}

// 26 sessions of 20 rendered views of a 9 x 7 board (520 views; 50 sessions until
// the suite had to fit 20 minutes), half eye-in-hand and half eye-to-hand, on two
// threads: of the views kept, at least 99.5% decided right (against the truth, up
// to each session's global turn); every view left out named for what its two distances say; the NEES of X over the
// sessions in its band for that many sessions. A view costs about 90 ms of CPU
// (rendering ~50 ms; OpenCV's sector-based detector, for the 5-8% of far or steep
// views the classic one misses, ~1 s). Rendered at 2x supersampling instead of 3x
// the views cost half, but the far views' corners then alias (NEES of X 8.5 with 96
// texels a square).
TEST(HalfTurn, RenderedSymmetricBoardSessionsAreDecidedRightAndXIsHonest) {
  const Target target = make_target(ChessboardTarget{9, 7, 0.025});
  const CameraModel camera = simulated_camera();
  const PatternRenderer renderer(target, camera);
  constexpr int kSessions = 26, kViews = 20, kThreads = 2;  // 13 eye-in-hand, 13 eye-to-hand
  std::vector<RenderedTally> tallies(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int k = t; k < kSessions; k += kThreads) {
        rendered_session(target, renderer, k % 2 ? Setup::EyeToHand : Setup::EyeInHand, kViews, 9100 + k, tallies[t]);
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  RenderedTally all;
  for (const RenderedTally& t : tallies) {
    all.views += t.views, all.detected += t.detected, all.kept += t.kept, all.right += t.right;
    all.left_out += t.left_out, all.misnamed += t.misnamed, all.detector_turned += t.detector_turned;
    all.sessions += t.sessions, all.nees += t.nees;
    all.near_squared += t.near_squared, all.far_squared += t.far_squared, all.near += t.near, all.far += t.far;
    all.reasons.insert(all.reasons.end(), t.reasons.begin(), t.reasons.end());
  }
  const double nees = all.nees / all.sessions;
  std::printf("rendered 9 x 7 board: %d sessions, %d views, %d detected (%d of them the turned candidate), %d kept, "
              "%d decided right (%.2f%%), %d left out; NEES of X %.2f; the right candidate's mean squared sigmas "
              "%.2f below 0.8 m, %.2f beyond 1.2 m\n",
              all.sessions, all.views, all.detected, all.detector_turned, all.kept, all.right,
              100.0 * all.right / std::max(all.kept, 1), all.left_out, nees, all.near_squared / std::max(all.near, 1),
              all.far_squared / std::max(all.far, 1));
  for (const std::string& r : all.reasons) std::printf("  left out: %s\n", r.c_str());
  EXPECT_EQ(all.sessions, kSessions);
  EXPECT_GE(all.detected, all.views * 95 / 100);
  EXPECT_GE(all.right, all.kept * 995 / 1000.0);
  EXPECT_EQ(all.misnamed, 0);
  // Left out as "neither fits" are far views (1-1.5 m) whose right candidate lies a
  // little beyond the 99.9% gate, the other thousands of sigmas off: there the
  // detector's covariance is too small (the mean squared distance of a right
  // candidate, printed, grows with the distance). At most 3%.
  EXPECT_LE(all.left_out, all.detected * 3 / 100);
  // The candidate OpenCV gives is arbitrary: both occur often.
  EXPECT_GT(all.detector_turned, all.detected / 5);
  EXPECT_LT(all.detector_turned, all.detected * 4 / 5);
  // An honest X: the mean 6-dof NEES within its 99.9% band over this many sessions
  // (4.52-7.74 at 50 sessions, where the bar was first set at 4.5-7.5; 4.01-8.49 at 26).
  const auto [low, high] = test::chi2_mean_band(all.sessions, 6, 0.999);
  std::printf("  honest 6-dof NEES over %d sessions: %.2f-%.2f (99.9%%)\n", all.sessions, low, high);
  EXPECT_GE(nees, low);
  EXPECT_LE(nees, high);
}

}  // namespace
}  // namespace handeye
