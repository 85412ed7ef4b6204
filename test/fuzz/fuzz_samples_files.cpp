// libFuzzer target for the samples family (src/io/samples_file.cpp): samples,
// motions and candidate poses on the same bytes. A reader may only return or throw
// HandEyeError; anything else (another exception, a crash, a leak, undefined
// behaviour under UBSan) is a bug. What a reader accepts is written and read back,
// and, on small sets, solved: what `handeye solve` does next.
//
// Built twice: fuzz_samples_files (readers, then the estimator) and, with
// HANDEYE_FUZZ_READERS_ONLY, fuzz_samples_parse (readers and the round trip only):
// the estimator runs at ~100 exec/s under ASan, the parse-only build reaches 10^6
// inputs in minutes. Seeds: test/fuzz/corpus/samples_files. Short run in
// ./scripts/test; the long runs in docs/evidence.md.
#include <cstdint>
#include <string>

#include "handeye_covariance/core/errors.h"
#include "named_errors_only.h"
#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/estimation/outliers.h"
#include "handeye_covariance/estimation/solve.h"
#include "handeye_covariance/io/samples_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace handeye;
  const std::string text(reinterpret_cast<const char*>(data), size);
  named_errors_only([&] {
    const SampleSet s = io::parse_samples(text, "fuzz");
#ifndef HANDEYE_FUZZ_READERS_ONLY
    if (s.samples.size() <= 8) named_errors_only([&] { solve_robust(s); });
#endif
    io::parse_samples(io::format_samples(s), "round trip");  // what we write, we read
  });
  named_errors_only([&] {
    const MotionSet m = io::parse_motions(text, "fuzz");
#ifndef HANDEYE_FUZZ_READERS_ONLY
    if (m.motions.size() <= 8) named_errors_only([&] { solve(m); });
#endif
    io::parse_motions(io::format_motions(m), "round trip");
  });
  named_errors_only([&] { io::parse_candidate_poses(text, "fuzz"); });
  return 0;
}
