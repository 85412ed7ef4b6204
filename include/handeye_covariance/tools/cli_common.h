// What the command-line programs share: `handeye` (no ROS library), `handeye_bag`
// (rosbag; `handeye bag` and `handeye sim --output x.bag` run it) and
// `handeye_images` (OpenCV; `handeye images` runs it).
// Option parsing, the command table with its exit codes, a progress bar, and the
// options of `sim` that both kinds of output take.
#pragma once

#include <boost/program_options.hpp>
#include <functional>
#include <iosfwd>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "handeye_covariance/core/rig.h"
#include "handeye_covariance/session/calibration_session.h"

namespace handeye {
namespace cli {

namespace po = boost::program_options;

/// Exit codes: 0 success, 2 bad or degenerate input (reason on stderr, no output
/// file written), 1 an unexpected internal failure.
constexpr int kOk = 0;
constexpr int kInternal = 1;
constexpr int kBadInput = 2;

using Args = std::vector<std::string>;

struct Command {
  const char* summary;
  std::function<int(const Args&, std::ostream&, std::ostream&)> run;
};
using CommandTable = std::map<std::string, Command>;

/// Parses `args` against `options`; prints help and returns false on --help.
bool parse(const std::string& name, const std::string& usage, const po::options_description& options,
           const Args& args, po::variables_map& vm, std::ostream& out);

/// <input stem>_result.yaml in the current directory.
std::string default_result_path(const std::string& input);

/// Runs the command argv[1] of `commands` with the shared error handling: a
/// HandEyeError or a bad option exits 2 with the reason, anything else 1.
int run_commands(const CommandTable& commands, int argc, const char* const* argv, std::ostream& out, std::ostream& err);

/// "usage: handeye <command> ..." and the command list.
void print_help(const CommandTable& commands, std::ostream& out);

/// A progress bar on stderr ("<label> [#####....] 40%"), redrawn when the
/// percentage changes; silent when disabled (stderr is not a terminal).
class ProgressBar {
 public:
  ProgressBar(std::ostream& err, std::string label, bool enabled)
      : err_(err), label_(std::move(label)), enabled_(enabled) {}
  void operator()(double fraction);

 private:
  std::ostream& err_;
  std::string label_;
  bool enabled_;
  int last_ = -1;
};

/// The honesty check's options of every command that calibrates (solve, images,
/// bag): --split-check N (0: none), --reference-sessions N, --split-runs K, --no-inflation,
/// --shared-robot-error use|advice|off.
struct HonestyArgs {
  HonestyOptions options;
  bool no_inflation = false;
  std::string shared_robot_error = "use";
  /// Into a session's settings, after checking the values (HandEyeError naming the option).
  void apply(SessionSettings& settings) const;
};
void add_honesty_options(po::options_description& options, HonestyArgs& args);

/// `handeye check`: exit 0 when the views fit the calibration, 3 when it changed (as
/// `diff` exits 1 on a difference; 1 and 2 are taken).
constexpr int kChanged = 3;
/// The check of `calibration_path` (a result file) against `views` (from a samples
/// file, or images in handeye_images): refuses another setup, prints the verdict and
/// the views' table, writes `output` when given, returns kOk or kChanged.
int run_check(const std::string& calibration_path, const SampleSet& views, const std::string& output, double alpha,
              std::ostream& out);

/// The options of `sim` common to a samples file and a bag.
struct SimArgs {
  std::string output, truth, setup_name = "eye_in_hand";
  int samples = 20;
  unsigned seed = 1;
  double rotation_deg = 0.05, translation_mm = 0.5, robot_rotation_deg = 0.01, robot_translation_mm = 0.05;
  bool omit_noise = false;
  /// The setup, after checking the values (HandEyeError naming the option).
  Setup checked_setup() const;
};
void add_sim_options(po::options_description& options, SimArgs& args);

}  // namespace cli
}  // namespace handeye
