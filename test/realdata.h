// Where the real sessions are (../shared/realdata; read from there, never copied
// into the package): $HANDEYE_REALDATA, else shared/realdata beside the repository
// or beside one of its parents (a clone may sit deeper than the working copy),
// else this workplace's /work/shared/realdata. The test defines
// HANDEYE_REPOSITORY_DIR.
#pragma once

#include <cstdlib>
#include <filesystem>

namespace handeye {
namespace test {

inline std::filesystem::path realdata() {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("HANDEYE_REALDATA")) return env;
  for (fs::path dir = fs::path(HANDEYE_REPOSITORY_DIR).parent_path(); !dir.empty(); dir = dir.parent_path()) {
    if (fs::exists(dir / "shared" / "realdata")) return dir / "shared" / "realdata";
    if (dir == dir.root_path()) break;
  }
  return "/work/shared/realdata";
}

}  // namespace test
}  // namespace handeye
