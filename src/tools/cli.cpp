#include "cli.h"

#include <cerrno>
#include <cstring>

#include <boost/program_options.hpp>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <sstream>
#include <unistd.h>

#include "handeye_covariance/tools/cli_common.h"

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/python_script.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/simulation/monte_carlo_study.h"
#include "handeye_covariance/estimation/noise_estimation.h"
#include "handeye_covariance/core/object_pose.h"
#include "handeye_covariance/estimation/outliers.h"
#include "handeye_covariance/estimation/solve.h"
#include "handeye_covariance/core/validation.h"
#include "handeye_covariance/simulation/simulation.h"
#include "handeye_covariance/io/summary.h"
#include "handeye_covariance/io/warning_text.h"
#include "handeye_covariance/session/calibration_session.h"
#include "handeye_covariance/session/report.h"

namespace handeye {
namespace cli {

namespace {

/// `handeye bag ...` and `handeye sim --output x.bag ...` run the handeye_bag
/// program beside this one (it links rosbag), `handeye images ...` handeye_images
/// (OpenCV, libapriltag), `handeye target ...` handeye_target (cairo): this one
/// links none of them.
int run_tool(const std::string& program, const std::string& command, const Args& args, std::ostream& out,
             std::ostream& err) {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) {  // never a relative "handeye_bag" from the current directory
    err << "handeye " << command << ": cannot find this program's own path (/proc/self/exe: " << ec.message()
        << "); run " << program << " from the package's lib folder instead\n";
    return kInternal;
  }
  const std::string tool = (self.parent_path() / program).string();
  std::vector<std::string> words = {tool, command};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  out.flush();
  err.flush();
  ::execv(tool.c_str(), argv.data());
  err << "handeye " << command << ": cannot run " << tool << ": " << std::strerror(errno)
      << " (it is built with the package: ./scripts/setup, or catkin_make)\n";
  return kInternal;
}

int run_bag_tool(const std::string& command, const Args& args, std::ostream& out, std::ostream& err) {
  return run_tool("handeye_bag", command, args, out, err);
}

/// What `handeye solve` and `handeye report` both take for a samples file's session:
/// declared once (add_session_options), read once (samples_session).
struct SessionArgs {
  std::string noise_path, method = "joint", robust = "auto";
  bool keep_outliers = false;
};

void add_session_options(po::options_description& options, SessionArgs& a) {
  options.add_options()(
      "noise", po::value(&a.noise_path), "a file with a `noise:` block (e.g. from `handeye noise`); replaces the input's")(
      "keep-outliers", po::bool_switch(&a.keep_outliers), "samples: do not reject wrong detections (they are by default)")(
      "method", po::value(&a.method),
      "samples: joint (X and the pattern pose from the poses; default) or pairs (the paper's AX = XB)")(
      "robust", po::value(&a.robust),
      "joint: auto (Huber's loss and the sandwich covariance when the residuals are heavy-tailed; default), on, off");
}

/// The session `handeye solve` and `handeye report` run on the samples of `input`:
/// the file's setup, frames and noise (or --noise's), the options' rejection,
/// method and robust mode, the node's other settings from `config`.
CalibrationSession samples_session(const SampleSet& samples, const std::string& input, const SessionConfig& config,
                                   const SessionArgs& a, const HonestyArgs& honesty = {}) {
  SessionSettings settings = session_settings(samples, config);
  honesty.apply(settings);
  if (!a.noise_path.empty()) settings.noise = io::read_noise_file(a.noise_path);
  settings.reject_outliers = !a.keep_outliers;
  settings.method = method_from_string(a.method);
  settings.robust = robust_from_string(a.robust);
  CalibrationSession session(settings);
  session.replace(samples.samples, "read " + input);
  return session;
}

int solve_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  std::string input, output;
  SessionArgs session_args;
  HonestyArgs honesty;
  po::options_description options("solve: AX = XB with the covariance of X");
  options.add_options()("help,h", "show this help")(
      "input,i", po::value(&input)->required(), "samples or motions file (YAML)")(
      "output,o", po::value(&output),
      "result file (YAML); default: <input stem>_result.yaml in the current directory");
  add_session_options(options, session_args);
  add_honesty_options(options, honesty);
  po::variables_map vm;
  if (!parse("solve", "--input FILE [--noise FILE] [--output FILE] [--split-check N] [--no-inflation]", options, args, vm,
             out)) {
    return kOk;
  }

  if (output.empty()) output = default_result_path(input);

  io::Input data = io::read_input(input);
  if (!session_args.noise_path.empty() && !std::holds_alternative<SampleSet>(data)) {
    throw HandEyeError(ErrorCode::MalformedFile, "--noise applies to samples files", input,
                       "put the motions' noise in the motions file's `noise: {A, B}` block");
  }
  Calibration calibration;
  io::ResultContext context;
  if (const SampleSet* samples = std::get_if<SampleSet>(&data)) {
    // Samples go through the session the node and the bag replay use.
    const CalibrationSession session =
        samples_session(*samples, input, {}, session_args, honesty);
    const SessionSnapshot snapshot = session.snapshot();
    calibration = session.calibrate_checked(snapshot);
    context = io::context_of(snapshot.samples);
  } else {
    if (vm.count("split-check") && honesty.options.splits > 0) {
      throw HandEyeError(ErrorCode::MalformedFile, "--split-check applies to samples files", input,
                         "record absolute poses (a samples file): motion pairs cannot be split into independent halves");
    }
    calibration = solve(std::get<MotionSet>(data));
    context = io::context_of(std::get<MotionSet>(data));
  }
  io::write_file_atomically(output, io::format_result(calibration, context));
  out << io::human_summary(calibration, context);
  out << "  result written to     " << output << "\n";
  (void)err;
  return kOk;
}

int report_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  SessionConfig config;
  std::string input, output;
  SessionArgs session_args;
  ReportOptions report_options;
  double target_mm = config.target_tolerance_mm, working_distance = config.working_distance;
  po::options_description options(
      "report: how far X can be trusted and what to do about it: per-sample residuals, leave-one-out and split-half "
      "checks, rotation axes, advice; an HTML page with figures");
  options.add_options()("help,h", "show this help")(
      "input,i", po::value(&input)->required(), "samples file (YAML), e.g. the node's saved session")(
      "output,o", po::value(&output), "directory for report.html, the figures and the YAML; default: <input stem>_report")(
      "splits", po::value(&report_options.splits), "random halves for the split-half check (default 200; 0: leave it out)")(
      "reference-sessions", po::value(&report_options.reference_sessions),
      "simulated honest sessions the split-half check is judged against (default 100)")(
      "split-runs", po::value(&report_options.run_length),
      "the second look: halves made of runs of K consecutive samples (default: the session's, 0: n / 8 within "
      "[2, 4] from 16 samples; 1: random halves alone; docs/how_it_works.md)")(
      "working-distance", po::value(&working_distance),
      ("m along the optical axis for the object's 1 sigma (default " + number_text(working_distance) + ")").c_str())(
      "target-mm", po::value(&target_mm),
      ("the object 1 sigma wanted (default " + number_text(target_mm) + ")").c_str());
  add_session_options(options, session_args);
  po::variables_map vm;
  if (!parse("report", "--input FILE [--output DIR] [--noise FILE] [--splits N]", options, args, vm, out)) return kOk;
  if (!(working_distance > 0.0) || !(target_mm > 0.0) || report_options.splits < 0 || report_options.reference_sessions < 2 ||
      (vm.count("split-runs") && report_options.run_length < 0)) {
    throw HandEyeError(ErrorCode::MalformedFile,
                       "--working-distance and --target-mm must be > 0, --splits >= 0, --reference-sessions >= 2, "
                       "--split-runs >= 0",
                       "options", "give positive values");
  }
  if (output.empty()) output = std::filesystem::path(input).stem().string() + "_report";
  config.working_distance = working_distance;
  config.target_tolerance_mm = target_mm;
  const SampleSet samples = io::read_samples(input);
  // The session the node, solve and the bag replay use: the same X.
  const CalibrationSession session = samples_session(samples, input, config, session_args);
  const SessionSnapshot snapshot = session.snapshot();
  const CalibrationReport report = make_report(session, snapshot, report_options);
  out << io::human_summary(report.calibration, io::context_of(snapshot.samples));
  out << io::report_summary(report);
  const ReportFiles files = write_report(output, report, snapshot.samples, input);
  out << "  written to            " << output << "/ (calibration.yaml, report.yaml";
  if (files.problem.empty()) {
    out << ", report.html and its figures)\n  open it: xdg-open " << files.html << "\n";
    return kOk;
  }
  out << ")\n";
  err << "handeye report: " << files.problem << "\n";
  return kInternal;
}

int sim_command(const Args& args, std::ostream& out, std::ostream& err) {
  SimArgs a;
  po::options_description options(
      "sim: a simulated calibration session with known truth (a samples file; with --output x.bag a rosbag, whose "
      "further options `handeye sim --output x.bag --help` lists)");
  add_sim_options(options, a);
  double camera_moved_mm = 0.0;
  options.add_options()("camera-moved-mm", po::value(&camera_moved_mm),
                        "samples file: the camera moved on its mount by this much along its own x axis since the "
                        "calibration (same seed's target, X changed): views to try `handeye check` on");
  po::variables_map vm;
  po::store(po::command_line_parser(args).options(options).allow_unregistered().run(), vm);
  if (vm.count("output") && std::filesystem::path(vm["output"].as<std::string>()).extension() == ".bag") {
    return run_bag_tool("sim", args, out, err);
  }
  vm.clear();
  if (!parse("sim", "--output FILE [options]", options, args, vm, out)) return kOk;
  const Setup setup = a.checked_setup();
  const double deg = kRadiansPerDegree, mm = kMetresPerMillimetre;
  MeasurementNoise noise;
  noise.robot.rotation = std::pow(a.robot_rotation_deg * deg, 2) * Eigen::Matrix3d::Identity();
  noise.robot.translation = std::pow(a.robot_translation_mm * mm, 2) * Eigen::Matrix3d::Identity();
  noise.camera.rotation = std::pow(a.rotation_deg * deg, 2) * Eigen::Matrix3d::Identity();
  noise.camera.translation = std::pow(a.translation_mm * mm, 2) * Eigen::Matrix3d::Identity();
  Rng rng(a.seed);
  Eigen::Isometry3d X = typical_X(setup);
  X.translation() += X.linear() * Eigen::Vector3d(camera_moved_mm * mm, 0.0, 0.0);  // X' = X T(d): in the camera frame
  SimulatedSession session = simulate_session(rng, setup, X, a.samples, noise);
  if (a.omit_noise) session.samples.noise.reset();
  io::write_file_atomically(a.output, io::format_samples(session.samples));
  out << "wrote " << a.samples << " simulated " << a.setup_name << " samples to " << a.output << "\n";
  if (!a.truth.empty()) {
    io::write_file_atomically(a.truth, io::format_pose_file({session.X, Matrix6d::Zero()}, io::context_of(session.samples)));
    out << "wrote the true X to " << a.truth << "\n";
  }
  return kOk;
}

std::vector<double> parse_list(const std::string& text, const std::string& option) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      values.push_back(std::stod(item));
    } catch (const std::exception&) {
      throw HandEyeError(ErrorCode::MalformedFile, "`" + item + "` is not a number", option,
                         "give a comma-separated list, e.g. 1e-6,1e-5,1e-4");
    }
  }
  return values;
}

int validate_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  std::string protocols = "paper", lambdas = "1e-6,1e-5,1e-4,1e-3", out_dir;
  StudyOptions options;
  options.M = 10000;
  po::options_description description("validate: the Monte-Carlo study of the paper, section IV-A");
  description.add_options()("help,h", "show this help")(
      "protocol", po::value(&protocols),
      "paper | published | rotation-dominated | pose-stream | joint-eye-in-hand | joint-eye-to-hand | "
      "joint-estimated-noise | all, or a comma list")(
      "lambda", po::value(&lambdas), "noise levels, comma-separated (default 1e-6,1e-5,1e-4,1e-3)")(
      "k", po::value(&options.k), "motions per dataset (default 30)")(
      "M", po::value(&options.M), "datasets per noise level (default 10000)")(
      "seed", po::value(&options.seed), "random seed (default 1)")(
      "out", po::value(&out_dir), "directory for validation.csv, covariances.csv and the plots");
  po::variables_map vm;
  if (!parse("validate", "[--protocol P] [--lambda L,...] [--k 30] [--M 10000] [--out DIR]", description, args, vm, out)) {
    return kOk;
  }
  if (options.M < 10 || options.k < 3) {
    throw HandEyeError(ErrorCode::MalformedFile, "--M must be >= 10 and --k >= 3", "--M/--k", "raise them");
  }
  std::vector<Protocol> list;
  if (protocols == "all") {
    list = {Protocol::Paper, Protocol::Published, Protocol::RotationDominated, Protocol::PoseStream,
            Protocol::JointEyeInHand, Protocol::JointEyeToHand, Protocol::JointEstimatedNoise};
  } else {
    std::stringstream in(protocols);
    for (std::string name; std::getline(in, name, ',');) list.push_back(protocol_from_string(name));
  }
  std::ostringstream csv, covariances;
  csv << "protocol,lambda,k,M,eps_R,floor_R,eps_t,floor_t,nees_R,nees_t,nees_6,coverage95_R,coverage95_t,coverage95_6,"
         "per_pair_nees_R,per_pair_nees_t,not_converged,us_per_solve\n";
  covariances.precision(17);
  char line[512];
  // One row of validation.csv (the per-pair columns empty for the joint protocols) and
  // the mean predicted and Monte-Carlo covariances behind the plots.
  const auto write_rows = [&](Protocol protocol, double lambda, const StudyResult& r, const MonteCarloSummary& s,
                              bool per_pair) {
    csv << to_string(protocol) << "," << lambda << "," << options.k << "," << options.M << "," << s.rotation.epsilon << ","
        << s.rotation.floor << "," << s.translation.epsilon << "," << s.translation.floor << "," << s.rotation.nees_mean
        << "," << s.translation.nees_mean << "," << s.pose.nees_mean << "," << s.rotation.coverage_95 << ","
        << s.translation.coverage_95 << "," << s.pose.coverage_95 << ",";
    if (per_pair) csv << r.per_pair.rotation.nees_mean << "," << r.per_pair.translation.nees_mean;
    else csv << ",";
    csv << "," << r.not_converged << "," << r.seconds_per_solve * 1e6 << "\n";
    for (const auto& [kind, matrix] : {std::pair<const char*, const Matrix6d*>{"predicted", &s.mean_predicted_covariance},
                                       {"monte_carlo", &s.monte_carlo_covariance}}) {
      covariances << to_string(protocol) << "," << lambda << "," << kind;
      for (double v : to_row_major_6x6(*matrix)) covariances << "," << v;
      covariances << "\n";
    }
  };
  for (Protocol protocol : list) {
    const bool joint = is_joint(protocol);
    if (joint) {
      out << "protocol " << to_string(protocol) << ", " << options.k + 1 << " poses, M = " << options.M
          << ": the joint estimator's X and Y, the pairs estimator's X on the same data\n";
      out << "  lambda    X: NEES R    t     6dof  eps_t (floor)   Y: NEES R    t     6dof   pairs X: NEES 6dof"
             "  RMS t joint / pairs [mm]  nonconv  us/solve\n";
    } else {
      out << "protocol " << to_string(protocol) << ", k = " << options.k << ", M = " << options.M << "\n";
      out << "  lambda    eps_R (floor)    eps_t (floor)    NEES R    t     6dof   cov95 R    t     6dof  eq.35/56 NEES R  t"
             "   nonconv  us/solve\n";
    }
    for (double lambda : parse_list(lambdas, "--lambda")) {
      options.protocol = protocol;
      options.lambda = lambda;
      const StudyResult r = run_study(options);
      const MonteCarloSummary &s = r.ours, &y = r.pattern;
      if (joint) {
        std::snprintf(line, sizeof line,
                      "  %-8.0e     %.2f  %.2f  %.2f  %.3f (%.3f)      %.2f  %.2f  %.2f        %.2f          %.4f / %.4f"
                      "       %6d  %8.1f\n",
                      lambda, s.rotation.nees_mean, s.translation.nees_mean, s.pose.nees_mean, s.translation.epsilon,
                      s.translation.floor, y.rotation.nees_mean, y.translation.nees_mean, y.pose.nees_mean,
                      r.pairs.pose.nees_mean, millimetres(r.rms_translation), millimetres(r.pairs_rms_translation), r.not_converged,
                      r.seconds_per_solve * 1e6);
      } else {
        std::snprintf(line, sizeof line,
                      "  %-8.0e  %.3f (%.3f)    %.3f (%.3f)    %.2f  %.2f  %.2f   %.3f  %.3f  %.3f    %.2f  %.2f    %6d  %8.1f\n",
                      lambda, s.rotation.epsilon, s.rotation.floor, s.translation.epsilon, s.translation.floor,
                      s.rotation.nees_mean, s.translation.nees_mean, s.pose.nees_mean, s.rotation.coverage_95,
                      s.translation.coverage_95, s.pose.coverage_95, r.per_pair.rotation.nees_mean,
                      r.per_pair.translation.nees_mean, r.not_converged, r.seconds_per_solve * 1e6);
      }
      out << line << std::flush;
      write_rows(protocol, lambda, r, s, !joint);
    }
  }
  if (!out_dir.empty()) {
    io::write_file_atomically(out_dir + "/validation.csv", csv.str());
    io::write_file_atomically(out_dir + "/covariances.csv", covariances.str());
    out << "wrote " << out_dir << "/validation.csv and covariances.csv\n";
    const std::string problem = run_python_script(HANDEYE_PLOT_SCRIPT, {out_dir});
    if (!problem.empty()) {
      err << "handeye validate: the plots were not made (needs Debian's python3-matplotlib): " << problem << "\n";
      return kInternal;
    }
    out << "wrote the plots to " << out_dir << " (fig2_<protocol>.png, fig3_epsilon.png)\n";
  }
  return kOk;
}

/// A pose given on the command line: a pose file (YAML), or 7 numbers x,y,z,qx,qy,qz,qw.
io::PoseFile pose_argument(const std::string& value, const std::string& option) {
  const std::string extension = std::filesystem::path(value).extension().string();
  if (extension == ".yaml" || extension == ".yml" || std::filesystem::exists(value)) return io::read_pose_file(value);
  const std::vector<double> v = parse_list(value, option);
  if (v.size() != 7) {
    throw HandEyeError(ErrorCode::WrongLength, "expected 7 numbers x,y,z,qx,qy,qz,qw, got " + std::to_string(v.size()),
                       option, "give a pose file (.yaml) or x,y,z,qx,qy,qz,qw in m");
  }
  io::PoseFile file;
  const Eigen::Quaterniond q = checked_unit_quaternion(Eigen::Quaterniond(v[6], v[3], v[4], v[5]), option);
  file.value.pose = se3::make_pose(q.toRotationMatrix(), Eigen::Vector3d(v[0], v[1], v[2]));
  return file;
}

/// The 1 sigma options `--<prefix>-sigma-mm/-deg` as a covariance, if given.
std::optional<Matrix6d> stated_covariance(const po::variables_map& vm, const std::string& prefix) {
  const std::string mm = prefix + "-sigma-mm", deg = prefix + "-sigma-deg";
  if (!vm.count(mm) && !vm.count(deg)) return std::nullopt;
  if (!vm.count(mm) || !vm.count(deg)) {
    throw HandEyeError(ErrorCode::MissingKey, "give both --" + mm + " and --" + deg, "--" + prefix,
                       "state the translation and the rotation 1 sigma (0 for exact)");
  }
  const double sigma_t = metres(vm[mm].as<double>()), sigma_R = radians(vm[deg].as<double>());
  if (!(sigma_t >= 0.0) || !(sigma_R >= 0.0)) {
    throw HandEyeError(ErrorCode::InvalidNoise, "a 1 sigma must be a number >= 0", "--" + mm + "/--" + deg,
                       "give the standard deviation per axis, e.g. 0.3 (mm) and 0.05 (deg)");
  }
  return isotropic_covariance(sigma_t, sigma_R);
}

/// The covariance of a pose argument by choose_covariance's rule (the object_localizer's):
/// the file's own, else the stated sigmas, else the calibration's noise model; said aloud.
Matrix6d covariance_of(const io::PoseFile& pose, const po::variables_map& vm, const std::string& prefix,
                       const std::optional<PoseNoise>& model, const std::string& model_name, std::ostream& notes) {
  const std::optional<Matrix6d> stated = stated_covariance(vm, prefix);
  const ChosenCovariance chosen =
      choose_covariance(pose.has_covariance ? std::optional<Matrix6d>(pose.value.covariance) : std::nullopt, stated, model);
  switch (chosen.origin) {
    case CovarianceOrigin::None:
      throw HandEyeError(ErrorCode::MissingKey, "no covariance for the " + prefix + " pose", "--" + prefix,
                         "add `covariance:` to its file, or give --" + prefix + "-sigma-mm and --" + prefix + "-sigma-deg");
    case CovarianceOrigin::Input:
      if (stated) notes << "  (--" << prefix << "-sigma-* not used: the " << prefix << " file has its own covariance)\n";
      break;
    case CovarianceOrigin::CalibrationModel:
      notes << "  (" << prefix << " covariance: " << model_name << ")\n";
      break;
    case CovarianceOrigin::Stated:
      break;
  }
  return chosen.covariance;
}

int compose_command(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  std::string calibration_path, object_arg, effector_arg, output, base_frame, object_frame = "object";
  std::vector<std::string> point_args;
  po::options_description options(
      "compose: the object's pose in the robot base with its covariance (paper eq. 68): robot pose, X and detection");
  options.add_options()("help,h", "show this help")(
      "calibration,c", po::value(&calibration_path)->required(), "result file of `solve`, `bag` or the node")(
      "object", po::value(&object_arg)->required(),
      "T_camera_object: a pose file (YAML, covariance optional) or x,y,z,qx,qy,qz,qw")(
      "object-sigma-mm", po::value<double>(), "1 sigma per axis of the detection's translation")(
      "object-sigma-deg", po::value<double>(), "1 sigma per axis of the detection's rotation")(
      "effector", po::value(&effector_arg), "T_base_effector when the image was taken (eye_in_hand): file or 7 numbers")(
      "robot-sigma-mm", po::value<double>(), "1 sigma per axis of the robot's translation")(
      "robot-sigma-deg", po::value<double>(), "1 sigma per axis of the robot's rotation")(
      "point", po::value(&point_args), "x,y,z of a point on the object (e.g. a hole), in m; repeatable")(
      "base-frame", po::value(&base_frame), "name of the base frame (default: from the files, else base_link)")(
      "object-frame", po::value(&object_frame), "name of the object frame (default object)")(
      "output,o", po::value(&output), "write T_base_object with its covariance (pose file YAML)");
  po::variables_map vm;
  if (!parse("compose", "--calibration FILE --object POSE [--effector POSE] [--point x,y,z]... [--output FILE]",
             options, args, vm, out)) {
    return kOk;
  }
  const io::CalibrationFile calibration = io::read_result(calibration_path);
  if (!calibration.context.setup) {
    throw HandEyeError(ErrorCode::MissingKey, "the calibration does not say eye_in_hand or eye_to_hand",
                       calibration_path + ": setup", "add `setup: eye_in_hand` or `setup: eye_to_hand` to it");
  }
  const Setup setup = *calibration.context.setup;
  const auto noise_part = [&](bool robot) -> std::optional<PoseNoise> {
    if (!calibration.noise) return std::nullopt;
    return robot ? calibration.noise->robot : calibration.noise->camera;
  };
  ObjectPoseInput input;
  input.rig.setup = setup;
  input.X = calibration.T_parent_camera();
  std::ostringstream notes;
  const io::PoseFile object = pose_argument(object_arg, "--object");
  input.T_camera_object = {object.value.pose, covariance_of(object, vm, "object", noise_part(false),
                                                            "the calibration pattern's noise from " + calibration_path,
                                                            notes)};
  if (input.rig.eye_in_hand()) {
    if (effector_arg.empty()) {
      throw HandEyeError(ErrorCode::MissingKey, "eye_in_hand needs the robot pose when the image was taken",
                         "--effector", "give T_base_effector as a pose file or x,y,z,qx,qy,qz,qw");
    }
    const io::PoseFile effector = pose_argument(effector_arg, "--effector");
    input.T_base_effector = {effector.value.pose,
                             covariance_of(effector, vm, "robot", noise_part(true),
                                           "the robot noise from " + calibration_path, notes)};
    if (base_frame.empty()) base_frame = effector.parent;
  } else if (!effector_arg.empty()) {
    notes << "  (--effector ignored: eye_to_hand, X is T_base_camera)\n";
  }
  if (base_frame.empty()) {
    base_frame = !input.rig.eye_in_hand() && !calibration.context.parent.empty() ? calibration.context.parent : "base_link";
  }
  std::vector<Eigen::Vector3d> points;
  for (const std::string& p : point_args) {
    const std::vector<double> v = parse_list(p, "--point");
    if (v.size() != 3) {
      throw HandEyeError(ErrorCode::WrongLength, "a point is x,y,z", "--point " + p, "give three numbers in m");
    }
    points.emplace_back(v[0], v[1], v[2]);
  }
  const ObjectPose result = object_in_base(input);
  out << io::object_summary(result, base_frame, object_frame, points) << notes.str();
  if (!output.empty()) {
    io::ResultContext context;
    context.parent = base_frame;
    context.child = object_frame;
    io::write_file_atomically(output, io::format_pose_file(result.T_base_object, context));
    out << "  written to            " << output << "\n";
  }
  return kOk;
}

int noise_command(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  std::string input, calibration_path, source = "auto", output;
  RepeatedObservationOptions grouping;
  double group_mm = millimetres(grouping.group_translation), group_deg = degrees(grouping.group_rotation);
  po::options_description options("noise: measure the pose noise (paper eq. 64-67) and write a `noise` block");
  options.add_options()("help,h", "show this help")(
      "input,i", po::value(&input)->required(), "samples file (YAML)")(
      "calibration,c", po::value(&calibration_path),
      "X from this result file (residuals); default: solved from the input itself")(
      "source", po::value(&source),
      "repeated (the robot held poses while the camera saw the pattern several times), residuals, or auto "
      "(repeated when poses repeat, else residuals; the default)")(
      "robot-sigma-mm", po::value<double>(), "residuals: the robot's known 1 sigma per axis, subtracted")(
      "robot-sigma-deg", po::value<double>(), "residuals: the robot's known rotation 1 sigma per axis")(
      "group-mm", po::value(&group_mm), "repeated: effector poses this close are one held pose (default 1)")(
      "group-deg", po::value(&group_deg), "repeated: ... and this close in rotation (default 0.1)")(
      "output,o", po::value(&output), "noise file; default: <input stem>_noise.yaml in the current directory");
  po::variables_map vm;
  if (!parse("noise", "--input FILE [--calibration FILE] [--source auto|repeated|residuals] [--output FILE]", options,
             args, vm, out)) {
    return kOk;
  }
  if (source != "auto" && source != "repeated" && source != "residuals") {
    throw HandEyeError(ErrorCode::MalformedFile, "unknown source `" + source + "`", "--source",
                       "use auto, repeated or residuals");
  }
  if (output.empty()) output = std::filesystem::path(input).stem().string() + "_noise.yaml";
  grouping.group_translation = metres(group_mm);
  grouping.group_rotation = radians(group_deg);
  const SampleSet samples = io::read_samples(input);

  std::optional<NoiseEstimate> estimate;
  if (source != "residuals") {
    try {
      estimate = noise_from_repeated_observations(samples, grouping);
    } catch (const HandEyeError& e) {
      if (source == "repeated" || e.code() != ErrorCode::NoiseUnidentifiable) throw;
      out << "No pose was held for repeated observations; using the residuals against X.\n";
    }
  }
  if (!estimate) {
    std::optional<PoseNoise> robot;
    if (vm.count("robot-sigma-mm") || vm.count("robot-sigma-deg")) {
      robot = PoseNoise::from_pose_covariance(*stated_covariance(vm, "robot"));
    }
    if (!calibration_path.empty()) {
      const io::CalibrationFile calibration = io::read_result(calibration_path);
      if (calibration.context.setup && *calibration.context.setup != samples.rig.setup) {
        throw HandEyeError(ErrorCode::MalformedFile, "the calibration is for another setup", calibration_path + ": setup",
                           "give the result file of this setup (" + std::string(to_string(samples.rig.setup)) + ")");
      }
      estimate = noise_from_residuals(samples, calibration.T_parent_camera().pose, false, robot);
    } else {
      SampleSet unlabelled = samples;  // its own noise block is what is being measured
      unlabelled.noise.reset();
      for (PoseSample& s : unlabelled.samples) s.noise.reset();
      // Outliers would inflate the estimate: measure on the samples that agree.
      const Calibration fitted = solve_robust(unlabelled);
      for (const auto& r : fitted.rejected) out << "  left out samples[" << r.index << "]: " << io::rejected_text(r) << "\n";
      estimate = noise_from_residuals(without_rejected(samples, fitted), fitted.T_parent_camera, true, robot);
    }
  }
  const NoiseEstimate& e = *estimate;
  const auto per_axis = [](const Eigen::Matrix3d& covariance, double unit) {
    const Eigen::Vector3d s = covariance.diagonal().cwiseMax(0.0).cwiseSqrt() * unit;
    char text[96];
    std::snprintf(text, sizeof text, "%8.4f %8.4f %8.4f", s.x(), s.y(), s.z());
    return std::string(text);
  };
  out << "Noise from " << to_string(e.source) << ": " << e.samples_used << " samples"
      << (e.source == NoiseSource::RepeatedObservations ? " at " + std::to_string(e.groups) + " held poses" : "")
      << ", " << number_text(e.dof) << " dof (each variance +-" << number_text(100.0 * std::sqrt(2.0 / e.dof), 2)
      << "% at 1 sigma)\n";
  out << "  pattern 1 sigma [mm]   " << per_axis(e.noise.camera.translation, kMillimetresPerMetre) << "   (camera x, y, z)\n";
  out << "  pattern 1 sigma [deg]  " << per_axis(e.noise.camera.rotation, kDegreesPerRadian) << "\n";
  out << "  robot 1 sigma [mm]     " << per_axis(e.noise.robot.translation, kMillimetresPerMetre)
      << (e.robot_identified ? "" : "   (not identifiable from residuals: as given, else 0)") << "\n";
  out << "  robot 1 sigma [deg]    " << per_axis(e.noise.robot.rotation, kDegreesPerRadian) << "\n";
  for (const std::string& note : e.notes) out << "  note: " << note << "\n";
  io::write_file_atomically(output, io::format_noise_estimate(e));
  out << "  written to             " << output << "\n"
      << "  use it: handeye solve --input " << input << " --noise " << output
      << "   (node: noise_config:=" << output << ")\n";
  return kOk;
}

int suggest_command(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  // The node's defaults (config/calibration_defaults.yaml), overridden by the options.
  SessionConfig config;
  const SessionSettings defaults;
  std::string input, output, config_path;
  int count = 5, max_poses = defaults.max_plan_poses;
  double target_mm = config.target_tolerance_mm, reach_mm = millimetres(config.reach_translation),
         reach_deg = degrees(config.reach_rotation), working_distance = config.working_distance;
  unsigned seed = defaults.suggest.seed;
  po::options_description description(
      "suggest: which poses to add next, and how many more reach the target (ranked by the predicted covariance)");
  description.add_options()("help,h", "show this help")(
      "input,i", po::value(&input)->required(), "samples file of the session so far (YAML, >= 3 samples)")(
      "config,c", po::value(&config_path), "YAML with the node's settings (the defaults below come from there)")(
      "candidates", po::value(&config.candidate_poses_file),
      "candidate effector poses (YAML `candidates: [{translation, rotation}]`); default: sampled views of the pattern")(
      "count,n", po::value(&count), "how many ranked next poses to print (default 5)")(
      "criterion", po::value(&config.suggest_criterion), "object_sigma (default) or determinant")(
      "working-distance", po::value(&working_distance),
      ("m along the optical axis, for object_sigma (default " + number_text(working_distance) + ")").c_str())(
      "target-mm", po::value(&target_mm), ("plan until the object 1 sigma reaches this (default " + number_text(target_mm) + ")").c_str())(
      "max-poses", po::value(&max_poses), ("plan at most this many more poses (default " + std::to_string(max_poses) + ")").c_str())(
      "reach-mm", po::value(&reach_mm), ("sampled candidates: at most this far from the last pose (default " + number_text(reach_mm) + ")").c_str())(
      "reach-deg", po::value(&reach_deg), ("sampled candidates: at most this rotation from the last pose (default " + number_text(reach_deg) + ")").c_str())(
      "seed", po::value(&seed), ("sampled candidates: random seed, plus the number of samples (default " + std::to_string(seed) + ")").c_str())(
      "output,o", po::value(&output), "write the suggestions and the plan (YAML)");
  po::variables_map vm;
  if (!parse("suggest", "--input FILE [--candidates FILE] [--criterion object_sigma|determinant] [--target-mm 1]",
             description, args, vm, out)) {
    return kOk;
  }
  if (!config_path.empty()) {  // the file first, then the options given on the command line
    const SessionConfig command_line = config;
    read_session_config(config_path, config);
    if (vm.count("candidates")) config.candidate_poses_file = command_line.candidate_poses_file;
    if (vm.count("criterion")) config.suggest_criterion = command_line.suggest_criterion;
    if (!vm.count("working-distance")) working_distance = config.working_distance;
    if (!vm.count("target-mm")) target_mm = config.target_tolerance_mm;
    if (!vm.count("reach-mm")) reach_mm = millimetres(config.reach_translation);
    if (!vm.count("reach-deg")) reach_deg = degrees(config.reach_rotation);
  }
  if (!(working_distance > 0.0) || !(target_mm > 0.0) || count < 1 || max_poses < 0) {
    throw HandEyeError(ErrorCode::MalformedFile, "--working-distance and --target-mm must be > 0, --count >= 1",
                       "options", "give positive values");
  }
  config.working_distance = working_distance;
  config.target_tolerance_mm = target_mm;
  config.reach_translation = metres(reach_mm);
  config.reach_rotation = radians(reach_deg);
  const SampleSet all = io::read_samples(input);
  SessionSettings settings = session_settings(all, config);
  settings.max_plan_poses = max_poses;
  settings.suggest.seed = seed;
  CalibrationSession session(settings);
  session.replace(all.samples, "read " + input);
  SuggestRequest request;
  request.count = count;
  const SuggestResult result = session.suggest(session.snapshot(), request);
  const SampleSet& samples = result.samples;  // the consistent ones
  const Suggestion& suggestion = result.suggestion;
  const Plan& plan = result.plan;
  const SuggestOptions& options = result.options;
  const bool sampled = settings.candidate_poses.empty();

  char line[320];
  out << "Now: " << samples.samples.size() << " samples, object 1 sigma " << number_text(millimetres(suggestion.current_object_sigma))
      << " mm at " << number_text(options.working_distance) << " m (worst axis); criterion " << to_string(options.criterion)
      << ", " << suggestion.considered << " candidates" << (sampled ? " (sampled views)" : "")
      << (suggestion.refused ? ", " + std::to_string(suggestion.refused) + " refused" : "") << "\n";
  out << "Next poses, best first (T_base_effector):\n"
         "   #  translation [m]                     quaternion [x y z w]                      object 1 sigma after [mm]\n";
  for (int i = 0; i < count && i < static_cast<int>(suggestion.ranked.size()); ++i) {
    const ScoredPose& p = suggestion.ranked[i];
    Eigen::Quaterniond q(p.T_base_effector.linear());
    if (q.w() < 0) q.coeffs() *= -1.0;
    const Eigen::Vector3d t = p.T_base_effector.translation();
    std::snprintf(line, sizeof line, "  %2d  %+.4f %+.4f %+.4f   %+.5f %+.5f %+.5f %+.5f   %.3f\n", i + 1, t.x(), t.y(),
                  t.z(), q.x(), q.y(), q.z(), q.w(), millimetres(p.object_sigma));
    out << line;
  }
  if (plan.reached) {
    out << "To reach " << number_text(target_mm) << " mm: " << plan.poses.size() << " more pose(s)"
        << (plan.poses.empty() ? " (already there)" : ", predicted " + number_text(plan.poses.empty() ? 0.0 : millimetres(plan.poses.back().object_sigma)) + " mm after them")
        << poses_for_the_noise_text(plan) << "\n";
  } else {
    out << "To reach " << number_text(target_mm) << " mm: not within " << plan.poses.size() << " more pose(s) (predicted "
        << number_text(plan.poses.empty() ? millimetres(suggestion.current_object_sigma) : millimetres(plan.poses.back().object_sigma))
        << " mm after them); lower the noise, widen the reach, or relax the target\n";
  }
  out << "  (first-order prediction at the current estimate; the node's /suggest_pose gives the same live)\n";
  if (!output.empty()) {
    io::write_file_atomically(output, io::format_suggestions(suggestion, count, plan, metres(target_mm), options));
    out << "  written to " << output << "\n";
  }
  return kOk;
}

int check_command(const Args& args, std::ostream& out, std::ostream& err) {
  // New views from images need OpenCV: handeye_images detects them and runs the same check.
  for (const std::string& a : args) {
    if (a == "--images" || a.rfind("--images=", 0) == 0) return run_tool("handeye_images", "check", args, out, err);
  }
  std::string calibration, input, output;
  double alpha = 0.01;
  po::options_description options("check: is a saved calibration still right? New views against X, Y and their covariance");
  options.add_options()("help,h", "show this help")(
      "calibration,c", po::value(&calibration)->required(),
      "the calibration's result file (`handeye solve`, `handeye images`, the node's /save_calibration)")(
      "input,i", po::value(&input), "the new views: a samples file (as `handeye solve` reads)")(
      "images", "or a folder of new images, with --poses, --camera and --target as `handeye images` takes them")(
      "alpha", po::value(&alpha), "the false-alarm rate (default 0.01: one check in 100 says changed when nothing did)")(
      "output,o", po::value(&output), "write the check (YAML): verdict, p_value, changed, change, change_covariance");
  po::variables_map vm;
  if (!parse("check", "--calibration FILE (--input SAMPLES | --images DIR --poses DIR --camera FILE --target FILE) "
             "[--output FILE]  (exit 0: consistent, 3: changed)",
             options, args, vm, out)) {
    return kOk;
  }
  if (input.empty()) {
    throw HandEyeError(ErrorCode::MissingKey, "no new views", "--input",
                       "give --input samples.yaml, or --images DIR --poses DIR --camera FILE --target FILE");
  }
  io::Input data = io::read_input(input);
  const SampleSet* views = std::get_if<SampleSet>(&data);
  if (!views) {
    throw HandEyeError(ErrorCode::MalformedFile, "a check needs absolute views (a samples file), not motion pairs", input,
                       "record the new views as samples: robot pose and detected pattern pose each");
  }
  return run_check(calibration, *views, output, alpha, out);
}

const CommandTable& commands() {
  static const CommandTable table = {
      {"solve", {"solve AX = XB from a samples or motions file; print X with 1 sigma, write the result YAML",
                 solve_command}},
      {"sim", {"write a simulated session with known truth: a samples file, or a rosbag (--output x.bag)", sim_command}},
      {"bag", {"calibrate from a rosbag (/tf, /tf_static, detections) without a roscore",
               [](const Args& args, std::ostream& out, std::ostream& err) { return run_bag_tool("bag", args, out, err); }}},
      {"images", {"calibrate from a folder of images of a target (any kind of config/targets/) and one robot pose per image",
                  [](const Args& args, std::ostream& out, std::ostream& err) {
                    return run_tool("handeye_images", "images", args, out, err);
                  }}},
      {"target", {"draw a target file at 1:1 to print (PDF, SVG, PNG) with a scale bar; or scale it to the print",
                  [](const Args& args, std::ostream& out, std::ostream& err) {
                    return run_tool("handeye_target", "target", args, out, err);
                  }}},
      {"compose", {"the object's pose in the robot base with its covariance: robot pose + X + detection (eq. 68)",
                   compose_command}},
      {"noise", {"measure the pose noise from repeated observations or residuals (eq. 64-67); write a noise block",
                 noise_command}},
      {"suggest", {"which poses to add next and how many more reach a target sigma (predicted covariance)",
                   suggest_command}},
      {"check", {"is a saved calibration still right? a few new views against it: verdict, p-value, what moved (exit 3)",
                 check_command}},
      {"report", {"a calibration report: residuals, leave-one-out and split-half checks, rotation axes, advice (HTML)",
                  report_command}},
      {"validate", {"Monte-Carlo check of the covariance (paper section IV-A): epsilon, NEES, coverage, plots",
                    validate_command}},
  };
  return table;
}

}  // namespace

int run(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  return run_commands(commands(), argc, argv, out, err);
}

}  // namespace cli
}  // namespace handeye
