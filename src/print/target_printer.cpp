#include "handeye_covariance/print/target_printer.h"

#include <cairo-pdf.h>
#include <cairo-svg.h>
#include <cairo.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>
#include <vector>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/target.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/vision/aruco.h"
#include "handeye_covariance/vision/tag_detector.h"
#include "handeye_covariance/vision/target.h"

namespace handeye {
namespace print {
namespace {

constexpr double kInch = 0.0254;       // m
constexpr double kPoint = kInch / 72;  // m, PDF's unit
constexpr double kScaleBar = 0.100;    // m
constexpr double kFontSize = 0.0025;   // m (7 pt)
constexpr double kLineHeight = 0.0034;
constexpr double kFooterGap = 0.005;   // white between the board and the footer
constexpr double kBarHeight = 0.007;   // the scale bar with its ticks and the gap below
constexpr std::size_t kMaxFileLines = 12;

std::string mm(double metres, int decimals = 1) { return millimetres_text(metres, decimals); }

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

PrintedBoard make_board(const Target& target) {
  check_target(target, "target");
  return print_kind(target.kind_name()).draw(target);
}

std::vector<std::string> file_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    const std::size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    lines.push_back(line.size() > 120 ? line.substr(0, 117) + "..." : line);
  }
  return lines;
}

/// The margin's text, top to bottom.
std::vector<std::string> footer_lines(const Target& target, const PrintOptions& options, const Page& page,
                                      bool landscape, const PrintedBoard& board) {
  const Eigen::Vector2d size = board.extent.sizes();
  std::vector<std::string> lines = {
      "Print at 100% / \"actual size\" (not \"fit to page\"). The bar above must measure 100 mm: measure it before use.",
      target.describe() + " (" + target.kind().sizes_text(target) + "); board " + mm(size.x()) + " x " + mm(size.y()) + ", page " +
          page.name + " " + mm(page.width, 0) + " x " + mm(page.height, 0) + (landscape ? ", landscape" : ""),
      target.kind().frame_text(target),
      "Measured a square (or marker) not at its size? handeye target --target FILE --measured-square MM --output "
      "measured.yaml",
  };
  std::vector<std::string> contents = file_lines(options.target_text);
  if (!contents.empty()) {
    lines.push_back("target file" + (options.target_source.empty() ? "" : " " + options.target_source) + ":");
    const std::size_t shown = std::min(contents.size(), kMaxFileLines);
    for (std::size_t i = 0; i < shown; ++i) lines.push_back("  " + contents[i]);
    if (contents.size() > shown) lines.push_back("  ... (" + std::to_string(contents.size() - shown) + " more lines)");
  }
  return lines;
}

double footer_height(std::size_t lines) { return kFooterGap + kBarHeight + lines * kLineHeight; }

struct Placement {
  PrintedTarget printed;
  PrintedBoard board;
  std::vector<std::string> footer;
  double margin = 0.0;
};

Placement place(const Target& target, const PrintOptions& options) {
  if (!(options.margin >= 0.0) || !(options.page.width > 2 * options.margin) || !(options.page.height > 2 * options.margin)) {
    throw HandEyeError(ErrorCode::MalformedFile, "the page has no room inside its margins", "--page",
                       "use a larger page (A4, Letter or WxH in mm)");
  }
  Placement out;
  out.margin = options.margin;
  out.board = make_board(target);
  const Eigen::Vector2d size = out.board.extent.sizes();
  // The footer's line count does not depend on the orientation.
  const std::size_t lines = footer_lines(target, options, options.page, false, out.board).size();
  double largest_scale = 0.0;
  for (bool landscape : {false, true}) {
    Page page = options.page;
    if (landscape) std::swap(page.width, page.height);
    const double width = page.width - 2 * options.margin;
    const double height = page.height - 2 * options.margin - footer_height(lines);
    if (width < kScaleBar || height <= 0.0) continue;
    largest_scale = std::max(largest_scale, std::min(width / size.x(), height / size.y()));
    if (size.x() > width || size.y() > height) continue;
    PrintedTarget& p = out.printed;
    p.page = page;
    p.landscape = landscape;
    // Centred in the space above the footer.
    const Eigen::Vector2d min = Eigen::Vector2d(options.margin, options.margin) +
                                0.5 * (Eigen::Vector2d(width, height) - size);
    p.board_min = min;
    p.board_max = min + size;
    Eigen::Isometry3d T_page_board = Eigen::Isometry3d::Identity();
    T_page_board.translation().head<2>() = min - out.board.extent.min();
    p.T_page_pattern = T_page_board * out.board.T_board_pattern;
    out.footer = footer_lines(target, options, page, landscape, out.board);
    return out;
  }
  const std::string what = target.kind().ruler_name();
  const std::string where = options.page.name + " (" + mm(options.page.width, 0) + " x " +
                            mm(options.page.height, 0) + ", " + mm(options.margin, 0) + " margins, " +
                            mm(footer_height(lines), 0) + " for the scale bar and text)";
  if (largest_scale <= 0.0) {
    throw HandEyeError(ErrorCode::InvalidLayout, "the page " + where + " has no room for the 100 mm scale bar", "--page",
                       "use a page at least " + mm(kScaleBar + 2 * options.margin, 0) + " wide");
  }
  const double largest = largest_scale * nominal_square(target);
  throw HandEyeError(ErrorCode::InvalidLayout,
                     "the " + target.describe() + " is " + mm(size.x()) + " x " + mm(size.y()) +
                         " and does not fit on " + where + " either way round; the largest " + what +
                         " that fits is " + mm(std::floor(largest * 1e4) / 1e4),
                     "--page",
                     "make the " + what + " at most " + mm(std::floor(largest * 1e4) / 1e4) +
                         " in the target file (and the other lengths in proportion), or print on a larger page "
                         "(--page WxH in mm)");
}

/// Draws in page metres: the caller has scaled the context to its surface.
/// `paper`: paint the page white first (not on a coverage-only surface, where
/// any paint is ink).
void draw(cairo_t* cr, const Placement& placement, bool paper) {
  const PrintedTarget& p = placement.printed;
  const PrintedBoard& board = placement.board;
  if (paper) {
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
  }
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_save(cr);
  const Eigen::Vector2d offset = p.board_min - board.extent.min();
  cairo_translate(cr, offset.x(), offset.y());
  // One fill per path: no seams between black cells or squares that touch.
  for (const Eigen::AlignedBox2d& square : board.black_squares) {
    cairo_rectangle(cr, square.min().x(), square.min().y(), square.sizes().x(), square.sizes().y());
  }
  cairo_fill(cr);
  for (const PrintedMarker& marker : board.markers) {
    cairo_save(cr);
    cairo_translate(cr, marker.centre.x(), marker.centre.y());
    cairo_rotate(cr, marker.angle);
    const cv::Mat& bits = marker.bitmap.pixels;
    const double x0 = -0.5 * bits.cols * marker.cell, y0 = -0.5 * bits.rows * marker.cell;
    for (int v = 0; v < bits.rows; ++v) {
      for (int u = 0; u < bits.cols; ++u) {
        if (bits.at<uint8_t>(v, u) < 128) {
          cairo_rectangle(cr, x0 + u * marker.cell, y0 + v * marker.cell, marker.cell, marker.cell);
        }
      }
    }
    cairo_fill(cr);
    cairo_restore(cr);
  }
  cairo_restore(cr);

  // The footer, below the board's space: the scale bar, then the text.
  const double left = placement.margin;
  const double text_width = p.page.width - 2 * placement.margin;
  const double bar_top = p.page.height - placement.margin - footer_height(placement.footer.size()) + kFooterGap;
  cairo_rectangle(cr, left, bar_top + 0.0030, kScaleBar, 0.0008);
  // Ticks every 10 mm; the end ones inside the bar, so that it is 100 mm end to end.
  for (int k = 0; k <= 10; ++k) {
    const double tick = (k % 5 == 0) ? 0.003 : 0.0018;
    const double x = std::clamp(left + k * 0.010 - 0.0001, left, left + kScaleBar - 0.0002);
    cairo_rectangle(cr, x, bar_top + 0.0038 - tick, 0.0002, tick);
  }
  cairo_fill(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, kFontSize);
  cairo_move_to(cr, left + kScaleBar + 0.002, bar_top + 0.0038);
  cairo_show_text(cr, "100 mm");
  // Shrink the text to the printable width when a line is longer.
  double widest = 0.0;
  for (const std::string& line : placement.footer) {
    cairo_text_extents_t extents;
    cairo_text_extents(cr, line.c_str(), &extents);
    widest = std::max(widest, extents.x_advance);
  }
  const double font = widest > text_width ? kFontSize * text_width / widest : kFontSize;
  cairo_set_font_size(cr, font);
  double y = bar_top + kBarHeight;
  for (const std::string& line : placement.footer) {
    cairo_move_to(cr, left, y + 0.75 * kFontSize);
    cairo_show_text(cr, line.c_str());
    y += kLineHeight;
  }
}

using Surface = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;
using Context = std::unique_ptr<cairo_t, decltype(&cairo_destroy)>;

void check_status(cairo_status_t status, const std::string& path) {
  if (status != CAIRO_STATUS_SUCCESS) {
    throw HandEyeError(ErrorCode::IoError, std::string("cannot write the drawing: ") + cairo_status_to_string(status),
                       path, "check that the folder exists and is writable, and that there is free space");
  }
}

}  // namespace

// Each kind's drawing (src/print/targets/; the markers' below), listed once.
PrintKind chessboard_print();
PrintKind charuco_print();

namespace {

/// The first marker upright: its x right, its y up, its z out of the paper.
PrintedBoard markers_board(const Target& target) {
  const TagLayout& layout = target.as<TagLayout>();
  PrintedBoard board;
  const Eigen::Matrix3d R_board_tag = Eigen::Vector3d(1, -1, -1).asDiagonal();
  board.T_board_pattern.linear() = R_board_tag * layout.tags.front().T_pattern_tag.linear().transpose();
  const Eigen::Vector3d first = board.T_board_pattern * layout.tags.front().T_pattern_tag.translation();
  board.T_board_pattern.translation().z() = -first.z();  // the tags' plane is the paper
  add_markers(layout, board.T_board_pattern, board);
  return board;
}

}  // namespace

const std::vector<PrintKind>& print_kinds() {
  static const std::vector<PrintKind> kinds = {chessboard_print(), charuco_print(), {"aruco", markers_board},
                                               {"apriltag", markers_board}};
  return kinds;
}

const PrintKind& print_kind(const std::string& name) {
  return layer_entry(print_kinds(), name, "printed drawing", "printer", "PrintKind", "src/print/target_printer.cpp");
}

void add_markers(const TagLayout& layout, const Eigen::Isometry3d& T_board_pattern, PrintedBoard& board) {
  for (const TagPlacement& tag : layout.tags) {
    const Eigen::Isometry3d T_board_tag = T_board_pattern * tag.T_pattern_tag;
    // Printed face up: the tag's z (out of its face) points out of the paper, -z here.
    if (std::abs(T_board_tag.translation().z()) > 1e-6 || T_board_tag.linear()(2, 2) > -1.0 + 1e-6) {
      throw HandEyeError(ErrorCode::InvalidLayout,
                         "tag " + std::to_string(tag.id) + " is not in the plane of the first tag, face up",
                         "target layout", "a layout printed on one page has every tag in one plane, facing the same way");
    }
    PrintedMarker marker;
    marker.bitmap = tag_bitmap(layout.family, tag.id);
    marker.cell = tag.size / marker.bitmap.width_at_border;
    marker.centre = T_board_tag.translation().head<2>();
    marker.angle = std::atan2(T_board_tag.linear()(1, 0), T_board_tag.linear()(0, 0));
    const double half = 0.5 * marker.cell * marker.bitmap.pixels.cols;
    const Eigen::Rotation2Dd turn(marker.angle);
    for (const Eigen::Vector2d& corner : {Eigen::Vector2d(-half, -half), Eigen::Vector2d(half, -half),
                                         Eigen::Vector2d(half, half), Eigen::Vector2d(-half, half)}) {
      board.extent.extend(marker.centre + turn * corner);
    }
    board.markers.push_back(std::move(marker));
  }
}

Page parse_page(const std::string& text) {
  const std::string name = lower(text);
  if (name == "a4") return Page{"A4", 0.210, 0.297};
  if (name == "letter") return Page{"Letter", 0.2159, 0.2794};
  double w = 0.0, h = 0.0;
  char rest[8] = {0};
  const int n = std::sscanf(name.c_str(), "%lfx%lf%7s", &w, &h, rest);
  if ((n == 2 || (n == 3 && std::string(rest) == "mm")) && w > 0.0 && h > 0.0 && w < 10000.0 && h < 10000.0) {
    char label[64];
    std::snprintf(label, sizeof label, "%gx%g mm", w, h);
    return Page{label, metres(w), metres(h)};
  }
  throw HandEyeError(ErrorCode::MalformedFile, "unknown page `" + text + "`", "--page",
                     "use A4, Letter, or the paper's width x height in mm, e.g. 297x420");
}

double nominal_square(const Target& target) { return target.kind().ruler_length(target); }

PrintedTarget place_target(const Target& target, const PrintOptions& options) { return place(target, options).printed; }

PrintedTarget print_target(const Target& target, const std::string& output, const PrintOptions& options) {
  const std::string extension = lower(std::filesystem::path(output).extension().string());
  if (extension != ".pdf" && extension != ".svg" && extension != ".png") {
    throw HandEyeError(ErrorCode::MalformedFile, "unknown drawing format `" + extension + "`", output,
                       "name the output .pdf or .svg (vectors, to print) or .png (at --dpi)");
  }
  if (extension == ".png" && !(options.dpi >= 10.0 && options.dpi <= 4800.0)) {
    throw HandEyeError(ErrorCode::MalformedFile, "--dpi " + number_text(options.dpi) + " is not a printer's resolution",
                       "--dpi", "give 10 to 4800 dots per inch, e.g. 600");
  }
  Placement placement = place(target, options);
  PrintedTarget& p = placement.printed;
  // Written beside the output, then renamed: no half-written drawing under its name.
  const std::string partial = output + ".partial" + extension;
  if (extension == ".pdf") {
    Surface surface(cairo_pdf_surface_create(partial.c_str(), p.page.width / kPoint, p.page.height / kPoint),
                    cairo_surface_destroy);
    check_status(cairo_surface_status(surface.get()), output);
    cairo_pdf_surface_set_metadata(surface.get(), CAIRO_PDF_METADATA_TITLE, target.describe().c_str());
    Context cr(cairo_create(surface.get()), cairo_destroy);
    cairo_scale(cr.get(), 1.0 / kPoint, 1.0 / kPoint);
    draw(cr.get(), placement, true);
    cairo_show_page(cr.get());
    cr.reset();
    cairo_surface_finish(surface.get());
    check_status(cairo_surface_status(surface.get()), output);
  } else if (extension == ".svg") {
    // Width and height in mm: the SVG's user unit is the millimetre.
    Surface surface(cairo_svg_surface_create(partial.c_str(), millimetres(p.page.width), millimetres(p.page.height)),
                    cairo_surface_destroy);
    check_status(cairo_surface_status(surface.get()), output);
    cairo_svg_surface_set_document_unit(surface.get(), CAIRO_SVG_UNIT_MM);
    Context cr(cairo_create(surface.get()), cairo_destroy);
    cairo_scale(cr.get(), kMillimetresPerMetre, kMillimetresPerMetre);  // SVG user units in mm, the drawing in m
    draw(cr.get(), placement, true);
    cr.reset();
    cairo_surface_finish(surface.get());
    check_status(cairo_surface_status(surface.get()), output);
  } else {
    const double px_per_m = options.dpi / kInch;
    p.png_width = static_cast<int>(std::lround(p.page.width * px_per_m));
    p.png_height = static_cast<int>(std::lround(p.page.height * px_per_m));
    const int largest_side = 32767;  // cairo's image surfaces
    if (std::max(p.png_width, p.png_height) > largest_side) {
      const double largest_dpi = std::floor(largest_side / std::max(p.page.width, p.page.height) * kInch);
      throw HandEyeError(ErrorCode::MalformedFile,
                         "a " + p.page.name + " page at " + number_text(options.dpi, 6) + " dpi is more than " +
                             std::to_string(largest_side) + " px a side",
                         "--dpi", "use at most " + number_text(largest_dpi, 6) + " dpi, or the PDF or SVG (vectors)");
    }
    // Coverage only (8 bits a pixel, not 32): an A4 page at 600 dpi is 35 MB.
    Surface surface(cairo_image_surface_create(CAIRO_FORMAT_A8, p.png_width, p.png_height), cairo_surface_destroy);
    check_status(cairo_surface_status(surface.get()), output);
    Context cr(cairo_create(surface.get()), cairo_destroy);
    cairo_scale(cr.get(), px_per_m, px_per_m);
    draw(cr.get(), placement, false);
    cr.reset();
    cairo_surface_flush(surface.get());
    const cv::Mat ink(p.png_height, p.png_width, CV_8UC1, cairo_image_surface_get_data(surface.get()),
                      static_cast<std::size_t>(cairo_image_surface_get_stride(surface.get())));
    cv::Mat gray = 255 - ink;
    bool written = false;
    try {
      written = cv::imwrite(partial, gray);
    } catch (const cv::Exception&) {
      written = false;
    }
    if (!written) check_status(CAIRO_STATUS_WRITE_ERROR, output);
  }
  std::error_code ec;
  std::filesystem::rename(partial, output, ec);
  if (ec) {
    std::filesystem::remove(partial, ec);
    check_status(CAIRO_STATUS_WRITE_ERROR, output);
  }
  return p;
}

std::string scaled_target_text(const std::string& text, double factor, const std::string& source) {
  io::parse_target(text, source);  // the same refusals as the detectors' reader
  YAML::Node root = YAML::Load(text);
  const auto scale = [&](YAML::Node node, const char* key) {
    if (!node[key]) return;
    char value[40];
    std::snprintf(value, sizeof value, "%.9g", node[key].as<double>() * factor);
    node[key] = std::string(value);
  };
  if (root["tags"] && !root["type"]) {
    for (YAML::Node tag : root["tags"]) {
      for (const char* key : {"size", "x", "y", "z"}) scale(tag, key);
    }
  } else {
    for (const std::string& key : find_target_kind_of_type(root["type"].as<std::string>())->length_keys()) {
      scale(root, key.c_str());
    }
  }
  YAML::Emitter out;
  out << root;
  return std::string(out.c_str()) + "\n";
}

}  // namespace print
}  // namespace handeye
