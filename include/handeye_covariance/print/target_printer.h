// A calibration target drawn at 1:1 for printing (no ROS): `handeye target`.
// PDF and SVG as vectors (cairo), PNG at a given dpi. Marker bits come from the
// libraries at run time (vision/tag_detector.h tag_bitmap: OpenCV's drawMarker,
// libapriltag's apriltag_to_image), one vector square per black cell; a ChArUco
// board's markers are where OpenCV's CharucoBoard puts them.
//
// The page frame: origin at the page's top-left corner, x right, y down, z into
// the paper (a camera looking straight down at the page with its x right sees
// this frame as its own). The target's frame on the page is the one its detector
// reports (core/target.h): a chessboard's at its first inner corner (the one
// whose outer diagonal square is white, top left), a ChArUco board's at the
// top-left corner of its top-left square, both x right, y down; markers: the
// layout's own frame, placed so that the first marker stands upright (its x
// right, its y up on the page).
//
// The margin holds a 100 mm scale bar, the print-at-100% line and the target's
// parameters (its file's contents, kind, sizes in mm).
#pragma once

#include <Eigen/Geometry>
#include <string>

#include <vector>

#include "handeye_covariance/core/target.h"
#include "handeye_covariance/vision/tag_detector.h"

namespace handeye {
namespace print {

/// One marker as printed: its bitmap centred at `centre` (page-aligned board
/// coordinates, m), turned by `angle` (rad, x towards y, y down), `cell` m a cell.
struct PrintedMarker {
  TagBitmap bitmap;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double angle = 0.0, cell = 0.0;
};

/// A target as printed, in page-aligned board coordinates (x right, y down, m;
/// origin anywhere): black squares, markers, the drawn extent and the pattern
/// frame in them.
struct PrintedBoard {
  std::vector<Eigen::AlignedBox2d> black_squares;
  std::vector<PrintedMarker> markers;
  Eigen::AlignedBox2d extent;
  Eigen::Isometry3d T_board_pattern = Eigen::Isometry3d::Identity();
};

/// A kind's drawing on paper: one file per kind in src/print/targets/, listed
/// once in src/print/target_printer.cpp under the core kind's name.
struct PrintKind {
  std::string name;  // TargetKind::name
  PrintedBoard (*draw)(const Target& target) = nullptr;  // a checked target (check_target)
};

const std::vector<PrintKind>& print_kinds();
/// Throws HandEyeError(InvalidLayout) when the kind has no drawing.
const PrintKind& print_kind(const std::string& name);

/// The layout's markers, each face up in the board's plane, into `board`
/// (its extent grown to hold them). Throws HandEyeError(InvalidLayout) for a
/// marker out of that plane.
void add_markers(const TagLayout& layout, const Eigen::Isometry3d& T_board_pattern, PrintedBoard& board);

/// A sheet of paper, m.
struct Page {
  std::string name = "A4";
  double width = 0.210, height = 0.297;
};

/// "A4", "Letter" (any case) or "WxH" in mm ("300x400", "300x400mm"); throws
/// HandEyeError(MalformedFile) naming the known forms.
Page parse_page(const std::string& text);

struct PrintOptions {
  Page page;
  double dpi = 600.0;            // PNG only
  double margin = 0.010;         // m, unprinted on every side (printers' edge)
  std::string target_text;       // the target file's contents, printed in the margin
  std::string target_source;     // its name, printed with it
};

/// Where the target lands on the page (page frame above), and what was written.
struct PrintedTarget {
  Page page;                     // as printed: width and height swapped when turned
  bool landscape = false;        // turned because the board fits only that way
  Eigen::Isometry3d T_page_pattern = Eigen::Isometry3d::Identity();
  Eigen::Vector2d board_min = Eigen::Vector2d::Zero(), board_max = Eigen::Vector2d::Zero();  // the drawn board, page m
  int png_width = 0, png_height = 0;  // px, PNG only
};

/// The target's place on the page without drawing it. Throws HandEyeError
/// (InvalidLayout) when the board does not fit the page inside its margins and
/// the footer, either way round, naming the largest square (marker) that fits;
/// and as check_target for a target its detector would refuse.
PrintedTarget place_target(const Target& target, const PrintOptions& options);

/// Draws the target at 1:1 into `output`: .pdf, .svg or .png by its extension
/// (HandEyeError(MalformedFile) for another, IoError when it cannot be written).
PrintedTarget print_target(const Target& target, const std::string& output, const PrintOptions& options);

/// The length a ruler measures on the print for --measured-square (the kind's
/// ruler_length): a chessboard's or ChArUco board's square, the first marker's black square.
double nominal_square(const Target& target);

/// The target file `text` (parse_target's format) with every length multiplied
/// by `factor` (its kind's length_keys; a layout's sizes and positions),
/// the rest as it was. Throws as parse_target does.
std::string scaled_target_text(const std::string& text, double factor, const std::string& source);

}  // namespace print
}  // namespace handeye
