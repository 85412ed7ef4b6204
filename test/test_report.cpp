// The calibration report (session/report.h, `handeye report`, scripts/report.py):
// its checks on simulated sessions with known properties, and the page of the
// demo session with a planted wrong detection, rendered by headless Chromium.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cli_helpers.h"
#include "handeye_covariance/io/honesty_text.h"
#include "handeye_covariance/io/result_file.h"
#include "handeye_covariance/io/summary.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/session/report.h"
#include "test_helpers.h"

namespace handeye {
namespace {

SampleSet simulated(int n, unsigned seed, const ViewpointOptions& views = {}) {
  Rng rng(seed);
  SampleSet samples =
      simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), n, test::sim_noise(), views).samples;
  samples.noise = test::sim_noise();  // given: the covariance is honest by construction
  return samples;
}

/// The report's options with a lighter split-half check (40 splits against 30
/// simulated sessions): the tests that are not about the check itself.
ReportOptions quick() {
  ReportOptions options;
  options.splits = 40;
  options.reference_sessions = 30;
  return options;
}

CalibrationReport report_of(const SampleSet& samples, const ReportOptions& options = quick()) {
  CalibrationSession session(session_settings(samples));
  session.replace(samples.samples, "test");
  return make_report(session, session.snapshot(), options);
}

bool mentions(const std::vector<std::string>& advice, const std::string& text) {
  for (const std::string& a : advice) {
    if (a.find(text) != std::string::npos) return true;
  }
  return false;
}

// Honest sessions (noise given and true): leave-one-out and split-half agree
// with the predicted sigma per axis (RMS ratio about 1 over sessions and axes),
// and the advice finds nothing to mend. Measured over 60 such sessions of 30
// samples: per-axis ratio RMS 1.06 (leave-one-out) and 1.01 (split-half), the
// worst axis of a session at most 1.65 and 1.71, split-half NEES 4.4-9.1
// (mean 6.2); of 15 samples, worst 1.98 and 1.74: hence the advice's threshold, 2.
// The split-half NEES is judged against its reference at the session's poses,
// whose 5-95% band an honest session leaves one time in twenty on either side:
// on each look (random halves; runs of 3) at most two of ten are called
// overconfident, or cautious (the binomial tail beyond is 1.2% each).
TEST(Report, OnHonestSessionsTheChecksAgreeWithThePredictedSigma) {
  double loo_square = 0.0, split_square = 0.0, nees = 0.0, worst = 1.0;
  const int sessions = 10;
  int flagged = 0, overconfident = 0, random_overconfident = 0, runs_overconfident = 0;
  for (unsigned seed = 1; seed <= sessions; ++seed) {
    const CalibrationReport r = report_of(simulated(30, seed));
    ASSERT_EQ(r.fits.size(), 30u);
    EXPECT_EQ(r.leave_one_out_solved, 30);
    EXPECT_EQ(r.honesty.observed.splits, 40);
    EXPECT_EQ(r.honesty.reference.replicates, 30);
    EXPECT_EQ(r.rotation_axes.size(), 30u * 29u / 2u);
    for (int k = 0; k < 6; ++k) {
      const double loo = r.leave_one_out_sigma(k) / r.predicted_sigma(k);
      const double split = r.split_half_sigma(k) / r.predicted_sigma(k);
      EXPECT_GT(loo, 0.45) << "seed " << seed << " axis " << k;
      EXPECT_LT(loo, 2.0) << "seed " << seed << " axis " << k;
      EXPECT_GT(split, 0.45) << "seed " << seed << " axis " << k;
      EXPECT_LT(split, 2.0) << "seed " << seed << " axis " << k;
      loo_square += loo * loo / (6.0 * sessions);
      split_square += split * split / (6.0 * sessions);
      worst = std::max({worst, loo, split});
    }
    nees += r.honesty.observed.mean_nees / sessions;
    EXPECT_EQ(r.honesty.runs_length, 3);  // the second look of the default: 30 / 8
    random_overconfident += r.honesty.random_verdict == Honesty::Overconfident;
    runs_overconfident += r.honesty.runs_verdict == Honesty::Overconfident;
    if (r.honesty.verdict != Honesty::Honest) {
      ++flagged;
      overconfident += r.honesty.verdict == Honesty::Overconfident ? 1 : 0;
      EXPECT_TRUE(mentions(r.advice, "for an honest covariance on these poses")) << r.advice.front();
      continue;
    }
    EXPECT_EQ(r.advice.size(), 1u) << r.advice.front();
    EXPECT_TRUE(mentions(r.advice, "nothing to mend")) << r.advice.front();
  }
  std::printf("[ figures  ] 10 honest sessions of 30: overconfident by random halves %d, by runs of 3 %d, by the verdict %d\n",
              random_overconfident, runs_overconfident, overconfident);
  EXPECT_LE(random_overconfident, 2);
  EXPECT_LE(runs_overconfident, 2);
  EXPECT_LE(flagged - overconfident, 2);
  EXPECT_GT(std::sqrt(loo_square), 0.85);
  EXPECT_LT(std::sqrt(loo_square), 1.25);
  EXPECT_GT(std::sqrt(split_square), 0.85);
  EXPECT_LT(std::sqrt(split_square), 1.25);
  EXPECT_GT(nees, 5.0);
  EXPECT_LT(nees, 7.5);
  std::cout << "[ figures  ] 10 honest sessions of 30: ratio to the predicted sigma, RMS over axes: leave-one-out "
            << std::sqrt(loo_square) << ", split-half " << std::sqrt(split_square) << "; worst " << worst
            << "; mean split-half NEES " << nees << "; called overconfident or cautious by the check: " << flagged << "\n";
}

// An overconfident session. The joint estimator corrects a stated noise that is
// too small (it estimates the missing part: DH errors of 1 mm / 0.1 deg gave a
// worst-axis ratio of 1.16 and NEES 6.2 here, robust mode off), so this takes the
// paper's pairs estimator, which trusts the stated noise, stated 3x too small.
// The calibrated check calls it overconfident by about 9 in variance and the
// calibration's covariance is inflated by what it measured; against the model's
// own sigma the leave-one-out and split-half spreads are 2-4.5 times larger.
TEST(Report, OnAnOverconfidentSessionTheChecksSeeIt) {
  SampleSet samples = simulated(30, 11);
  samples.noise->camera.rotation /= 9.0;
  samples.noise->camera.translation /= 9.0;
  samples.noise->robot.rotation /= 9.0;
  samples.noise->robot.translation /= 9.0;
  CalibrationSession session([&] {
    SessionSettings s = session_settings(samples);
    s.method = Method::Pairs;
    return s;
  }());
  session.replace(samples.samples, "test");
  ReportOptions options;
  options.reference_sessions = 30;
  const CalibrationReport r = make_report(session, session.snapshot(), options);
  ASSERT_TRUE(r.calibration.honesty);
  const Vector6d model_sigma = r.calibration.honesty->model_pose_covariance.diagonal().cwiseSqrt();
  double loo = 0.0, split = 0.0;
  for (int k = 0; k < 6; ++k) {
    loo += r.leave_one_out_sigma(k) / model_sigma(k) / 6.0;
    split += r.split_half_sigma(k) / model_sigma(k) / 6.0;
  }
  std::cout << "[ figures  ] pairs, noise stated 3x too small: mean ratio to the model's sigma leave-one-out " << loo
            << ", split-half " << split << ", NEES " << r.honesty.observed.mean_nees << " (middle 90% "
            << r.honesty.observed.trimmed_mean_nees << ") against " << r.honesty.reference.mean << ": " << io::honesty_text(r.honesty)
            << "\n";
  EXPECT_GT(loo, 2.0);
  EXPECT_LT(loo, 4.5);
  EXPECT_GT(split, 2.0);
  EXPECT_LT(split, 4.5);
  EXPECT_GT(r.honesty.observed.mean_nees, 20.0);
  EXPECT_EQ(r.honesty.verdict, Honesty::Overconfident);
  EXPECT_GT(r.honesty.ratio, 4.0);
  EXPECT_NEAR(r.calibration.honesty->inflation, r.honesty.ratio, 1e-12);
  EXPECT_NEAR(r.calibration.pose_covariance(0, 0), r.honesty.ratio * r.calibration.honesty->model_pose_covariance(0, 0),
              1e-9 * r.calibration.pose_covariance(0, 0));
  EXPECT_TRUE(mentions(r.advice, "the covariance is overconfident x")) << r.advice.front();
  EXPECT_TRUE(mentions(r.advice, "split-half NEES")) << r.advice.front();
  // The report's file and its summary give the verdict in the same words as the calibration's record.
  const std::string words = r.calibration.honesty->text;
  EXPECT_EQ(words.rfind("overconfident x", 0), 0u) << words;
  EXPECT_EQ(YAML::Load(io::format_report(r, {}, "test"))["checks"]["honesty_text"].as<std::string>(), words);
  EXPECT_NE(io::report_summary(r).find(": " + words + ")"), std::string::npos) << io::report_summary(r);
}

// Every detection's stated noise 3x too small: the joint estimator estimates the
// missing part, and the residuals are judged under it, so the samples' sigmas stay
// chi(6)-like, no good sample is called out and the threshold keeps its value; a
// planted outlier still is called out.
TEST(Report, UnderstatedDetectionNoiseDoesNotCallEverySampleOut) {
  SampleSet samples = simulated(30, 12);
  samples.noise->camera.rotation /= 9.0;
  samples.noise->camera.translation /= 9.0;
  const CalibrationReport r = report_of(samples);
  EXPECT_LT(r.advice_sigma, 1.5 * ReportOptions().advice_sigma);
  EXPECT_FALSE(mentions(r.advice, "sigma off")) << r.advice.front();
  samples.samples[9].T_camera_pattern.translation() += Eigen::Vector3d(0.0, 25e-3, 0.0);
  const CalibrationReport planted = report_of(samples);
  EXPECT_EQ(planted.advice.front().rfind("sample 9 is ", 0), 0u) << planted.advice.front();
  std::cout << "[ figures  ] noise stated 3x too small: advice threshold " << r.advice_sigma << " sigma\n";
}

// A wrong detection (sample 7's pattern pose 6 mm off): the report
// names it first, with its sigmas, whether or not X already leaves it out.
TEST(Report, AdviceNamesAPlantedOutlierFirst) {
  SampleSet samples = simulated(25, 5);
  // 6 mm off along the camera's x: kept by the estimator when rejection is off (a
  // swapped pose would be refused outright, AngleMismatch), about 12 camera sigmas.
  samples.samples[7].T_camera_pattern.translation() += Eigen::Vector3d(6e-3, 0.0, 0.0);
  const CalibrationReport rejected = report_of(samples);
  ASSERT_EQ(rejected.calibration.rejected.size(), 1u);
  EXPECT_EQ(rejected.calibration.rejected[0].index, 7);
  EXPECT_GT(rejected.fits[7].sigmas, 8.0);
  EXPECT_EQ(rejected.advice.front().rfind("sample 7 is ", 0), 0u) << rejected.advice.front();
  EXPECT_NE(rejected.advice.front().find("remove it (X already leaves it out"), std::string::npos);

  CalibrationSession keeping([&] {
    SessionSettings s = session_settings(samples);
    s.reject_outliers = false;
    return s;
  }());
  keeping.replace(samples.samples, "test");
  const CalibrationReport kept = make_report(keeping, keeping.snapshot(), quick());
  EXPECT_TRUE(kept.calibration.rejected.empty());
  EXPECT_EQ(kept.advice.front().rfind("sample 7 is ", 0), 0u) << kept.advice.front();
  EXPECT_NE(kept.advice.front().find("/remove_sample 7"), std::string::npos) << kept.advice.front();
  std::cout << "[ figures  ] planted outlier: " << rejected.fits[7].sigmas << " sigma (rejected), "
            << kept.fits[7].sigmas << " sigma (kept)\n";
}

// Views without roll about the optical axis and small tilts: the motions hardly
// turn about the camera's z, and the advice says so.
TEST(Report, AdviceNamesTheAxisTheMotionsDoNotTurnAbout) {
  ViewpointOptions views;
  views.max_roll = 0.5 * M_PI / 180.0;
  const CalibrationReport r = report_of(simulated(20, 3, views));
  const Eigen::Vector3d weakest = r.turning_axes.col(0);
  EXPECT_GT(std::abs(weakest.z()), 0.9) << weakest.transpose();
  EXPECT_LT(r.turning(0), 0.1 * r.turning(2));
  EXPECT_TRUE(mentions(r.advice, "little rotation about the camera's z (optical axis)")) << r.advice.front();
  // The honest session above has no such advice: the default views roll up to 60 degrees.
  const CalibrationReport rolled = report_of(simulated(20, 3));
  EXPECT_FALSE(mentions(rolled.advice, "little rotation")) << rolled.advice.front();
  std::cout << "[ figures  ] turning about the weakest direction / the strongest: no roll "
            << r.turning(0) / r.turning(2) << ", rolled " << rolled.turning(0) / rolled.turning(2) << "\n";
}

// 100 samples: 4950 motions. The turning uses every one; the figure gets at most
// 2000, evenly spread; the split-half check can be left out.
TEST(Report, ALargeSessionKeepsTheFigureSmall) {
  ReportOptions options = quick();
  options.splits = 0;
  const CalibrationReport r = report_of(simulated(100, 8), options);
  EXPECT_EQ(r.leave_one_out_solved, 100);
  EXPECT_GT(r.rotation_axes.size(), 1000u);
  EXPECT_LE(r.rotation_axes.size(), 2000u);
  EXPECT_EQ(r.honesty.observed.splits, 0);
  EXPECT_EQ(r.split_problem, "left out (splits: 0)");
  EXPECT_FALSE(mentions(r.advice, "no split-half check")) << r.advice.front();
  EXPECT_GT(r.turning(0), 0.1 * r.turning(2));
}

// A target met on a noise estimated from too few samples is not reached (target_progress):
// the report says why, and its file carries the decision that report.py shows.
TEST(Report, AnEstimatedNoiseSaysWhyTheTargetIsNotReachedYet) {
  ReportOptions options = quick();
  options.splits = 0;
  const auto report_at = [&](int n) {
    SampleSet samples = simulated(n, 12);
    samples.noise.reset();  // estimated from the residuals
    SessionSettings settings = session_settings(samples);
    settings.target_object_sigma = 1.0;  // m: met by any sigma, so only the sample count decides
    CalibrationSession session(settings);
    session.replace(samples.samples, "test");
    return make_report(session, session.snapshot(), options);
  };
  const CalibrationReport few = report_at(kTargetMinimumSamplesEstimatedNoise - 2);
  EXPECT_EQ(few.calibration.noise_origin, NoiseOrigin::EstimatedFromResiduals);
  EXPECT_LE(few.object_sigma, few.target_object_sigma);
  EXPECT_FALSE(few.target_reached);
  EXPECT_TRUE(mentions(few.advice, "a target is reached from " + std::to_string(kTargetMinimumSamplesEstimatedNoise)))
      << few.advice.front();
  const YAML::Node file = YAML::Load(io::format_report(few, {}, "test"));
  EXPECT_FALSE(file["object"]["reached"].as<bool>());
  const CalibrationReport enough = report_at(kTargetMinimumSamplesEstimatedNoise);
  EXPECT_TRUE(enough.target_reached);
  EXPECT_TRUE(enough.target_not_reached.empty()) << enough.target_not_reached;
  EXPECT_FALSE(mentions(enough.advice, "a target is reached from"));
  EXPECT_TRUE(YAML::Load(io::format_report(enough, {}, "test"))["object"]["reached"].as<bool>());
}

TEST(Report, CameraAxisNames) {
  EXPECT_EQ(camera_axis_name({0, 0, -1}), "the camera's z (optical axis)");
  EXPECT_EQ(camera_axis_name({0.99, 0.1, 0}), "the camera's x (image right)");
  EXPECT_EQ(camera_axis_name({-1, -1, -1}), "the camera-frame direction (0.58, 0.58, 0.58)");
}

// ---------------------------------------------------------------- the page

/// Pixels of `image` within `tolerance` of the BGR colour.
int pixels_of(const cv::Mat& image, cv::Vec3b bgr, int tolerance = 12) {
  int count = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const cv::Vec3b p = image.at<cv::Vec3b>(y, x);
      if (std::abs(p[0] - bgr[0]) <= tolerance && std::abs(p[1] - bgr[1]) <= tolerance &&
          std::abs(p[2] - bgr[2]) <= tolerance) {
        ++count;
      }
    }
  }
  return count;
}

/// Share of pixels that are not (near) white.
double inked_share(const cv::Mat& image) {
  cv::Mat gray;
  cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  return static_cast<double>(cv::countNonZero(gray < 235)) / static_cast<double>(gray.total());
}

// `handeye report` on the demo session (handeye sim --seed 7, 15 poses, as the
// demo bag) with a wrong detection planted at sample 3, as a user runs it; the
// page rendered by headless Chromium.
TEST(ReportPage, DemoSessionWithAPlantedOutlierRendersInChromium) {
  const std::string session = test::temp("demo_samples.yaml");
  const test::CliRun sim = test::run("sim --samples 15 --seed 7 --output " + session);
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  SampleSet samples = io::read_samples(session);
  samples.samples[3].T_camera_pattern = samples.samples[0].T_camera_pattern;
  io::write_file_atomically(session, io::format_samples(samples));

  const std::string dir = test::temp("report");
  const test::CliRun run = test::run("report --input " + session + " --output " + dir);
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("sample 3 is "), std::string::npos) << run.out;

  const YAML::Node report = YAML::LoadFile(dir + "/report.yaml");
  ASSERT_TRUE(report["advice"].IsSequence());
  const std::string first = report["advice"][0].as<std::string>();
  EXPECT_EQ(first.rfind("sample 3 is ", 0), 0u) << first;
  EXPECT_NE(first.find("remove it"), std::string::npos) << first;
  EXPECT_TRUE(report["samples"][3]["rejected"].as<bool>());
  EXPECT_EQ(report["samples"].size(), 15u);
  const std::string html = io::read_file(dir + "/report.html");
  EXPECT_NE(html.find(first.substr(0, 20)), std::string::npos);

  // Each figure: a real image with ink and the report's colours, not a blank canvas.
  for (const char* name : {"residuals", "ellipsoids", "checks", "noise", "rotation_axes"}) {
    const std::string path = dir + "/" + name + ".png";
    const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
    ASSERT_FALSE(image.empty()) << path;
    EXPECT_GT(image.cols, 600) << path;
    EXPECT_GT(image.rows, 300) << path;
    EXPECT_GT(std::filesystem::file_size(path), 20000u) << path;
    EXPECT_GT(inked_share(image), 0.03) << path;
    EXPECT_NE(html.find(std::string("src=\"") + name + ".png\""), std::string::npos) << name;
  }
  // The residual bars: the rejected sample in red (#c0392b), the kept ones in blue (#2e86c1).
  const cv::Mat residuals = cv::imread(dir + "/residuals.png", cv::IMREAD_COLOR);
  EXPECT_GT(pixels_of(residuals, {0x39, 0x39, 0xc0}), 200);
  EXPECT_GT(pixels_of(residuals, {0xc1, 0x86, 0x2e}), 2000);

  // Headless Chromium (Debian's chromium) renders the page as a user's browser would.
  const std::string screenshot = dir + "/page.png";
  const std::string chromium = "chromium --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=1280,6000"
                               " --screenshot=" + screenshot + " file://" + dir + "/report.html >" + dir +
                               "/chromium.log 2>&1";
  ASSERT_EQ(std::system(chromium.c_str()), 0) << io::read_file(dir + "/chromium.log");
  const cv::Mat page = cv::imread(screenshot, cv::IMREAD_COLOR);
  ASSERT_FALSE(page.empty()) << screenshot << ": " << io::read_file(dir + "/chromium.log");
  EXPECT_EQ(page.cols, 1280);
  EXPECT_EQ(page.rows, 6000);
  // The figures are in the page (their blue is no colour of the page's own style),
  // and so is the rejected row of the samples table (#fadbd8).
  EXPECT_GT(pixels_of(page, {0xc1, 0x86, 0x2e}), 2000);
  EXPECT_GT(pixels_of(page, {0xd8, 0xdb, 0xfa}, 3), 1000);
  EXPECT_GT(inked_share(page), 0.05);
  // The report in docs/ is this one: HANDEYE_REPORT_DOCS=docs/report test_report --gtest_filter=ReportPage.*
  if (const char* keep = std::getenv("HANDEYE_REPORT_DOCS")) {
    std::filesystem::create_directories(keep);
    for (const auto& file : std::filesystem::directory_iterator(dir)) {
      if (file.path().filename() == "chromium.log") continue;
      std::filesystem::copy_file(file.path(), std::filesystem::path(keep) / file.path().filename(),
                                 std::filesystem::copy_options::overwrite_existing);
    }
  }
}

}  // namespace
}  // namespace handeye
