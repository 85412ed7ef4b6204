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
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "handeye_covariance/simulation/check_study.h"

namespace {

using namespace handeye;

void row(const char* what, const CheckStudyResult& r, double multiple) {
  char two[16] = "-", named[16] = "-";
  if (multiple > 0.0) std::snprintf(two, sizeof two, "%.1f%%", 100.0 * r.two_hypothesis_bound);
  if (multiple > 0.0 && r.changed > 0) std::snprintf(named, sizeof named, "%.1f%%", 100.0 * r.named_right());
  std::printf("| %s | %.0f | %.1f%% | %.1f%% | %s | %s |\n", what, multiple, 100.0 * r.rate(), 100.0 * r.bound, two, named);
}

}  // namespace

int main(int argc, char** argv) {
  int checks = 300;
  unsigned seed = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--checks")) checks = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--seed")) seed = static_cast<unsigned>(std::atoi(argv[i + 1]));
    else {
      std::fprintf(stderr, "usage: handeye_check_study [--checks 300] [--seed 1]\n");
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
