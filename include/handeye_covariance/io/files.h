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

/// A YAML file of `setting: value` lines, read key by key: each accessor returns the
/// key's value, nothing when the key is absent or null, and throws MalformedFile
/// naming the file and key when the value has the wrong type. refuse_unknown()
/// throws for a key no accessor asked for (a typo), with `fix` as the advice.
class SettingsFile {
 public:
  explicit SettingsFile(const std::string& path);
  ~SettingsFile();
  std::optional<double> number(const std::string& key);
  std::optional<bool> flag(const std::string& key);
  std::optional<int> whole_number(const std::string& key);
  std::optional<std::string> text(const std::string& key);
  std::optional<std::vector<int>> whole_numbers(const std::string& key);
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
