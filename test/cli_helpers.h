// Running the real `handeye` binary from a test, as a user would.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "handeye_covariance/io/yaml_io.h"
#include "scratch_directory.h"

namespace handeye::test {

struct CliRun {
  int exit_code;
  std::string out, err;
};

/// `handeye <args>`; its exit code, stdout and stderr.
inline CliRun run(const std::string& args) {
  const std::string& dir = scratch_directory();
  const std::string out_file = dir + "/cli_stdout", err_file = dir + "/cli_stderr";
  const std::string command = std::string(HANDEYE_CLI) + " " + args + " >" + out_file + " 2>" + err_file;
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, io::read_file(out_file), io::read_file(err_file)};
}

/// A path in the test process's own directory; the file is removed first.
inline std::string temp(const std::string& name) {
  const std::string path = scratch_directory() + "/cli_" + name;
  std::filesystem::remove(path);
  return path;
}

}  // namespace handeye::test
