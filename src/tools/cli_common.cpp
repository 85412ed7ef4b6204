#include "handeye_covariance/tools/cli_common.h"

#include <filesystem>
#include <iostream>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/io/summary.h"
#include "handeye_covariance/io/yaml_io.h"

namespace handeye {
namespace cli {

bool parse(const std::string& name, const std::string& usage, const po::options_description& options,
           const Args& args, po::variables_map& vm, std::ostream& out) {
  po::store(po::command_line_parser(args).options(options).run(), vm);
  if (vm.count("help")) {
    out << "usage: handeye " << name << " " << usage << "\n\n" << options << "\n";
    return false;
  }
  po::notify(vm);
  return true;
}

std::string default_result_path(const std::string& input) {
  return std::filesystem::path(input).stem().string() + "_result.yaml";
}

void print_help(const CommandTable& commands, std::ostream& out) {
  out << "usage: handeye <command> [options]    (handeye <command> --help for its options)\n\n"
         "Hand-eye calibration AX = XB with the covariance of X.\n\ncommands:\n";
  std::size_t width = 0;
  for (const auto& entry : commands) width = std::max(width, entry.first.size());
  for (const auto& [name, command] : commands) {
    out << "  " << name << std::string(width + 2 - name.size(), ' ') << command.summary << "\n";
  }
  out << "\nexit codes: 0 success, 2 bad or degenerate input (reason on stderr, nothing written), "
         "1 internal error\n";
}

int run_commands(const CommandTable& commands, int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h" || std::string(argv[1]) == "help") {
    print_help(commands, out);
    return argc < 2 ? kBadInput : kOk;
  }
  const std::string name = argv[1];
  const auto command = commands.find(name);
  if (command == commands.end()) {
    err << "handeye: unknown command `" << name << "`\n\n";
    print_help(commands, err);
    return kBadInput;
  }
  const Args args(argv + 2, argv + argc);
  try {
    return command->second.run(args, out, err);
  } catch (const HandEyeError& e) {
    err << "handeye " << name << ": error: " << e.what() << "\n";
    return kBadInput;
  } catch (const po::error& e) {
    err << "handeye " << name << ": " << e.what() << " (see `handeye " << name << " --help`)\n";
    return kBadInput;
  } catch (const std::exception& e) {
    err << "handeye " << name << ": internal error: " << e.what() << "\n";
    return kInternal;
  }
}

void ProgressBar::operator()(double fraction) {
  const int percent = static_cast<int>(100.0 * fraction);
  if (!enabled_ || percent == last_) return;
  last_ = percent;
  const int filled = percent / 4;
  err_ << "\r" << label_ << " [" << std::string(filled, '#') << std::string(25 - filled, '.') << "] " << percent << "%"
       << (percent >= 100 ? "\n" : "") << std::flush;
}

Setup SimArgs::checked_setup() const {
  const Setup setup = setup_from_string(setup_name, "--setup");
  if (samples < 3) {
    throw HandEyeError(ErrorCode::TooFewMotions, "--samples must be at least 3", "--samples", "ask for more samples");
  }
  return setup;
}

void add_honesty_options(po::options_description& options, HonestyArgs& a) {
  options.add_options()(
      "split-check", po::value(&a.options.splits),
      "the honesty check: solve N random halves (default 200; 0: no check) and compare the NEES of their difference "
      "with what an honest covariance gives on these poses (a parametric bootstrap); from 8 samples")(
      "reference-sessions", po::value(&a.options.replicates), "the honesty check's simulated honest sessions (default 100)")(
      "split-runs", po::value(&a.options.run_length),
      "the honesty check's second look: halves made of runs of K consecutive samples, as well as random ones (an "
      "error shared by poses taken close together cancels between random halves); default 0: K = n / 8 within "
      "[2, 4] from 16 samples; 1: random halves alone; from 4 K samples")(
      "no-inflation", po::bool_switch(&a.no_inflation),
      "keep the noise model's covariance even when the honesty check finds it overconfident (by default it is "
      "inflated by the measured factor)")(
      "shared-robot-error", po::value(&a.shared_robot_error),
      "a robot error shared by nearby poses, fitted from 16 to 40 samples: use (default: where the likelihood prefers "
      "it, X and its covariance are its own, and the honesty check judges it), advice (said, not used) or off");
}

void HonestyArgs::apply(SessionSettings& settings) const {
  if (options.splits < 0 || options.replicates < 2 || options.run_length < 0) {
    throw HandEyeError(ErrorCode::MalformedFile, "--split-check must be >= 0, --reference-sessions >= 2 and --split-runs >= 0",
                       "--split-check", "e.g. --split-check 200 --reference-sessions 100 --split-runs 4, or --split-check 0 for no check");
  }
  settings.honesty = options;
  settings.inflate_when_overconfident = !no_inflation;
  settings.shared_robot_error = shared_error_use_from_string(shared_robot_error, "--shared-robot-error");
}

int run_check(const std::string& calibration_path, const SampleSet& views, const std::string& output, double alpha,
              std::ostream& out) {
  CheckOptions options;
  options.alpha = alpha;
  const CalibrationCheck check = check_calibration(io::read_calibration_to_check(calibration_path, views.rig), views, options);
  out << io::check_summary(check);
  if (!output.empty()) {
    io::write_file_atomically(output, io::format_check(check, calibration_path));
    out << "  check written to      " << output << "\n";
  }
  return check.changed ? kChanged : kOk;
}

void add_sim_options(po::options_description& options, SimArgs& a) {
  options.add_options()("help,h", "show this help")(
      "output,o", po::value(&a.output)->required(), "samples file to write (YAML), or a rosbag (.bag)")(
      "truth", po::value(&a.truth), "also write the true X as a result file (bags: default <bag stem>_truth.yaml beside it)")(
      "setup", po::value(&a.setup_name), "eye_in_hand (default) or eye_to_hand")(
      "samples,n", po::value(&a.samples), "number of robot poses (default 20)")(
      "seed", po::value(&a.seed), "random seed (default 1)")(
      "pattern-rotation-noise-deg", po::value(&a.rotation_deg), "1 sigma per axis of the pattern pose rotation (default 0.05)")(
      "pattern-translation-noise-mm", po::value(&a.translation_mm), "1 sigma per axis of the pattern pose translation (default 0.5)")(
      "robot-rotation-noise-deg", po::value(&a.robot_rotation_deg), "1 sigma per axis of the flange rotation (default 0.01)")(
      "robot-translation-noise-mm", po::value(&a.robot_translation_mm), "1 sigma per axis of the flange translation (default 0.05)")(
      "omit-noise-block", po::bool_switch(&a.omit_noise), "leave the noise out of the file, so `solve` estimates it");
}

}  // namespace cli
}  // namespace handeye
