// libFuzzer target for the samples family (src/io/samples_file.cpp): samples,
// motions and candidate poses on the same bytes. A reader may only return or throw
// HandEyeError; anything else (another exception, a crash, a leak, undefined
// behaviour under UBSan) is a bug. What a reader accepts is written and read back
// with the same values (a refusal or a difference there is a bug too), and, on small
// sets, solved: what `handeye solve` does next.
//
// Built twice: fuzz_samples_files (readers, then the estimator) and, with
// HANDEYE_FUZZ_READERS_ONLY, fuzz_samples_parse (readers and the round trip only):
// the estimator runs at ~100 exec/s under ASan, the parse-only build reaches 10^6
// inputs in minutes. Seeds: test/fuzz/corpus/samples_files. Short run in
// ./scripts/test; the long runs in docs/evidence.md.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

#include "handeye_covariance/core/errors.h"
#include "named_errors_only.h"
#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/estimation/outliers.h"
#include "handeye_covariance/estimation/solve.h"
#include "handeye_covariance/io/samples_file.h"

namespace {

/// What we write we read, with the same values: a re-read that throws (even a named
/// error) or differs is a bug of the writer, reported as a crash.
[[noreturn]] void round_trip_failed(const char* what) {
  std::fprintf(stderr, "round trip: %s\n", what);
  std::abort();
}

bool same_pose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff() <= 1e-9 * std::max(1.0, a.matrix().cwiseAbs().maxCoeff());
}

template <typename Read>
auto read_back(Read&& read) {
  try {
    return read();
  } catch (const handeye::HandEyeError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    round_trip_failed("the writer's output was refused");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace handeye;
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::optional<SampleSet> samples;
  named_errors_only([&] { samples = io::parse_samples(text, "fuzz"); });
  if (samples) {
#ifndef HANDEYE_FUZZ_READERS_ONLY
    if (samples->samples.size() <= 8) named_errors_only([&] { solve_robust(*samples); });
#endif
    const SampleSet back = read_back([&] { return io::parse_samples(io::format_samples(*samples), "round trip"); });
    if (back.samples.size() != samples->samples.size()) round_trip_failed("a different number of samples");
    if (back.noise.has_value() != samples->noise.has_value()) round_trip_failed("the noise block lost or added");
    for (std::size_t i = 0; i < back.samples.size(); ++i) {
      const PoseSample &a = samples->samples[i], &b = back.samples[i];
      if (!same_pose(a.T_base_effector, b.T_base_effector) || !same_pose(a.T_camera_pattern, b.T_camera_pattern)) {
        round_trip_failed("a pose read back differs");
      }
      if (a.stamp != b.stamp || a.noise.has_value() != b.noise.has_value()) round_trip_failed("a stamp or noise differs");
    }
  }
  std::optional<MotionSet> motions;
  named_errors_only([&] { motions = io::parse_motions(text, "fuzz"); });
  if (motions) {
#ifndef HANDEYE_FUZZ_READERS_ONLY
    if (motions->motions.size() <= 8) named_errors_only([&] { solve(*motions); });
#endif
    const MotionSet back = read_back([&] { return io::parse_motions(io::format_motions(*motions), "round trip"); });
    if (back.motions.size() != motions->motions.size()) round_trip_failed("a different number of motions");
    for (std::size_t i = 0; i < back.motions.size(); ++i) {
      if (!same_pose(motions->motions[i].A, back.motions[i].A) || !same_pose(motions->motions[i].B, back.motions[i].B)) {
        round_trip_failed("a motion read back differs");
      }
    }
  }
  named_errors_only([&] { io::parse_candidate_poses(text, "fuzz"); });
  return 0;
}
