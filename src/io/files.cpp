// Reading and writing whole files, and settings files (files.h).
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

// ---------------------------------------------------------------- settings file

struct SettingsFile::Yaml {
  YAML::Node root;
};

SettingsFile::SettingsFile(const std::string& path) : yaml_(std::make_unique<Yaml>()), path_(path) {
  yaml_->root = load(read_file(path), path);
  if (!yaml_->root.IsNull() && !yaml_->root.IsMap()) {
    throw HandEyeError(ErrorCode::MalformedFile, "expected `setting: value` lines", path,
                       "see config/calibration_defaults.yaml for the settings and their form");
  }
}

SettingsFile::~SettingsFile() = default;

/// `key`'s value as T (yaml-cpp's conversion), nothing when absent or null.
template <class T>
std::optional<T> SettingsFile::value(const std::string& key) {
  asked_.insert(key);
  const YAML::Node node = yaml_->root[key];
  if (!node || node.IsNull()) return std::nullopt;
  const Location at = Location{path_, ""} / key;
  try {
    if constexpr (std::is_same_v<T, double>) {
      return as_double(node, at);
    } else {
      return node.as<T>();
    }
  } catch (const YAML::Exception&) {
    throw HandEyeError(ErrorCode::MalformedFile, "`" + key + "` has the wrong type", at.str(),
                       "see config/calibration_defaults.yaml for the expected value");
  }
}
template std::optional<double> SettingsFile::value(const std::string&);
template std::optional<bool> SettingsFile::value(const std::string&);
template std::optional<int> SettingsFile::value(const std::string&);
template std::optional<std::string> SettingsFile::value(const std::string&);
template std::optional<std::vector<int>> SettingsFile::value(const std::string&);

void SettingsFile::refuse_unknown(const std::string& fix) const {
  for (const auto& entry : yaml_->root) {
    const std::string key = as_text(entry.first, Location{path_, ""});
    if (!asked_.count(key)) throw HandEyeError(ErrorCode::MalformedFile, "unknown setting `" + key + "`", path_, fix);
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
