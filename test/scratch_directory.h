// A directory of this test process's own, for the files a test writes and reads back.
// catkin_make runs two test binaries or rostests at once (-j of the core count), so a
// fixed name under /tmp shared by two of them is overwritten under the other's feet
// (the CI of 2026-11-25 failed that way twice: the detector_end_to_end variants, and
// test_cli against test_bad_inputs on `handeye`'s captured output).
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

namespace handeye::test {

/// Made on first use under gtest's TempDir(); removed when the process ends, unless
/// HANDEYE_KEEP_TEST_FILES is set (to look at them after a failure).
inline const std::string& scratch_directory() {
  struct Directory {
    std::string path;
    Directory() {
      path = ::testing::TempDir() + "/handeye_test-XXXXXX";
      if (::mkdtemp(path.data()) == nullptr) {
        std::fprintf(stderr, "mkdtemp(%s) failed: free space in %s\n", path.c_str(), ::testing::TempDir().c_str());
        std::abort();
      }
    }
    ~Directory() {
      std::error_code ignored;
      if (std::getenv("HANDEYE_KEEP_TEST_FILES") == nullptr) std::filesystem::remove_all(path, ignored);
    }
  };
  static const Directory directory;
  return directory.path;
}

}  // namespace handeye::test
