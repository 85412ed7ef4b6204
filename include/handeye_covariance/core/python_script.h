// One way to run the package's figure scripts (matplotlib): the report's
// (scripts/report.py) and validate's (scripts/plot_validation.py).
#pragma once

#include <string>
#include <vector>

namespace handeye {

/// Runs /usr/bin/python3 `script` `arguments...` without a shell (an argument such as
/// a directory's name is passed as it is, never parsed) and waits for it. Returns ""
/// when it exited 0, else what went wrong: it could not start, or its exit status.
std::string run_python_script(const std::string& script, const std::vector<std::string>& arguments);

}  // namespace handeye
