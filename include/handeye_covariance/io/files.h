// Whole files: reading, writing atomically, `~/` paths; and a file of
// `setting: value` lines read key by key (the session's settings file). No ROS.
#pragma once

#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace handeye {
namespace io {

/// A YAML file of `setting: value` lines, read key by key: value<T>(key) returns the
/// key's value (T: double, bool, int, std::string or std::vector<int>), nothing when the
/// key is absent or null, and throws MalformedFile naming the file and key when the
/// value has the wrong type. refuse_unknown() throws for a key no one asked for (a
/// typo), with `fix` as the advice.
class SettingsFile {
 public:
  explicit SettingsFile(const std::string& path);
  ~SettingsFile();
  template <class T>
  std::optional<T> value(const std::string& key);
  void refuse_unknown(const std::string& fix) const;

 private:
  struct Yaml;
  std::unique_ptr<Yaml> yaml_;
  std::string path_;
  std::set<std::string> asked_;
};

/// Write to `path.tmp-<pid>` then rename, so a reader never sees half a file
/// and a failure leaves no file behind. Creates missing parent directories.
void write_file_atomically(const std::string& path, const std::string& content);

/// Whole file as text; HandEyeError(IoError) when it cannot be read.
std::string read_file(const std::string& path);

/// `~/rest` as $HOME/rest (a path from a launch file or a parameter); any other path as it is.
std::string expand_home(const std::string& path);

}  // namespace io
}  // namespace handeye
