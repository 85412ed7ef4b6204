// Reading and writing whole files, and the session settings file (files.h).
#include "handeye_covariance/io/files.h"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <type_traits>
#include <fcntl.h>
#include <unistd.h>

#include "yaml_primitives.h"

namespace handeye {
namespace io {

using namespace detail;  // the shared readers and writers (yaml_primitives.h)

// ---------------------------------------------------------------- session config

void read_session_config(const std::string& path, SessionConfig& config) {
  const YAML::Node root = load(read_file(path), path);
  const Location top{path, ""};
  if (!root.IsNull() && !root.IsMap()) {
    throw HandEyeError(ErrorCode::MalformedFile, "expected `setting: value` lines", path,
                       "see config/calibration_defaults.yaml for the settings and their form");
  }
  std::set<std::string> known;
  for_each_setting(config, [&](const char* key, auto& member, double scale) {
    known.insert(key);
    const YAML::Node node = root[key];
    if (!node || node.IsNull()) return;
    using T = std::decay_t<decltype(member)>;
    try {
      if constexpr (std::is_same_v<T, double>) {
        member = as_double(node, top / key) * scale;
      } else if constexpr (std::is_same_v<T, Setup>) {
        member = setup_from_eye_on_hand(node.as<bool>());
      } else {
        member = node.as<T>();
      }
    } catch (const YAML::Exception&) {
      throw HandEyeError(ErrorCode::MalformedFile, std::string("`") + key + "` has the wrong type", (top / key).str(),
                         "see config/calibration_defaults.yaml for the expected value");
    }
  });
  for (const auto& entry : root) {
    const std::string key = as_text(entry.first, top);
    if (!known.count(key)) {
      throw HandEyeError(ErrorCode::MalformedFile, "unknown setting `" + key + "`", path,
                         "use the node's parameter names (config/calibration_defaults.yaml, launch/calibrate.launch)");
    }
  }
}


// ---------------------------------------------------------------- files

std::string expand_home(const std::string& path) {
  if (path.rfind("~/", 0) != 0) return path;
  const char* home = std::getenv("HOME");
  return std::string(home ? home : ".") + path.substr(1);
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw HandEyeError(ErrorCode::IoError, std::string("cannot open: ") + std::strerror(errno), path,
                       "check the path and the permissions");
  }
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_file_atomically(const std::string& path, const std::string& content) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  std::error_code ec;
  if (target.has_parent_path()) fs::create_directories(target.parent_path(), ec);
  // Unique per process and per call: two threads writing the same file never share a temporary.
  static std::atomic<unsigned> calls{0};
  const std::string temporary = path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(calls++);
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  bool ok = fd >= 0;
  for (std::size_t written = 0; ok && written < content.size();) {
    const ssize_t n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) written += static_cast<std::size_t>(n);
  }
  ok = ok && ::fsync(fd) == 0;  // the data is on disk before the name points at it
  if (fd >= 0) ok = (::close(fd) == 0) && ok;
  if (!ok) {
    const std::string reason = std::strerror(errno);
    std::remove(temporary.c_str());
    throw HandEyeError(ErrorCode::IoError, "cannot write: " + reason, path,
                       "check that the directory is writable and the disk is not full");
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    const std::string reason = std::strerror(errno);
    std::remove(temporary.c_str());
    throw HandEyeError(ErrorCode::IoError, "cannot rename the temporary file into place: " + reason, path,
                       "check the permissions of the target directory");
  }
}

}  // namespace io
}  // namespace handeye
