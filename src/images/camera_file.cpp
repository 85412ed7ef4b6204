// OpenCV's camera files, read from memory (so the fuzzer can drive it without
// files): XML by cv::FileStorage after tinyxml2's check, YAML and JSON by
// yaml-cpp. Only opencv_core, tinyxml2 and yaml-cpp: test/sanitize builds this
// file alone into fuzz_target_files.
#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/core.hpp>
#include <opencv2/core/persistence.hpp>
#include <tinyxml2.h>
#include <yaml-cpp/yaml.h>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/images/image_folder.h"

namespace handeye {
namespace images {
namespace {

/// image_width or image_height as read (NaN: not a number), checked.
int checked_image_size(double value, const std::string& key, const std::string& source) {
  if (!(value >= 1 && value <= 100000) || value != std::floor(value)) {
    throw HandEyeError(ErrorCode::MalformedFile, key + " must be a whole number of pixels in [1, 100000]", source,
                       "write the image size in pixels, or leave it out");
  }
  return static_cast<int>(value);
}

int image_size(const cv::FileNode& node, const std::string& key, const std::string& source) {
  if (node.empty()) return 0;
  return checked_image_size(node.isInt() || node.isReal() ? node.real() : std::numeric_limits<double>::quiet_NaN(), key,
                            source);
}

/// An opencv-matrix's declared rows and cols (-1: not a number) and its number of
/// data entries, checked before anything is allocated or read.
void check_matrix_size(const std::string& key, const double (&dims)[2], std::size_t data_entries, int max_entries,
                       const std::string& source, const std::string& hint) {
  const char* names[2] = {"rows", "cols"};
  for (int i = 0; i < 2; ++i) {
    if (!(dims[i] >= 1 && dims[i] <= max_entries) || dims[i] != std::floor(dims[i])) {
      throw HandEyeError(ErrorCode::MalformedFile, key + "." + names[i] + " must be a whole number in [1, " +
                                                       std::to_string(max_entries) + "]",
                         source, hint);
    }
  }
  const double entries = dims[0] * dims[1];
  if (entries > max_entries || data_entries != static_cast<std::size_t>(entries)) {
    throw HandEyeError(ErrorCode::WrongLength, key + ".data must hold rows x cols numbers (at most " +
                                                   std::to_string(max_entries) + ")",
                       source, hint);
  }
}

/// A matrix node read only after its declared size is checked: OpenCV allocates
/// rows x cols before it reads `data`, so `cols: 1000000000` would ask for gigabytes.
cv::Mat small_matrix(const cv::FileNode& node, const std::string& key, int max_entries, const std::string& source,
                     const std::string& hint) {
  cv::Mat m;
  if (node.empty()) return m;
  if (!node.isMap()) {
    throw HandEyeError(ErrorCode::MalformedFile, key + " is not an opencv-matrix", source, hint);
  }
  const auto number = [](const cv::FileNode& n) { return n.isInt() || n.isReal() ? n.real() : -1.0; };
  check_matrix_size(key, {number(node["rows"]), number(node["cols"])}, node["data"].size(), max_entries, source, hint);
  node >> m;
  return m;
}

/// OpenCV 4.6's XML parser reads past the end of a malformed document (a NULL
/// dereference on "<?xml versio...=" cut short: test/fuzz/corpus/target_files/
/// regression-opencv-xml-cut-attribute.xml), so an XML file is checked by a real
/// XML parser first; OpenCV only ever sees well-formed XML.
void require_well_formed_xml(const std::string& text, const std::string& source, const std::string& hint) {
  tinyxml2::XMLDocument document;
  if (document.Parse(text.data(), text.size()) != tinyxml2::XML_SUCCESS) {
    throw HandEyeError(ErrorCode::MalformedFile,
                       "not well-formed XML (line " + std::to_string(document.ErrorLineNum()) +
                           "): " + document.ErrorStr(),
                       source, hint);
  }
}

/// OpenCV 4.6's YAML parser loops forever on some malformed files (a directive
/// after a document start, "---%YAML:1.0" then "----"; bytes beyond ASCII in a
/// flow sequence: test/fuzz/corpus/target_files/regression-opencv-yaml-*), so a YAML
/// file is checked first: ASCII outside comments, '%' only in its first line's
/// %YAML:1.0, and well-formed for yaml-cpp (with that line left out, which is
/// OpenCV's, not YAML 1.2's). OpenCV then sees only what a YAML parser accepts.
YAML::Node parse_opencv_yaml(const std::string& text, const std::string& source, const std::string& hint) {
  std::string body;
  int line = 1;
  for (std::size_t start = 0; start <= text.size(); ++line) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    const std::string content = text.substr(start, end - start);
    const std::string code = content.substr(0, content.find('#'));
    const bool header = line == 1 && code.rfind("%YAML", 0) == 0;
    for (const char c : code) {
      const auto byte = static_cast<unsigned char>(c);
      if (byte >= 0x80 || (byte < 0x20 && c != '\t' && c != '\r') || (c == '%' && !header)) {
        throw HandEyeError(ErrorCode::MalformedFile,
                           "line " + std::to_string(line) +
                               (c == '%' ? " has a '%': only the first line holds a directive (%YAML:1.0)"
                                         : " has a byte that is not printable ASCII (outside a comment)"),
                           source, hint);
      }
    }
    body += header ? "\n" : content + "\n";
    start = end + 1;
  }
  try {
    return YAML::Load(body);
  } catch (const YAML::Exception& e) {
    throw HandEyeError(ErrorCode::MalformedFile,
                       "not well-formed YAML (line " + std::to_string(e.mark.line + 1) + "): " + e.msg, source, hint);
  }
}

/// An opencv-matrix node's numbers (rows x cols of them, at most max_entries), read by yaml-cpp.
cv::Mat yaml_matrix(const YAML::Node& root, const std::string& key, int max_entries, const std::string& source,
                    const std::string& hint) {
  const YAML::Node node = root[key];
  if (!node) return {};
  if (!node.IsMap() || !node["data"] || !node["data"].IsSequence()) {
    throw HandEyeError(ErrorCode::MalformedFile, key + " is not an opencv-matrix (rows, cols, dt, data)", source, hint);
  }
  const auto number = [](const YAML::Node& n) {
    try {
      return n ? n.as<double>() : -1.0;
    } catch (const YAML::Exception&) {
      return -1.0;
    }
  };
  const YAML::Node data = node["data"];
  const double dims[2] = {number(node["rows"]), number(node["cols"])};
  check_matrix_size(key, dims, data.size(), max_entries, source, hint);
  const int rows = static_cast<int>(dims[0]), cols = static_cast<int>(dims[1]);
  cv::Mat m(rows, cols, CV_64F);
  for (int i = 0; i < rows * cols; ++i) {
    try {
      m.at<double>(i / cols, i % cols) = data[static_cast<std::size_t>(i)].as<double>();
    } catch (const YAML::Exception&) {
      throw HandEyeError(ErrorCode::MalformedFile, key + ".data[" + std::to_string(i) + "] is not a number", source, hint);
    }
  }
  return m;
}

int yaml_image_size(const YAML::Node& root, const std::string& key, const std::string& source) {
  if (!root[key]) return 0;
  double value = std::numeric_limits<double>::quiet_NaN();
  try {
    value = root[key].as<double>();
  } catch (const YAML::Exception&) {
  }
  return checked_image_size(value, key, source);
}

}  // namespace

CameraModel parse_opencv_camera(const std::string& text, const std::string& source) {
  const std::string hint = "OpenCV's camera file has camera_matrix (3 x 3) and distortion_coefficients "
                           "(write it with cv::FileStorage)";
  CameraModel file;
  // OpenCV 4.6's XML parser dereferences NULL on a NUL byte inside a tag
  // (test/fuzz/corpus/target_files/regression-opencv-nul-byte.xml); a camera file is text.
  if (const std::size_t nul = text.find('\0'); nul != std::string::npos) {
    throw HandEyeError(ErrorCode::MalformedFile, "a NUL byte at offset " + std::to_string(nul) + ": not a text file",
                       source, hint);
  }
  // YAML and JSON are read by yaml-cpp: OpenCV 4.6's YAML parser loops forever on
  // some malformed files (parse_opencv_yaml), and OpenCV's only XML is left to it.
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  const bool xml = first != std::string::npos && text[first] == '<';
  YAML::Node yaml;
  if (xml) {
    require_well_formed_xml(text, source, hint);
  } else {
    yaml = parse_opencv_yaml(text, source, hint);
    if (!yaml.IsMap()) throw HandEyeError(ErrorCode::MalformedFile, "not a mapping of camera_matrix, ...", source, hint);
  }
  try {
    cv::FileStorage storage;
    if (xml) {
      storage.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
      if (!storage.isOpened()) throw HandEyeError(ErrorCode::MalformedFile, "OpenCV cannot read it", source, hint);
    }
    cv::Mat K = xml ? small_matrix(storage["camera_matrix"], "camera_matrix", 9, source, hint)
                    : yaml_matrix(yaml, "camera_matrix", 9, source, hint);
    cv::Mat D = xml ? small_matrix(storage["distortion_coefficients"], "distortion_coefficients", 14, source, hint)
                    : yaml_matrix(yaml, "distortion_coefficients", 14, source, hint);
    if (K.rows != 3 || K.cols != 3 || K.channels() != 1) {
      throw HandEyeError(ErrorCode::MissingKey, "no 3 x 3 camera_matrix", source, hint);
    }
    K.convertTo(K, CV_64F);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        file.K(r, c) = K.at<double>(r, c);
        if (!std::isfinite(file.K(r, c))) {
          throw HandEyeError(ErrorCode::NonFinite, "camera_matrix has a non-finite entry", source, hint);
        }
      }
    }
    if (!D.empty()) {  // at most 14 entries: small_matrix checked rows x cols
      if (D.channels() != 1) {
        throw HandEyeError(ErrorCode::MalformedFile, "distortion_coefficients has " + std::to_string(D.channels()) +
                                                         " channels; it is one row or column of numbers",
                           source, hint);
      }
      D.convertTo(D, CV_64F);
      D = D.reshape(1, 1);
      file.distortion.assign(D.begin<double>(), D.end<double>());
      for (double d : file.distortion) {
        if (!std::isfinite(d)) {
          throw HandEyeError(ErrorCode::NonFinite, "distortion_coefficients has a non-finite entry", source, hint);
        }
      }
    }
    // Optional: the 1 sigma of fx, fy, cx, cy (px), an opencv-matrix of 4 as the others.
    const cv::Mat sigma = xml ? small_matrix(storage["intrinsics_sigma"], "intrinsics_sigma", 4, source, hint)
                              : yaml_matrix(yaml, "intrinsics_sigma", 4, source, hint);
    if (!sigma.empty()) {
      if (sigma.total() != 4 || sigma.channels() != 1) {
        throw HandEyeError(ErrorCode::WrongLength, "intrinsics_sigma needs 4 numbers: the 1 sigma of fx, fy, cx, cy (px)",
                           source, hint);
      }
      cv::Mat values;
      sigma.convertTo(values, CV_64F);
      for (int k = 0; k < 4; ++k) {
        const double v = values.at<double>(k);
        if (!(v >= 0.0) || !std::isfinite(v)) {
          throw HandEyeError(ErrorCode::MalformedFile, "intrinsics_sigma holds a negative or non-finite sigma", source,
                             "give the 1 sigma of fx, fy, cx, cy in px, each >= 0");
        }
        file.intrinsics_sigma[k] = v;
      }
    }
    file.width = xml ? image_size(storage["image_width"], "image_width", source)
                     : yaml_image_size(yaml, "image_width", source);
    file.height = xml ? image_size(storage["image_height"], "image_height", source)
                      : yaml_image_size(yaml, "image_height", source);
  } catch (const HandEyeError&) {
    throw;
  } catch (const std::exception& e) {
    // cv::Exception from OpenCV's XML reader. (OpenCV 4.6's YAML parser, which no
    // longer reads these files, let std::length_error out on some: regression-opencv-length-error.yaml.)
    throw HandEyeError(ErrorCode::MalformedFile, "OpenCV cannot read it: " + std::string(e.what()), source, hint);
  }
  return file;
}

}  // namespace images
}  // namespace handeye
