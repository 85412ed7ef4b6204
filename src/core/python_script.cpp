#include "handeye_covariance/core/python_script.h"

#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstring>

extern char** environ;

namespace handeye {

std::string run_python_script(const std::string& script, const std::vector<std::string>& arguments) {
  std::vector<std::string> words = {"/usr/bin/python3", script};
  words.insert(words.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (std::string& word : words) argv.push_back(word.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = ::posix_spawn(&pid, words[0].c_str(), nullptr, nullptr, argv.data(), environ);
  if (spawned != 0) return "cannot run " + words[0] + ": " + std::strerror(spawned);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return "lost " + words[0] + " " + script + ": " + std::strerror(errno);
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return "";
  return words[0] + " " + script + " failed (exit " + std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")";
}

}  // namespace handeye
