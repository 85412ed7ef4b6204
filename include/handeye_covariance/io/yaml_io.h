// All of the package's file formats, one header per family (yaml-cpp; no ROS).
// See docs/file_formats.md. Include the narrower header where one family is enough.
#pragma once

#include "handeye_covariance/io/files.h"         // read_file, write_file_atomically, expand_home, session config
#include "handeye_covariance/io/pose_files.h"    // robot pose files, the CSV pose table
#include "handeye_covariance/io/result_file.h"   // results, reports, checks, pose files, stored calibrations
#include "handeye_covariance/io/samples_file.h"  // samples, motions, candidates, noise, suggestions
#include "handeye_covariance/io/target_file.h"   // targets, tag layouts, camera_info
