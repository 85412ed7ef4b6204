// handeye_target: `handeye target` runs it (it links cairo, OpenCV and
// libapriltag; `handeye` links none of them). The target file drawn at 1:1 to
// print (print/target_printer.h), or, with --measured-square, the target file
// scaled to what the print measures.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "handeye_covariance/tools/cli_common.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/print/target_printer.h"

namespace handeye {
namespace cli {
namespace {

std::string mm(double metres) { return number_text(millimetres(metres), 4) + " mm"; }

bool is_yaml(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  return ext == ".yaml" || ext == ".yml";
}

/// --output x.yaml: the target file again, every length times measured / nominal.
int write_measured(const std::string& target_path, const std::string& text, const Target& target,
                   const std::string& measured_text, const std::string& output, std::ostream& out) {
  char* end = nullptr;
  const double measured = metres(std::strtod(measured_text.c_str(), &end));
  if (end == measured_text.c_str() || *end != '\0' || !(measured > 0.0) || !std::isfinite(measured)) {
    throw HandEyeError(ErrorCode::MalformedFile, "`" + measured_text + "` is not a length", "--measured-square",
                       "give the printed square (marker) as measured, in mm, e.g. 20.1");
  }
  const double nominal = print::nominal_square(target);
  const double factor = measured / nominal;
  // A printer off by more than a few percent, or a length in other units.
  if (factor < 0.8 || factor > 1.25) {
    throw HandEyeError(ErrorCode::MalformedFile,
                       "the measured " + mm(measured) + " is " + number_text(factor, 3) + " times the file's " +
                           mm(nominal),
                       "--measured-square",
                       "give the length in mm as a ruler reads it on the print; a print off by more than 20% was "
                       "not printed at 100%: print it again at \"actual size\"");
  }
  const std::string scaled = print::scaled_target_text(text, factor, target_path);
  io::write_file_atomically(output, "# " + target_path + " scaled by measured / nominal = " + mm(measured) + " / " +
                                        mm(nominal) + " = " + number_text(factor, 6) +
                                        " (handeye target --measured-square)\n" + scaled);
  out << "wrote " << output << ": every length of " << target_path << " times " << number_text(factor, 6) << " ("
      << mm(nominal) << " measured as " << mm(measured) << ")\n";
  return kOk;
}

int target_command(const Args& args, std::ostream& out, std::ostream&) {
  std::string target_path, output, page_name = "A4", measured;
  double dpi = 600.0;
  po::options_description options(
      "target: draw a target file at 1:1 to print (PDF, SVG or PNG), with a 100 mm scale bar and its parameters");
  options.add_options()("help,h", "show this help")(
      "target", po::value(&target_path)->required(),
      ("target file (" + target_file_types() + ", or a tag layout), as the detectors read it").c_str())(
      "output,o", po::value(&output)->required(),
      "board.pdf or board.svg (vectors: print these), board.png (at --dpi); with --measured-square, the scaled "
      "target file (.yaml)")(
      "page", po::value(&page_name), "A4 (default), Letter, or WxH in mm (e.g. 297x420); turned to landscape when "
                                     "the board fits only that way")(
      "dpi", po::value(&dpi), "PNG resolution in dots per inch (default 600)")(
      "measured-square", po::value(&measured),
      "mm, a square (a marker's black square) as a ruler measures it on the print: with --output x.yaml, writes "
      "the target file with every length scaled by measured / nominal");
  po::variables_map vm;
  if (!parse("target", "--target FILE --output board.pdf|board.svg|board.png [--page A4|Letter|WxH] [--dpi 600] | "
                       "--target FILE --measured-square MM --output measured.yaml",
             options, args, vm, out)) {
    return kOk;
  }
  const std::string text = io::read_file(target_path);
  const Target target = io::parse_target(text, target_path);
  if (is_yaml(output) != !measured.empty()) {
    throw HandEyeError(ErrorCode::MalformedFile,
                       measured.empty() ? "a .yaml output is the measured target file" : "--measured-square writes a target file",
                       "--output", "use --measured-square MM with --output measured.yaml; draw to .pdf, .svg or .png");
  }
  if (!measured.empty()) return write_measured(target_path, text, target, measured, output, out);

  print::PrintOptions print_options;
  print_options.page = print::parse_page(page_name);
  print_options.dpi = dpi;
  print_options.target_text = text;
  print_options.target_source = target_path;
  const print::PrintedTarget printed = print::print_target(target, output, print_options);
  const Eigen::Vector3d origin = printed.T_page_pattern.translation();
  out << "wrote " << output << ": " << target.describe() << " on " << printed.page.name
      << (printed.landscape ? " (landscape)" : "");
  if (printed.png_width > 0) out << ", " << printed.png_width << " x " << printed.png_height << " px at " << dpi << " dpi";
  out << "\n  the target's origin is " << mm(origin.x()) << " from the page's left edge and " << mm(origin.y())
      << " from its top edge\n"
      << "  print at 100% / \"actual size\" (not \"fit to page\"), then measure the 100 mm scale bar and a square\n";
  return kOk;
}

}  // namespace
}  // namespace cli
}  // namespace handeye

int main(int argc, char** argv) {
  using namespace handeye::cli;
  static const CommandTable table = {
      {"target", {"draw a target file at 1:1 to print, or scale it to the print's measured square", target_command}}};
  return run_commands(table, argc, argv, std::cout, std::cerr);
}
