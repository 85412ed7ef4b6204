// handeye target's drawings (print/target_printer.h): each kind printed to PDF,
// rasterised at 600 dpi by pdftoppm and found by the package's own detector,
// as a pinhole camera looking straight down at the page would see it.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <tinyxml2.h>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/print/target_printer.h"
#include "handeye_covariance/vision/aruco.h"
#include "handeye_covariance/vision/target.h"
#include "scratch_directory.h"

namespace handeye {
namespace {

constexpr double kDpi = 600.0;
constexpr double kPxPerM = kDpi / 0.0254;
constexpr double kCameraDistance = 0.15;  // m, any: the raster is the same

std::string scratch(const std::string& name) { return test::scratch_directory() + "/" + name; }

int run(const std::string& command) { return std::system((command + " > /dev/null 2>&1").c_str()); }

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The printed PDF seen from straight above: the page rasterised at 600 dpi
/// (cropped to the board and 5 mm around), a camera with f = d * 600 / 0.0254
/// px whose axes are the page's (x right, y down, z into the paper).
struct Seen {
  print::PrintedTarget printed;
  CameraModel camera;
  Eigen::Isometry3d T_camera_page = Eigen::Isometry3d::Identity();
  PointCorrespondences points;
  PatternPose pose;
  cv::Mat gray;  // the raster
};

Seen print_and_detect(const Target& target, const std::string& name, const std::string& page = "A4") {
  Seen seen;
  print::PrintOptions options;
  options.page = print::parse_page(page);
  const std::string pdf = scratch(name + ".pdf");
  seen.printed = print::print_target(target, pdf, options);
  const Eigen::Vector2d from = (seen.printed.board_min.array() - 0.005).max(0.0).matrix() * kPxPerM;
  const Eigen::Vector2d to = (seen.printed.board_max.array() + 0.005).matrix() * kPxPerM;
  const int x0 = static_cast<int>(std::floor(from.x())), y0 = static_cast<int>(std::floor(from.y()));
  const int w = static_cast<int>(std::ceil(to.x())) - x0, h = static_cast<int>(std::ceil(to.y())) - y0;
  const std::string prefix = scratch(name);
  const std::string command = "pdftoppm -r 600 -png -gray -singlefile -x " + std::to_string(x0) + " -y " +
                              std::to_string(y0) + " -W " + std::to_string(w) + " -H " + std::to_string(h) + " " +
                              pdf + " " + prefix;
  EXPECT_EQ(run(command), 0) << command;
  const cv::Mat gray = cv::imread(prefix + ".png", cv::IMREAD_GRAYSCALE);
  seen.gray = gray;
  EXPECT_EQ(gray.cols, w);
  EXPECT_EQ(gray.rows, h);
  // Principal point off the crop's centre: anywhere on the page will do.
  const double cx = 0.31 * w, cy = 0.64 * h, f = kCameraDistance * kPxPerM;
  seen.camera.K << f, 0, cx, 0, f, cy, 0, 0, 1;
  seen.camera.width = w;
  seen.camera.height = h;
  // Pixel (u, v) of pdftoppm's crop is centred on page point ((x0 + u + 0.5), (y0 + v + 0.5)) / kPxPerM.
  seen.T_camera_page.translation() = -Eigen::Vector3d((x0 + cx + 0.5) / kPxPerM, (y0 + cy + 0.5) / kPxPerM, -kCameraDistance);
  const TargetDetector detector(target);
  const TargetObservation observation = detector.detect(gray);
  if (!observation.points) {
    ADD_FAILURE() << name << ": not detected: " << observation.refusal;
    return seen;
  }
  seen.points = *observation.points;
  PixelNoise noise;
  const PatternPoseResult result = estimate_pose(seen.camera, seen.points, noise);
  if (!result.pose) {
    ADD_FAILURE() << name << ": no pose: " << result.refusal;
    return seen;
  }
  seen.pose = *result.pose;
  return seen;
}

/// The printed scale from the detected corners: image distance (px, at 600 dpi)
/// over target distance, for every pair of points at least half the board apart.
double printed_scale(const Seen& seen) {
  const std::vector<Eigen::Vector3d>& object = seen.points.object;
  double longest = 0.0;
  for (std::size_t i = 0; i < object.size(); ++i)
    for (std::size_t j = i + 1; j < object.size(); ++j) longest = std::max(longest, (object[i] - object[j]).norm());
  double sum_image = 0.0, sum_object = 0.0;
  for (std::size_t i = 0; i < object.size(); ++i) {
    for (std::size_t j = i + 1; j < object.size(); ++j) {
      const double d = (object[i] - object[j]).norm();
      if (d < 0.5 * longest) continue;
      sum_image += (seen.points.image[i] - seen.points.image[j]).norm() / kPxPerM;
      sum_object += d;
    }
  }
  return sum_image / sum_object;
}

double angle_between(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

const Eigen::Matrix3d kFaceUp = Eigen::Vector3d(1, -1, -1).asDiagonal();  // a marker's frame seen from above

/// The frame on the page: the detector's pose is the printed one, the printed
/// one is `R_page` at `origin_page`; the corners are 1:1 to 0.05%.
void expect_frame(const Seen& seen, const Eigen::Matrix3d& R_page, const Eigen::Vector2d& origin_page,
                  const std::string& name) {
  const Eigen::Isometry3d& printed = seen.printed.T_page_pattern;
  EXPECT_LT(angle_between(printed.linear(), R_page), 1e-12) << name;
  EXPECT_LT((printed.translation() - Eigen::Vector3d(origin_page.x(), origin_page.y(), 0)).norm(), 1e-12) << name;
  const Eigen::Isometry3d expected = seen.T_camera_page * printed;
  const Eigen::Isometry3d& detected = seen.pose.T_camera_pattern;
  const double angle = angle_between(detected.linear(), expected.linear());
  const double offset = (detected.translation() - expected.translation()).norm();
  const double scale_error = printed_scale(seen) - 1.0;
  std::printf("[ figures  ] %-16s %3zu points, frame rotation %.3f mrad, origin off by %.3f mm (in plane "
              "%.4f mm), square size %+.4f%%\n",
              name.c_str(), seen.points.object.size(), angle * 1e3, offset * 1e3,
              (detected.translation() - expected.translation()).head<2>().norm() * 1e3, scale_error * 100);
  EXPECT_LT(angle, 2e-3) << name;                 // rad
  EXPECT_LT(offset, 1e-4) << name;                // m, depth included
  EXPECT_LT((detected.translation() - expected.translation()).head<2>().norm(), 2e-5) << name;
  EXPECT_LT(std::abs(scale_error), 5e-4) << name;  // 0.05%
}

TEST(TargetPrinter, ChessboardFrameIsOpenCVsAtTheFirstInnerCorner) {
  const Target target = make_target(ChessboardTarget{9, 6, 0.012});
  const Seen seen = print_and_detect(target, "chessboard_9x6");
  ASSERT_EQ(seen.points.object.size(), 54u);
  // One square (white) from the board's top-left corner to the first inner corner; x right, y down.
  const Eigen::Vector2d origin = seen.printed.board_min + Eigen::Vector2d(0.012, 0.012);
  expect_frame(seen, Eigen::Matrix3d::Identity(), origin, "chessboard 9x6");
}

TEST(TargetPrinter, EvenChessboardIsOneOfItsTwoHalfTurnCandidates) {
  const Target target = make_target(ChessboardTarget{8, 6, 0.012});
  Seen seen = print_and_detect(target, "chessboard_8x6");
  ASSERT_EQ(seen.points.object.size(), 48u);
  // Looks the same turned by 180 degrees: the detector may report either candidate.
  const Eigen::Isometry3d expected = seen.T_camera_page * seen.printed.T_page_pattern;
  if (angle_between(seen.pose.T_camera_pattern.linear(), expected.linear()) > 1.0) {
    seen.pose.T_camera_pattern = seen.pose.T_camera_pattern * half_turn(target);
  }
  expect_frame(seen, Eigen::Matrix3d::Identity(), seen.printed.board_min + Eigen::Vector2d(0.012, 0.012),
               "chessboard 8x6");
}

TEST(TargetPrinter, CharucoFrameIsOpenCVsAtTheBoardsCorner) {
  const Target target = make_target(CharucoTarget{5, 7, 0.020, 0.015, "DICT_5X5_100"});
  const Seen seen = print_and_detect(target, "charuco_5x7");
  EXPECT_EQ(seen.points.object.size(), 4u * 6u);  // every inner corner
  // Every marker, by the dictionary's own detector.
  std::vector<int> found;
  for (const TagCorners& marker : ArucoDetector("DICT_5X5_100").detect(seen.gray)) found.push_back(marker.id);
  std::vector<int> ids = charuco_marker_layout(target.as<CharucoTarget>()).ids();
  std::sort(ids.begin(), ids.end());
  std::sort(found.begin(), found.end());
  EXPECT_EQ(found, ids);
  EXPECT_EQ(ids.size(), 17u);  // the 5 x 7 board's white squares
  expect_frame(seen, Eigen::Matrix3d::Identity(), seen.printed.board_min, "charuco 5x7");
}

TEST(TargetPrinter, CharucoHasOpenCVsCellsBlack) {
  // OpenCV's own drawing and ours at the same scale: the same cells black (a
  // difference wider than the anti-aliased edge would be a wrong square, marker or id).
  const CharucoTarget board{5, 7, 0.020, 0.015, "DICT_5X5_100"};
  const Target target = make_target(board);
  print::PrintOptions options;
  options.dpi = 300;
  const std::string png = scratch("charuco.png");
  const print::PrintedTarget printed = print::print_target(target, png, options);
  const cv::Mat ours_page = cv::imread(png, cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(ours_page.empty());
  const int texels = 120;  // per square
  const cv::Mat opencv = charuco_image(board, texels);
  // Our page resampled onto OpenCV's texels: texel (u, v) is centred on board point ((u, v) + 0.5) / texels squares.
  const double px_per_m = 300 / 0.0254, m_per_texel = board.square / texels;
  cv::Matx23d texel_to_page(m_per_texel * px_per_m, 0, (printed.board_min.x() + 0.5 * m_per_texel) * px_per_m - 0.5,
                            0, m_per_texel * px_per_m, (printed.board_min.y() + 0.5 * m_per_texel) * px_per_m - 0.5);
  cv::Mat ours;
  cv::warpAffine(ours_page, ours, texel_to_page, opencv.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP);
  cv::Mat differ = (ours < 128) != (opencv < 128);
  const double edge_fraction = cv::countNonZero(differ) / static_cast<double>(differ.total());
  cv::erode(differ, differ, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(5, 5)));
  std::printf("[ figures  ] charuco vs CharucoBoard::draw: %.3f%% of texels differ (edges), %d beyond the edges\n",
              edge_fraction * 100, cv::countNonZero(differ));
  EXPECT_EQ(cv::countNonZero(differ), 0);
  EXPECT_LT(edge_fraction, 0.02);
  EXPECT_GT(cv::countNonZero(opencv < 128), static_cast<int>(opencv.total() / 3));  // a board, not a blank
}

TEST(TargetPrinter, OneArucoMarkerFrameIsItsCentreFaceUp) {
  const Target target = make_target(single_tag_layout(7, 0.050, "DICT_4X4_50"));
  const Seen seen = print_and_detect(target, "aruco_7");
  EXPECT_EQ(seen.pose.ids, std::vector<int>{7});
  expect_frame(seen, kFaceUp, 0.5 * (seen.printed.board_min + seen.printed.board_max), "aruco id 7");
}

TEST(TargetPrinter, ArucoGridFrameIsOpenCVsAtTheFirstMarkersCorner) {
  const Target target = make_target(aruco_grid_layout("DICT_4X4_50", 4, 3, 0.030, 0.008));
  const Seen seen = print_and_detect(target, "aruco_grid");
  EXPECT_EQ(seen.pose.ids, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}));
  // The marker's bitmap has one white cell around its black border (4x4 + 2 cells).
  const double cell = 0.030 / 6;
  expect_frame(seen, Eigen::Matrix3d::Identity(), seen.printed.board_min + Eigen::Vector2d(cell, cell), "aruco grid");
}

TEST(TargetPrinter, OneAprilTagFrameIsItsCentreFaceUp) {
  const Target target = make_target(single_tag_layout(0, 0.060, "tag36h11"));
  const Seen seen = print_and_detect(target, "apriltag_0");
  EXPECT_EQ(seen.pose.ids, std::vector<int>{0});
  expect_frame(seen, kFaceUp, 0.5 * (seen.printed.board_min + seen.printed.board_max), "tag36h11 id 0");
}

TEST(TargetPrinter, TagBoardFromConfigFrameIsTheLayouts) {
  const Target target = io::read_target(std::string(HANDEYE_SOURCE_DIR) + "/config/tag_board_2x2.yaml");
  const Seen seen = print_and_detect(target, "tag_board_2x2", "180x230");
  EXPECT_EQ(seen.printed.page.name, "180x230 mm");
  EXPECT_EQ(seen.pose.ids, (std::vector<int>{0, 1, 2, 3}));
  // The layout's origin is the board's centre (the tags at +-40 mm), y up.
  expect_frame(seen, kFaceUp, 0.5 * (seen.printed.board_min + seen.printed.board_max), "tag board 2x2");
}

TEST(TargetPrinter, PngHasThePagesPixelsAtItsDpi) {
  const Target target = make_target(single_tag_layout(3, 0.040, "tag36h11"));
  print::PrintOptions options;
  options.dpi = 150;
  const std::string png = scratch("tag.png");
  const print::PrintedTarget printed = print::print_target(target, png, options);
  const cv::Mat image = cv::imread(png, cv::IMREAD_UNCHANGED);
  EXPECT_EQ(image.cols, std::lround(0.210 / 0.0254 * 150));  // 1240
  EXPECT_EQ(image.rows, std::lround(0.297 / 0.0254 * 150));  // 1754
  EXPECT_EQ(printed.png_width, image.cols);
  EXPECT_EQ(printed.png_height, image.rows);
  // The tag is 40 mm across at 150 dpi: its black border spans 236 px in the middle row.
  const int row = static_cast<int>(std::lround(printed.T_page_pattern.translation().y() * 150 / 0.0254));
  const cv::Mat line = image.row(row) < 128;
  std::vector<cv::Point> black;
  cv::findNonZero(line, black);
  ASSERT_FALSE(black.empty());
  int first = image.cols, last = 0;
  for (const cv::Point& p : black) {
    if (std::abs(p.x - printed.T_page_pattern.translation().x() * 150 / 0.0254) > 200) continue;  // not the tag
    first = std::min(first, p.x);
    last = std::max(last, p.x);
  }
  EXPECT_NEAR(last - first + 1, 0.040 / 0.0254 * 150, 1.5);
}

TEST(TargetPrinter, ScaleBarIs100mm) {
  const Target target = make_target(single_tag_layout(1, 0.020, "DICT_4X4_50"));
  print::PrintOptions options;
  options.page = print::parse_page("130x100mm");
  const std::string pdf = scratch("scale_bar.pdf"), prefix = scratch("scale_bar");
  print::print_target(target, pdf, options);
  ASSERT_EQ(run("pdftoppm -r 600 -png -gray -singlefile " + pdf + " " + prefix), 0);
  const cv::Mat ink = cv::imread(prefix + ".png", cv::IMREAD_GRAYSCALE) < 128;
  ASSERT_FALSE(ink.empty());
  // The longest black run of any row is the bar (the 20 mm marker is shorter).
  int longest = 0;
  for (int v = 0; v < ink.rows; ++v) {
    int run_length = 0;
    for (int u = 0; u < ink.cols; ++u) {
      run_length = ink.at<uint8_t>(v, u) ? run_length + 1 : 0;
      longest = std::max(longest, run_length);
    }
  }
  std::printf("[ figures  ] scale bar: %.3f mm at 600 dpi\n", longest / kPxPerM * 1e3);
  EXPECT_NEAR(longest / kPxPerM, 0.100, 1.5 / kPxPerM);  // within a pixel and a half
}

TEST(TargetPrinter, SvgIsXmlWithThePagesSizeInMm) {
  const Target target = make_target(ChessboardTarget{9, 6, 0.015});
  print::PrintOptions options;
  options.page = print::parse_page("Letter");
  const std::string svg = scratch("board.svg");
  print::print_target(target, svg, options);
  tinyxml2::XMLDocument document;
  ASSERT_EQ(document.LoadFile(svg.c_str()), tinyxml2::XML_SUCCESS) << document.ErrorStr();
  const tinyxml2::XMLElement* root = document.RootElement();
  ASSERT_NE(root, nullptr);
  EXPECT_STREQ(root->Name(), "svg");
  const auto length_mm = [&](const char* attribute) {
    const char* text = root->Attribute(attribute);
    EXPECT_NE(text, nullptr) << attribute;
    if (text == nullptr) return 0.0;
    char* end = nullptr;
    const double value = std::strtod(text, &end);
    EXPECT_STREQ(end, "mm") << attribute << "=" << text;
    return value;
  };
  EXPECT_NEAR(length_mm("width"), 215.9, 1e-3);
  EXPECT_NEAR(length_mm("height"), 279.4, 1e-3);
}

/// The size the refusal names as the largest that fits (mm), or NaN.
double largest_named(const std::string& message) {
  const std::string key = "that fits is ";
  const std::size_t at = message.find(key);
  return at == std::string::npos ? NAN : std::strtod(message.c_str() + at + key.size(), nullptr);
}

TEST(TargetPrinter, TooLargeBoardIsRefusedWithTheLargestThatFits) {
  print::PrintOptions options;  // A4
  for (const bool markers : {false, true}) {
    const auto make = [&](double size) {
      return markers ? make_target(aruco_grid_layout("DICT_4X4_50", 5, 7, size, size / 4))
                     : make_target(ChessboardTarget{9, 6, size});
    };
    std::string message;
    try {
      print::place_target(make(0.040), options);
      ADD_FAILURE() << "a board far larger than A4 was placed";
    } catch (const HandEyeError& e) {
      EXPECT_EQ(e.code(), ErrorCode::InvalidLayout);
      message = e.what();
    }
    const double largest = largest_named(message) * 1e-3;
    std::printf("[ figures  ] refused on A4: %s\n", message.c_str());
    ASSERT_TRUE(largest > 0.005 && largest < 0.040) << message;
    EXPECT_NE(message.find(markers ? "largest marker" : "largest square"), std::string::npos) << message;
    // The size named fits; 0.2 mm more does not.
    EXPECT_NO_THROW(print::place_target(make(largest), options)) << message;
    EXPECT_THROW(print::place_target(make(largest + 0.0002), options), HandEyeError) << message;
  }
}

TEST(TargetPrinter, MeasuredSquareWritesTheTargetFileScaled) {
  const double nominal = 20.0, measured = 20.1, factor = measured / nominal;
  struct Case {
    std::string name, text;
  };
  const std::vector<Case> cases = {
      {"chessboard", "type: chessboard\ninner_corners: [9, 6]\nsquare: 0.020\n"},
      {"charuco", "type: charuco\nsquares: [5, 7]\nsquare: 0.020\nmarker: 0.015\ndictionary: DICT_5X5_100\n"},
      {"aruco", "type: aruco\ndictionary: DICT_4X4_50\nid: 7\nmarker: 0.020\n"},
      {"aruco_board",
       "type: aruco_board\ndictionary: DICT_4X4_50\nmarkers: [4, 3]\nmarker: 0.020\nseparation: 0.005\nfirst_id: 2\n"},
      {"apriltag", "type: apriltag\nfamily: tag36h11\nid: 4\nsize: 0.020\n"},
      {"layout", "family: tag36h11\ntags:\n  - {id: 0, size: 0.02, x: -0.04, y: 0.04}\n"
                 "  - {id: 5, size: 0.03, x: 0.05, y: -0.01, z: 0.001}\n"},
  };
  for (const Case& c : cases) {
    const std::string in = scratch("nominal_" + c.name + ".yaml"), out = scratch("measured_" + c.name + ".yaml");
    std::ofstream(in) << c.text;
    const std::string command = std::string(HANDEYE_TARGET_TOOL) + " target --target " + in + " --measured-square 20.1 --output " + out;
    ASSERT_EQ(run(command), 0) << command;
    const Target before = io::parse_target(c.text, in), after = io::read_target(out);
    ASSERT_EQ(after.kind_name(), before.kind_name()) << c.name;
    EXPECT_NEAR(print::nominal_square(after), measured * 1e-3, 1e-12) << c.name;
    if (const ChessboardTarget* board = before.get<ChessboardTarget>()) {
      EXPECT_EQ(after.as<ChessboardTarget>().columns, 9);
      EXPECT_NEAR(after.as<ChessboardTarget>().square, board->square * factor, 1e-12);
    } else if (const CharucoTarget* charuco = before.get<CharucoTarget>()) {
      EXPECT_NEAR(after.as<CharucoTarget>().square, charuco->square * factor, 1e-12);
      EXPECT_NEAR(after.as<CharucoTarget>().marker, charuco->marker * factor, 1e-12);
      EXPECT_EQ(after.as<CharucoTarget>().dictionary, "DICT_5X5_100");
    } else {
      const TagLayout &markers_before = before.as<TagLayout>(), &markers_after = after.as<TagLayout>();
      EXPECT_EQ(markers_after.family, markers_before.family) << c.name;
      ASSERT_EQ(markers_after.ids(), markers_before.ids()) << c.name;
      for (std::size_t i = 0; i < markers_before.tags.size(); ++i) {
        const TagPlacement &b = markers_before.tags[i], &a = markers_after.tags[i];
        EXPECT_NEAR(a.size, b.size * factor, 1e-12) << c.name;
        EXPECT_LT((a.T_pattern_tag.translation() - b.T_pattern_tag.translation() * factor).norm(), 1e-12) << c.name;
        EXPECT_LT(angle_between(a.T_pattern_tag.linear(), b.T_pattern_tag.linear()), 1e-12) << c.name;
      }
    }
  }
  // A length in metres (or a print at 50%) is refused, naming the option.
  const std::string in = scratch("nominal_chessboard.yaml");
  EXPECT_EQ(run(std::string(HANDEYE_TARGET_TOOL) + " target --target " + in + " --measured-square 0.0201 --output " +
                scratch("wrong.yaml")) >> 8,
            2);
  EXPECT_FALSE(std::ifstream(scratch("wrong.yaml")).good());
}

TEST(TargetPrinter, ToolDrawsByExtensionAndHasHelp) {
  const std::string tool = HANDEYE_TARGET_TOOL;
  EXPECT_EQ(run(tool + " target --help"), 0);
  const std::string target = std::string(HANDEYE_SOURCE_DIR) + "/config/targets/chessboard.yaml";
  EXPECT_EQ(run(tool + " target --target " + target + " --output " + scratch("cli.pdf")), 0);
  EXPECT_EQ(read_text(scratch("cli.pdf")).rfind("%PDF", 0), 0u);
  EXPECT_EQ(run(tool + " target --target " + target + " --output " + scratch("cli.bmp")) >> 8, 2);
  EXPECT_EQ(run(tool + " target --target " + target + " --page B7 --output " + scratch("cli2.pdf")) >> 8, 2);
}

}  // namespace
}  // namespace handeye
