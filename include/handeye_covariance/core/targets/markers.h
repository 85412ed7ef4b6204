// The marker kinds (core/target.h): ArUco (`type: aruco`, `type: aruco_board`)
// and AprilTag (`type: apriltag`), one marker or a board; both are a TagLayout
// (tag_layout.h, its frames) whose family names the detector: an OpenCV
// dictionary (DICT_4X4_50, ...) for ArUco, a libapriltag family for AprilTag. A
// tag layout file (`tags:`) is either, by its family.
#pragma once

#include <string>

#include "handeye_covariance/core/tag_layout.h"
#include "handeye_covariance/core/target.h"

namespace handeye {

const TargetKind& aruco_kind();
const TargetKind& apriltag_kind();

/// ArUco when the family names an OpenCV dictionary, else AprilTag.
Target make_target(const TagLayout& markers);

/// A grid board of markers (OpenCV's GridBoard: ids row by row from `first_id`)
/// as a layout in OpenCV's board frame (the top-left corner of the top-left
/// marker, x right, y down, z into the board); `family` is the dictionary.
TagLayout aruco_grid_layout(const std::string& dictionary, int columns, int rows, double marker, double separation,
                            int first_id = 0);

/// The name is meant as an OpenCV dictionary (it starts with DICT, any case),
/// known or not: the ArUco path then names a typo with the known dictionaries.
bool names_aruco_dictionary(const std::string& name);

}  // namespace handeye
