// Issue 41's figure: the check of a saved calibration (estimation/calibration_check.h)
// on simulated sessions: how often it says "changed" as X's or Y's translation is moved
// by 0 to 8 times its own 1 sigma of the change along the move, beside the bound for a
// 6-dof test that knows which one moved (noncentral chi2) and the bound for any test
// that must catch either (the Neyman-Pearson test against their mixture, at each check's
// views); which one it names; at a session's usual views and at views turned about
// different axes. simulation/check_study.h. Seeded; no ROS.
//
//   handeye_check_study [--checks 300] [--seed 1]
// Prints Markdown tables (scripts/bench puts them in BENCHMARKS.md).
//   handeye_check_study --rendered config/tag_board_2x2.yaml [--checks 300] [--seed 1]
// The same through the images (simulation/rendered_views.h): each calibration's 20 views
// and each check's 5 rendered, detected with the pixel sigma pooled over the set, the
// noise estimated beside the detections' covariance, at the session's usual views.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/io/target_file.h"
#include "handeye_covariance/simulation/check_study.h"
#include "handeye_covariance/simulation/rendered_views.h"

namespace {

using namespace handeye;

void row(const char* what, const CheckStudyResult& r, double multiple) {
  char two[16] = "-", named[16] = "-";
  if (multiple > 0.0) std::snprintf(two, sizeof two, "%.1f%%", 100.0 * r.two_hypothesis_bound);
  if (multiple > 0.0 && r.changed > 0) std::snprintf(named, sizeof named, "%.1f%%", 100.0 * r.named_right());
  std::printf("| %s | %.0f | %.1f%% | %.1f%% | %s | %s |\n", what, multiple, 100.0 * r.rate(), 100.0 * r.bound, two, named);
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
  std::printf("| moved | sigma | says changed | 6-dof bound (knows which) | bound for X or Y | names it right | chi2 / dof |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|\n");
  const auto rendered_row = [](const char* what, const CheckStudyResult& r, double multiple) {
    char two[16] = "-", named[16] = "-";
    if (multiple > 0.0) std::snprintf(two, sizeof two, "%.1f%%", 100.0 * r.two_hypothesis_bound);
    if (multiple > 0.0 && r.changed > 0) std::snprintf(named, sizeof named, "%.1f%%", 100.0 * r.named_right());
    std::printf("| %s | %.0f | %.1f%% (%d of %d) | %.1f%% | %s | %s | %.3f |\n", what, multiple, 100.0 * r.rate(), r.changed,
                r.checks, 100.0 * r.bound, two, named, r.mean_chi2_over_dof);
    std::fflush(stdout);
  };
  rendered_row("nothing", run_check_study(o), 0.0);
  for (PlantedChange change : {PlantedChange::XTranslation, PlantedChange::YTranslation}) {
    o.change = change;
    o.multiple = 5.0;
    o.seed = seed + 50;
    rendered_row(change == PlantedChange::XTranslation ? "X (camera on its mount)" : "Y (the target)", run_check_study(o), 5.0);
  }
  return 0;
}

int main(int argc, char** argv) {
  int checks = 300;
  unsigned seed = 1;
  int calibration_views = 20;
  std::string rendered;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--checks")) checks = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--seed")) seed = static_cast<unsigned>(std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--rendered")) rendered = argv[i + 1];
    else if (!std::strcmp(argv[i], "--calibration-views")) calibration_views = std::atoi(argv[i + 1]);
    else {
      std::fprintf(stderr, "usage: handeye_check_study [--checks 300] [--seed 1] [--rendered TARGET_FILE [--calibration-views 20]]\n");
      return 2;
    }
  }
  if (!rendered.empty()) {
    try {
      return rendered_study(rendered, checks, seed, calibration_views);
    } catch (const HandEyeError& e) {
      std::fprintf(stderr, "handeye_check_study: %s\n", e.what());
      return 2;
    }
  }
  for (bool diverse : {false, true}) {
    std::printf("%s\n\n", diverse ? "Views turned about different axes (tilt to 60 deg, any roll about the optical axis):"
                                  : "The session's usual views (0.4-0.8 m, tilt to 35 deg, roll to 60 deg):");
    std::printf("| moved | sigma | says changed | 6-dof bound (knows which) | bound for X or Y | names it right |\n");
    std::printf("|---|---:|---:|---:|---:|---:|\n");
    CheckStudyOptions o;
    o.noise_given = true;
    o.checks = checks;
    o.seed = seed;
    if (diverse) o.viewpoints.max_tilt = 60.0 * M_PI / 180.0, o.viewpoints.max_roll = M_PI;
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
  std::printf("| moved | sigma | says changed | 6-dof bound (knows which) | bound for X or Y | names it right |\n");
  std::printf("|---|---:|---:|---:|---:|---:|\n");
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
