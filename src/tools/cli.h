// The `handeye` command line tool. Subcommands share the library; none copies logic.
#pragma once

#include <iosfwd>

namespace handeye {
namespace cli {

/// Exit codes: 0 success, 2 bad or degenerate input (reason on stderr, no output
/// file written), 1 an unexpected internal failure.
int run(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

}  // namespace cli
}  // namespace handeye
