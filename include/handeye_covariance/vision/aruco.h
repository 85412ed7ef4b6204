// ArUco markers and ChArUco boards with OpenCV's aruco module (no ROS).
//
// Marker frames: an ArUco marker is a TagPlacement like an AprilTag (origin at its
// centre, x right, y up, z out of the printed face), and its corners come in
// TagPlacement::corners() order, so a single marker or any board of markers is a
// TagLayout whose `family` is an OpenCV dictionary name (DICT_4X4_50, ...), and
// the edge-fit corner model and tag_correspondences serve it as they serve
// AprilTags (the corners are refined by fitting lines to the sides, as
// libapriltag does).
//
// Board frames are OpenCV's (4.6): the origin at the top-left corner of the
// board as OpenCV draws it, x to the right, y down the board, z into it.
//   ArUco grid board: the top-left corner of the top-left marker; ids row by row.
//   ChArUco board: the top-left corner of the top-left square (always black);
//     its corners are the inner chessboard corners, id c at
//     ((c % (columns - 1) + 1) square, (c / (columns - 1) + 1) square, 0).
// ChArUco corners are refined on their own by cornerSubPix: independent corners,
// the same sigma in x and y, pooled from the residuals.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "handeye_covariance/core/tag_layout.h"
#include "handeye_covariance/core/targets/charuco.h"
#include "handeye_covariance/core/targets/markers.h"
#include "handeye_covariance/vision/pattern_pose.h"
#include "handeye_covariance/vision/tag_detector.h"

namespace cv {
namespace aruco {
class Dictionary;
struct DetectorParameters;
}  // namespace aruco
}  // namespace cv

namespace handeye {

/// OpenCV's predefined dictionaries by name (DICT_4X4_50 ... DICT_APRILTAG_36h11).
std::vector<std::string> aruco_dictionaries();
/// The number of markers in the dictionary; throws HandEyeError(InvalidLayout)
/// naming the known dictionaries when `name` is not one.
int aruco_dictionary_size(const std::string& name);

/// A marker's printable bitmap: one pixel per cell, the black border and a
/// one-cell white quiet zone (TagBitmap's layout, as for AprilTags).
TagBitmap aruco_bitmap(const std::string& dictionary, int id);

/// The markers of `dictionary` in a gray image, in TagPlacement::corners() order
/// (bottom-left, bottom-right, top-right, top-left of the printed marker), sorted
/// by id. OpenCV finds and decodes them; the corners are refined as libapriltag
/// refines its own (lines fitted to each side's edge points, intersected), so
/// the edge-fit corner model holds. A marker whose sides cannot be fitted (cut
/// by the image border) is left out.
class ArucoDetector {
 public:
  explicit ArucoDetector(const std::string& dictionary);
  std::vector<TagCorners> detect(const cv::Mat& gray) const;

 private:
  // Made once: OpenCV builds a predefined dictionary's tables on each lookup.
  cv::Ptr<cv::aruco::Dictionary> dictionary_;
  cv::Ptr<cv::aruco::DetectorParameters> parameters_;
};

/// Throws HandEyeError(InvalidLayout): fewer than 3 squares either way, lengths
/// that are not positive or a marker that does not fit in its square, an unknown
/// dictionary, or a dictionary with fewer markers than the board needs.
void check_charuco(const CharucoTarget& target, const std::string& where);

/// The board's markers as OpenCV lays them out (CharucoBoard's ids and marker
/// corners), each a TagPlacement in the board's frame; `family` is the dictionary.
/// The squares that hold no marker are the black ones (what `handeye target` prints).
TagLayout charuco_marker_layout(const CharucoTarget& target);

/// The board as OpenCV draws it, `texels_per_square` texels to a square, with no
/// margin: texel (u, v) covers [u, u + 1) x [v, v + 1) / texels_per_square squares.
cv::Mat charuco_image(const CharucoTarget& target, int texels_per_square);

/// The board's corners that OpenCV interpolates from the markers it finds (at
/// least `min_corners`, not all on one line), each refined by cornerSubPix.
TargetObservation detect_charuco(const cv::Mat& gray, const CharucoTarget& target, int min_corners = 6);

}  // namespace handeye
