// The check of a saved calibration (estimation/calibration_check.h)
// on simulated sessions: how often it says "changed" as X's or Y's translation is moved
// by 0 to 8 times its own 1 sigma of the change along the move, beside the bound for a
// 6-dof test that knows which one moved (noncentral chi2) and the bound for any test
// that must catch either (the Neyman-Pearson test against their mixture, at each check's
// views); which one it names, and how often it detects and names right beside the most
// any test can (two_hypothesis_frontier); at a session's usual views and at views turned
// about different axes. simulation/check_study.h. Seeded; no ROS. Prints Markdown tables
// (scripts/bench puts them in BENCHMARKS.md). One of:
//
//   handeye_check_study [--checks 300] [--seed 1]
//   handeye_check_study --rendered config/tag_board_2x2.yaml [--calibration-views 20] [--checks 300] [--seed 1]
// The same through the images (simulation/rendered_views.h): each calibration's views
// and each check's 5 rendered, detected with the pixel sigma pooled over the set, the
// noise estimated beside the detections' covariance, at the session's usual views.
//   handeye_check_study --views-between [--checks 300] [--seed 1]
// The same at views between the usual and the turned ones (tilt to 45 deg, roll to 90).
//   handeye_check_study --any-direction [--checks 300] [--seed 1]
// At the usual views, X or Y moved along a direction uniform in its 6 dof, beside its translation.
//   handeye_check_study --frontier [--seed 1]
// Where detecting a change and naming it meet, at views of equal principal cosines
// between X's and Y's subspaces, and where views of several spreads sit.
//   handeye_check_study --estimated-scale [--seed 1]
// What a noise scale estimated from 360, 120 or 60 dof costs any test that must catch X
// or Y (and one that knows which), at views of equal principal cosines.
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/io/target_file.h"
#include "handeye_covariance/simulation/check_study.h"
#include "handeye_covariance/simulation/rendered_views.h"

namespace {

using namespace handeye;

/// One table row; `rendered` adds the counts and the new views' chi2 / dof, `moved` the
/// moved one's mean chi2 drop and the checks that left a view out as a wrong detection.
void row(const char* what, const CheckStudyResult& r, double multiple, bool rendered = false, bool moved = false) {
  char six[16] = "-", two[16] = "-", named[16] = "-", both[32] = "-", counts[32] = "", chi2[24] = "";
  if (r.bound > 0.0) std::snprintf(six, sizeof six, "%.1f%%", 100.0 * r.bound);
  if (multiple > 0.0 && r.two_hypothesis_bound > 0.0) {  // 0: not computed, or not a bound for these moves
    std::snprintf(two, sizeof two, "%.1f%%", 100.0 * r.two_hypothesis_bound);
    std::snprintf(both, sizeof both, "%.1f%% / %.1f%%", 100.0 * r.rate() * r.named_right(), 100.0 * r.best_detected_and_named);
  } else if (multiple > 0.0) {
    std::snprintf(both, sizeof both, "%.1f%% / -", 100.0 * r.rate() * r.named_right());
  }
  if (multiple > 0.0 && r.changed > 0) std::snprintf(named, sizeof named, "%.1f%%", 100.0 * r.named_right());
  if (rendered) {
    std::snprintf(counts, sizeof counts, " (%d of %d)", r.changed, r.checks);
    std::snprintf(chi2, sizeof chi2, " %.1f%% | %.3f |", 100.0 * r.noise_dof_bound, r.mean_chi2_over_dof);
  }
  if (moved) std::snprintf(chi2, sizeof chi2, " %.2f | %d |", r.mean_planted_drop, r.left_out);
  std::printf("| %s | %.0f | %.1f%%%s | %s | %s | %s | %s |%s\n", what, multiple, 100.0 * r.rate(), counts, six, two,
              named, both, chi2);
  std::fflush(stdout);
}

/// The tables' header; `extra` adds columns (" chi2 / dof |"), one per '|'.
void header(const std::string& extra = "") {
  std::string rule;
  for (char c : extra) rule += c == '|' ? "---:|" : "";
  std::printf("| moved | sigma | says changed | 6-dof bound (knows which) | bound for X or Y | names it right | detected and "
              "named right: the check / at best |%s\n|---|---:|---:|---:|---:|---:|---:|%s\n",
              extra.c_str(), rule.c_str());
}

/// A positive whole number from `text`, or nothing (then the usage).
std::optional<int> positive(const char* text) {
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || value <= 0 || value > 100000000) return std::nullopt;
  return static_cast<int>(value);
}

}  // namespace

/// The study through rendered images of `target_file`'s target: no change, and X's
/// and Y's translation moved by 5 sigma, at the session's usual views.
int rendered_study(const std::string& target_file, int checks, unsigned seed, int calibration_views) {
  const Target target = io::read_target(target_file);
  const PatternRenderer renderer(target, simulated_camera());
  const PoseNoise robot = check_study_noise().robot;
  CheckStudyOptions o;
  o.checks = checks;
  o.seed = seed;
  o.calibration_samples = calibration_views;
  o.observe = [&](Rng& rng, const Rig& rig, const std::vector<Eigen::Isometry3d>& effectors, const Eigen::Isometry3d& X,
                  const Eigen::Isometry3d& Y) { return rendered_views(rng, rig, effectors, X, Y, renderer, target, robot); };
  std::printf("Rendered views of %s (each calibration's %d and each check's 5 detected, the pixel sigma pooled over "
              "them), the session's usual views:\n\n",
              target_file.c_str(), calibration_views);
  header(" 6-dof bound, the noise known to its views' dof | chi2 / dof |");
  row("nothing", run_check_study(o), 0.0, true);
  for (PlantedChange change : {PlantedChange::XTranslation, PlantedChange::YTranslation}) {
    o.change = change;
    o.multiple = 5.0;
    o.seed = seed + 50;
    row(change == PlantedChange::XTranslation ? "X (camera on its mount)" : "Y (the target)", run_check_study(o), 5.0, true);
  }
  return 0;
}

/// Where detecting a change and naming it meet: at views whose X and Y subspaces have
/// equal principal cosines c, the most any test that must catch X or Y detects, the
/// check's statistic's power and naming, and the most any test detects and names right
/// (two_hypothesis_frontier); then where views of several spreads sit (their mean cosine).
int frontier(unsigned seed) {
  std::printf("At views whose X and Y subspaces have six equal principal cosines c (two_hypothesis_frontier, 200 000 "
              "draws a cell, alpha 1%%; a direction uniform in 6 dof):\n\n");
  std::printf("| c | bound for X or Y, 5 sigma | the check detects | and names right | detected and named right at best | "
              "bound, 6 sigma | the check names right, 6 sigma | detected and named right at best, 6 sigma |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (double c : {0.0, 0.3, 0.5, 0.6, 0.65, 0.7, 0.75, 0.8, 0.9}) {
    const TwoHypothesisFrontier five = two_hypothesis_frontier(Vector6d::Constant(c), 25.0, 0.01, seed, 200000);
    const TwoHypothesisFrontier six = two_hypothesis_frontier(Vector6d::Constant(c), 36.0, 0.01, seed, 200000);
    std::printf("| %.2f | %.1f%% | %.1f%% | %.1f%% | %.1f%% | %.1f%% | %.1f%% | %.1f%% |\n", c, 100.0 * five.bound,
                100.0 * five.larger_power, 100.0 * five.larger_named_right, 100.0 * five.detected_and_named,
                100.0 * six.bound, 100.0 * six.larger_named_right, 100.0 * six.detected_and_named);
    std::fflush(stdout);
  }
  std::printf("\nWhere views sit (their mean cosine over 200 checks, noise stated):\n\n| tilt to | roll to | mean cosine |\n"
              "|---:|---:|---:|\n");
  for (const auto& [tilt, roll] : std::vector<std::pair<double, double>>{{35, 60}, {40, 90}, {45, 90}, {45, 120}, {50, 150},
                                                                          {60, 180}}) {
    CheckStudyOptions o;
    o.noise_given = true;
    o.checks = 200;
    o.seed = seed;
    o.bound_draws = 0;
    o.viewpoints.max_tilt = radians(tilt), o.viewpoints.max_roll = radians(roll);
    std::printf("| %.0f deg | %.0f deg | %.2f |\n", tilt, roll, run_check_study(o).mean_x_y_cosine);
    std::fflush(stdout);
  }
  return 0;
}

/// What an estimated noise scale costs a test that must catch X or Y: the bound at views of
/// equal principal cosines c with the scale known, and estimated from 360, 120 and 60 dof
/// (60, 20 and 10 views' leave-one-out prediction), beside the F test's bound for a test
/// that knows which (two_hypothesis_power_bound_estimated_scale, f_test_power).
int estimated_scale(unsigned seed) {
  constexpr int kDraws = 40000;
  std::printf("At views whose X and Y subspaces have six equal principal cosines c, 5 sigma, alpha 1%% "
              "(two_hypothesis_power_bound_estimated_scale, %d draws a cell; the known-noise column 200 000):\n\n"
              "| c | bound for X or Y, noise known | its scale from 360 dof | from 120 dof | from 60 dof |\n"
              "|---:|---:|---:|---:|---:|\n", kDraws);
  for (double c : {0.5, 0.7, 0.82, 0.9}) {
    const Vector6d cosines = Vector6d::Constant(c);
    std::printf("| %.2f | %.1f%% |", c, 100.0 * two_hypothesis_power_bound(cosines, 25.0, 0.01, seed, 200000));
    for (double dof : {360.0, 120.0, 60.0}) {
      std::printf(" %.1f%% |", 100.0 * two_hypothesis_power_bound_estimated_scale(cosines, 25.0, dof, 0.01, seed, kDraws));
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  std::printf("| knows which (f_test_power) | %.1f%% | %.1f%% | %.1f%% | %.1f%% |\n", 100.0 * chi2_test_power(6, 25.0, 0.01),
              100.0 * f_test_power(6, 360.0, 25.0, 0.01), 100.0 * f_test_power(6, 120.0, 25.0, 0.01),
              100.0 * f_test_power(6, 60.0, 25.0, 0.01));
  return 0;
}

/// The study at the session's usual views with the move's direction uniform in X's or Y's 6
/// dof as the check weighs them (the family the "bound for X or Y" is for), beside the
/// translations the first study moves, at 5 and 6 sigma.
int any_direction_study(int checks, unsigned seed) {
  std::printf("The session's usual views, %d checks a row: the move along a direction uniform in 6 dof as the check "
              "weighs them, and along a translation (the first study's move):\n\n", checks);
  header(" the moved one's chi2 drop (6 + sigma^2) | left a view out |");
  CheckStudyOptions o;
  o.noise_given = true;
  o.checks = checks;
  const std::vector<std::pair<PlantedChange, const char*>> moves = {
      {PlantedChange::XAnyDirection, "X, any direction in 6 dof"}, {PlantedChange::XTranslation, "X, its translation"},
      {PlantedChange::YAnyDirection, "Y, any direction in 6 dof"}, {PlantedChange::YTranslation, "Y, its translation"}};
  for (const auto& [change, what] : moves) {
    for (double multiple : {5.0, 6.0}) {
      o.change = change;
      o.multiple = multiple;
      o.seed = seed + 300 + static_cast<unsigned>(10 * multiple) + (moves_X(change) ? 0u : 1000u);
      row(what, run_check_study(o), multiple, false, true);
    }
  }
  std::printf("\nThe translation moved by 5 times the 1 sigma the check prints beside a change (the translation's own "
              "spread along the move, its rotation not held fixed; the noncentrality 25 (u' Cov u)(u' Cov^-1 u), no bound shown):\n\n");
  header(" the moved one's chi2 drop | left a view out |");
  o.sigma_as_printed = true;
  o.multiple = 5.0;
  o.bound_draws = 0;
  for (PlantedChange change : {PlantedChange::XTranslation, PlantedChange::YTranslation}) {
    o.change = change;
    o.seed = seed + 350 + (moves_X(change) ? 0u : 1000u);
    CheckStudyResult r = run_check_study(o);
    r.bound = 0.0;  // its noncentrality is 25 (u' Cov u)(u' Cov^-1 u), at least 25: the bounds are not these moves'
    row(moves_X(change) ? "X, its translation" : "Y, its translation", r, 5.0, false, true);
  }
  return 0;
}

/// The study at views between the usual and the turned ones (tilt to 45 deg, roll to 90:
/// mean cosine 0.73): no change, and X's and Y's translation moved by 5 and 6 sigma.
int between_study(int checks, unsigned seed) {
  std::printf("Views between the two (tilt to 45 deg, roll to 90 deg about the optical axis), %d checks a row:\n\n", checks);
  header();
  CheckStudyOptions o;
  o.noise_given = true;
  o.checks = checks;
  o.seed = seed + 200;
  o.viewpoints.max_tilt = radians(45.0), o.viewpoints.max_roll = radians(90.0);
  row("nothing", run_check_study(o), 0.0);
  for (PlantedChange change : {PlantedChange::XTranslation, PlantedChange::YTranslation}) {
    for (double multiple : {5.0, 6.0}) {
      o.change = change;
      o.multiple = multiple;
      o.seed = seed + 200 + static_cast<unsigned>(10 * multiple);
      row(change == PlantedChange::XTranslation ? "X (camera on its mount)" : "Y (the target)", run_check_study(o), multiple);
    }
  }
  return 0;
}

int main(int argc, char** argv) {
  int checks = 300, calibration_views = 20;
  unsigned seed = 1;
  std::string rendered;
  bool between = false, frontier_only = false, scale_only = false, any_direction = false, views_given = false,
       checks_given = false;
  const auto usage = [] {
    std::fprintf(stderr, "usage: handeye_check_study [--checks 300] [--seed 1] [--rendered TARGET_FILE "
                         "[--calibration-views 20] | --views-between | --any-direction | --frontier | --estimated-scale]\n");
    return 2;
  };
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--views-between" || flag == "--frontier") {
      (flag == "--frontier" ? frontier_only : between) = true;
      continue;
    }
    if (flag == "--estimated-scale" || flag == "--any-direction") {
      (flag == "--any-direction" ? any_direction : scale_only) = true;
      continue;
    }
    if (i + 1 >= argc || std::string(argv[i + 1]).rfind("--", 0) == 0) return usage();  // a flag without its value
    const char* value = argv[++i];
    if (flag == "--rendered") {
      rendered = value;
      continue;
    }
    const std::optional<int> number = positive(value);
    if (!number) return usage();
    if (flag == "--checks") checks = *number, checks_given = true;
    else if (flag == "--seed") seed = static_cast<unsigned>(*number);
    else if (flag == "--calibration-views") calibration_views = *number, views_given = true;
    else return usage();
  }
  // One study at a time, and no setting it would not use.
  if (int(!rendered.empty()) + int(between) + int(frontier_only) + int(scale_only) + int(any_direction) > 1 ||
      (views_given && rendered.empty()) || (checks_given && (frontier_only || scale_only))) {
    return usage();
  }
  if (frontier_only) return frontier(seed);
  if (scale_only) return estimated_scale(seed);
  if (!rendered.empty()) {
    try {
      return rendered_study(rendered, checks, seed, calibration_views);
    } catch (const HandEyeError& e) {
      std::fprintf(stderr, "handeye_check_study: %s\n", e.what());
      return 2;
    }
  }
  if (between) return between_study(checks, seed);
  if (any_direction) return any_direction_study(checks, seed);
  for (bool diverse : {false, true}) {
    std::printf("%s\n\n", diverse ? "Views turned about different axes (tilt to 60 deg, any roll about the optical axis):"
                                  : "The session's usual views (0.4-0.8 m, tilt to 35 deg, roll to 60 deg):");
    header();
    CheckStudyOptions o;
    o.noise_given = true;
    o.checks = checks;
    o.seed = seed;
    if (diverse) o.viewpoints.max_tilt = radians(60.0), o.viewpoints.max_roll = M_PI;
    row("nothing", run_check_study(o), 0.0);
    for (PlantedChange change : {PlantedChange::XTranslation, PlantedChange::YTranslation}) {
      for (double multiple : {2.0, 3.0, 4.0, 5.0, 6.0, 7.0}) {
        o.change = change;
        o.multiple = multiple;
        o.seed = seed + static_cast<unsigned>(10 * multiple);
        row(change == PlantedChange::XTranslation ? "X (camera on its mount)" : "Y (the target)", run_check_study(o),
            multiple);
      }
    }
    std::printf("\n");
  }
  std::printf("The noise estimated from the calibration's 20 views (no noise block), the session's usual views:\n\n");
  header();
  CheckStudyOptions o;
  o.noise_given = false;
  o.checks = checks;
  o.seed = seed + 100;
  row("nothing", run_check_study(o), 0.0);
  for (PlantedChange change : {PlantedChange::XTranslation, PlantedChange::YTranslation}) {
    o.change = change;
    o.multiple = 5.0;
    row(change == PlantedChange::XTranslation ? "X (camera on its mount)" : "Y (the target)", run_check_study(o), 5.0);
  }
  return 0;
}
