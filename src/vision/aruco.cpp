#include "handeye_covariance/vision/aruco.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>

#include <Eigen/Dense>

#include <opencv2/aruco/charuco.hpp>
#include <opencv2/imgproc.hpp>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/vision/chessboard.h"
#include "edge_refinement.h"

namespace handeye {
namespace {

const std::map<std::string, cv::aruco::PREDEFINED_DICTIONARY_NAME>& dictionary_names() {
  using namespace cv::aruco;
  static const std::map<std::string, PREDEFINED_DICTIONARY_NAME> table = {
      {"DICT_4X4_50", DICT_4X4_50},         {"DICT_4X4_100", DICT_4X4_100},
      {"DICT_4X4_250", DICT_4X4_250},       {"DICT_4X4_1000", DICT_4X4_1000},
      {"DICT_5X5_50", DICT_5X5_50},         {"DICT_5X5_100", DICT_5X5_100},
      {"DICT_5X5_250", DICT_5X5_250},       {"DICT_5X5_1000", DICT_5X5_1000},
      {"DICT_6X6_50", DICT_6X6_50},         {"DICT_6X6_100", DICT_6X6_100},
      {"DICT_6X6_250", DICT_6X6_250},       {"DICT_6X6_1000", DICT_6X6_1000},
      {"DICT_7X7_50", DICT_7X7_50},         {"DICT_7X7_100", DICT_7X7_100},
      {"DICT_7X7_250", DICT_7X7_250},       {"DICT_7X7_1000", DICT_7X7_1000},
      {"DICT_ARUCO_ORIGINAL", DICT_ARUCO_ORIGINAL}, {"DICT_APRILTAG_16h5", DICT_APRILTAG_16h5},
      {"DICT_APRILTAG_25h9", DICT_APRILTAG_25h9},   {"DICT_APRILTAG_36h10", DICT_APRILTAG_36h10},
      {"DICT_APRILTAG_36h11", DICT_APRILTAG_36h11},
  };
  return table;
}

cv::Ptr<cv::aruco::Dictionary> dictionary(const std::string& name) {
  const auto it = dictionary_names().find(name);
  if (it == dictionary_names().end()) {
    std::string known;
    for (const std::string& n : aruco_dictionaries()) known += (known.empty() ? "" : ", ") + n;
    throw HandEyeError(ErrorCode::InvalidLayout, "unknown ArUco dictionary `" + name + "`", "dictionary",
                       "use one of " + known + " (the name printed with the board)");
  }
  return cv::aruco::getPredefinedDictionary(it->second);
}

cv::Ptr<cv::aruco::CharucoBoard> charuco_board(const CharucoTarget& t) {
  return cv::aruco::CharucoBoard::create(t.columns, t.rows, static_cast<float>(t.square), static_cast<float>(t.marker),
                                         dictionary(t.dictionary));
}

/// OpenCV finds and decodes the markers; the corners are then refined here (see
/// refine_marker_edges, to 0.014 px RMS on rendered markers), so OpenCV's own
/// refinement is off. Measured on
/// rendered markers (test_targets), OpenCV's refinements are biased towards the
/// marker's centre by 0.55 px (none, contour) or 0.20 px (cornerSubPix), i.e.
/// 2-5 mm of depth for a 0.1 m marker at 0.6 m; its port of libapriltag's
/// (CORNER_REFINE_APRILTAG) is unbiased but its errors do not follow the
/// edge-fit model (translation NEES 7 to 10).
cv::Ptr<cv::aruco::DetectorParameters> marker_parameters() {
  cv::Ptr<cv::aruco::DetectorParameters> p = cv::aruco::DetectorParameters::create();
  p->cornerRefinementMethod = cv::aruco::CORNER_REFINE_NONE;
  return p;
}


/// The smallest image distance between two corners one square apart.
float board_corner_spacing(const cv::Ptr<cv::aruco::CharucoBoard>& board, const std::vector<int>& ids,
                           const std::vector<cv::Point2f>& corners) {
  float spacing = INFINITY;
  const float square = board->getSquareLength();
  for (std::size_t i = 0; i < ids.size(); ++i) {
    for (std::size_t j = i + 1; j < ids.size(); ++j) {
      const cv::Point3f d = board->chessboardCorners[static_cast<std::size_t>(ids[i])] -
                            board->chessboardCorners[static_cast<std::size_t>(ids[j])];
      if (std::abs(std::hypot(d.x, d.y) - square) < 0.01f * square) {
        spacing = std::min(spacing, static_cast<float>(cv::norm(corners[i] - corners[j])));
      }
    }
  }
  return std::isfinite(spacing) ? spacing : 10.0f;
}

}  // namespace

std::vector<std::string> aruco_dictionaries() {
  std::vector<std::pair<int, std::string>> by_value;
  for (const auto& entry : dictionary_names()) by_value.emplace_back(entry.second, entry.first);
  std::sort(by_value.begin(), by_value.end());
  std::vector<std::string> names;
  for (const auto& entry : by_value) names.push_back(entry.second);
  return names;
}


int aruco_dictionary_size(const std::string& name) { return dictionary(name)->bytesList.rows; }

TagBitmap aruco_bitmap(const std::string& name, int id) {
  const cv::Ptr<cv::aruco::Dictionary> d = dictionary(name);
  if (id < 0 || id >= d->bytesList.rows) {
    throw HandEyeError(ErrorCode::InvalidLayout,
                       "marker id " + std::to_string(id) + " does not exist in " + name + " (ids 0 to " +
                           std::to_string(d->bytesList.rows - 1) + ")",
                       "target", "use an id of the dictionary, or change the dictionary");
  }
  const int side = d->markerSize + 2;  // the code and a one-cell black border
  cv::Mat marker;
  cv::aruco::drawMarker(d, id, side, marker, 1);
  TagBitmap bitmap;
  cv::copyMakeBorder(marker, bitmap.pixels, 1, 1, 1, 1, cv::BORDER_CONSTANT, cv::Scalar(255));
  bitmap.width_at_border = side;
  return bitmap;
}

ArucoDetector::ArucoDetector(const std::string& name) : dictionary_(dictionary(name)), parameters_(marker_parameters()) {}

std::vector<TagCorners> ArucoDetector::detect(const cv::Mat& gray) const {
  if (gray.type() != CV_8UC1) {
    throw HandEyeError(ErrorCode::MalformedFile, "the image is not 8-bit single-channel", "ArucoDetector::detect",
                       "convert it to mono8 first");
  }
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<int> ids;
  cv::aruco::detectMarkers(gray, dictionary_, corners, ids, parameters_);
  std::vector<TagCorners> tags;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    TagCorners tag;
    tag.id = ids[i];
    // OpenCV: top-left, top-right, bottom-right, bottom-left; ours starts bottom-left.
    const int order[4] = {3, 2, 1, 0};
    for (int c = 0; c < 4; ++c) tag.corners[c] = Eigen::Vector2d(corners[i][order[c]].x, corners[i][order[c]].y);
    if (!refine_marker_edges(gray, tag.corners, 2.0)) continue;
    tags.push_back(tag);
  }
  std::sort(tags.begin(), tags.end(), [](const TagCorners& a, const TagCorners& b) { return a.id < b.id; });
  return tags;
}

void check_charuco(const CharucoTarget& t, const std::string& where) {
  if (t.columns < 3 || t.rows < 3) {
    throw HandEyeError(ErrorCode::InvalidLayout,
                       "a ChArUco board needs at least 3 x 3 squares, got " + std::to_string(t.columns) + " x " +
                           std::to_string(t.rows),
                       where, "count the squares (black and white) along a row and along a column");
  }
  if (!(t.square > 0.0) || !std::isfinite(t.square) || !(t.marker > 0.0) || !(t.marker < t.square)) {
    throw HandEyeError(ErrorCode::InvalidLayout, "square and marker must be positive lengths in m, the marker smaller",
                       where, "measure one printed square and one marker (its black border included), e.g. "
                              "square: 0.036, marker: 0.018");
  }
  const int needed = (t.columns * t.rows) / 2;
  if (aruco_dictionary_size(t.dictionary) < needed) {
    throw HandEyeError(ErrorCode::InvalidLayout,
                       "a " + std::to_string(t.columns) + " x " + std::to_string(t.rows) + " board needs " +
                           std::to_string(needed) + " markers, " + t.dictionary + " has " +
                           std::to_string(aruco_dictionary_size(t.dictionary)),
                       where, "use the dictionary the board was printed with");
  }
}

TagLayout charuco_marker_layout(const CharucoTarget& t) {
  const cv::Ptr<cv::aruco::CharucoBoard> board = charuco_board(t);
  TagLayout layout;
  layout.family = t.dictionary;
  for (std::size_t i = 0; i < board->ids.size(); ++i) {
    // OpenCV's corners go round the printed marker from its top-left: the tag's
    // x runs from corner 0 to 1, its y (up on the print) from corner 3 to 0.
    const std::vector<cv::Point3f>& c = board->objPoints[i];
    const auto point = [&](int k) { return Eigen::Vector3d(c[k].x, c[k].y, c[k].z); };
    const Eigen::Vector3d x = (point(1) - point(0)).normalized(), y = (point(0) - point(3)).normalized();
    TagPlacement tag;
    tag.id = board->ids[i];
    tag.size = t.marker;
    tag.T_pattern_tag.linear() << x, y, x.cross(y);
    tag.T_pattern_tag.translation() = 0.25 * (point(0) + point(1) + point(2) + point(3));
    layout.tags.push_back(tag);
  }
  return layout;
}

cv::Mat charuco_image(const CharucoTarget& t, int texels_per_square) {
  cv::Mat image;
  charuco_board(t)->draw(cv::Size(t.columns * texels_per_square, t.rows * texels_per_square), image, 0, 1);
  return image;
}

TargetObservation detect_charuco(const cv::Mat& gray, const CharucoTarget& t, int min_corners) {
  TargetObservation out;
  if (gray.type() != CV_8UC1) {
    throw HandEyeError(ErrorCode::MalformedFile, "the image is not 8-bit single-channel", "detect_charuco",
                       "convert it to mono8 first");
  }
  const cv::Ptr<cv::aruco::CharucoBoard> board = charuco_board(t);
  std::vector<std::vector<cv::Point2f>> markers;
  std::vector<int> marker_ids;
  cv::aruco::detectMarkers(gray, board->dictionary, markers, marker_ids);
  if (marker_ids.empty()) {
    out.refusal = "no marker of " + t.dictionary + " found (is the board in view, and printed with this dictionary?)";
    return out;
  }
  std::vector<cv::Point2f> corners;
  std::vector<int> ids;
  cv::aruco::interpolateCornersCharuco(markers, marker_ids, gray, board, corners, ids);
  if (static_cast<int>(ids.size()) < std::max(4, min_corners)) {
    out.refusal = "saw " + std::to_string(marker_ids.size()) + " markers but only " + std::to_string(ids.size()) +
                  " board corners, need " + std::to_string(std::max(4, min_corners)) +
                  "; bring more of the board into view (or check its squares, dictionary and first id)";
    return out;
  }
  if (cv::aruco::testCharucoCornersCollinear(board, ids)) {
    out.refusal = "the " + std::to_string(ids.size()) + " board corners seen lie on one line; show more of the board";
    return out;
  }
  // OpenCV refines the interpolated corners with cornerSubPix, but stops at 0.1 px
  // of movement and adds 0.5 px to the result (opencv/opencv#25539, fixed upstream
  // by #28380): measured on rendered boards, a +0.50 px bias and a translation
  // NEES of 6.4. cornerSubPix again, to convergence, lands on each saddle point
  // whatever the start.
  // The window stays clear of the markers in the white squares around a corner.
  out.saddle_half_window =
      refine_saddle_points(gray, corners, board_corner_spacing(board, ids, corners) * static_cast<float>(1.0 - t.marker / t.square));
  PointCorrespondences points;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const cv::Point3f& p = board->chessboardCorners[static_cast<std::size_t>(ids[i])];
    points.object.emplace_back(p.x, p.y, p.z);
    points.image.emplace_back(corners[i].x, corners[i].y);
    points.ids.push_back(ids[i]);
  }
  points.blocks = 2;  // independent corners
  out.points = points;
  return out;
}

}  // namespace handeye
