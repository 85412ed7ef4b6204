#include "handeye_covariance/vision/tag_detector.h"

extern "C" {
#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagCircle21h7.h>
#include <apriltag/tagStandard41h12.h>
#include <apriltag/tagStandard52h13.h>
}

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <map>

#include "handeye_covariance/core/errors.h"
#include "edge_refinement.h"

namespace handeye {
namespace {

struct FamilyFactory {
  std::function<apriltag_family_t*()> create;
  std::function<void(apriltag_family_t*)> destroy;
};

const std::map<std::string, FamilyFactory>& factories() {
  static const std::map<std::string, FamilyFactory> table = {
      {"tag36h11", {tag36h11_create, tag36h11_destroy}},
      {"tag25h9", {tag25h9_create, tag25h9_destroy}},
      {"tag16h5", {tag16h5_create, tag16h5_destroy}},
      {"tagCircle21h7", {tagCircle21h7_create, tagCircle21h7_destroy}},
      {"tagStandard41h12", {tagStandard41h12_create, tagStandard41h12_destroy}},
      {"tagStandard52h13", {tagStandard52h13_create, tagStandard52h13_destroy}},
  };
  return table;
}

const FamilyFactory& factory(const std::string& family) {
  const auto it = factories().find(family);
  if (it == factories().end()) {
    std::string known;
    for (const std::string& name : tag_families()) known += (known.empty() ? "" : ", ") + name;
    throw HandEyeError(ErrorCode::InvalidLayout, "unknown tag family `" + family + "`", "family",
                       "use one of " + known);
  }
  return it->second;
}

/// A family owned with its destroy function.
using Family = std::unique_ptr<apriltag_family_t, std::function<void(apriltag_family_t*)>>;
Family make_family(const std::string& name) {
  const FamilyFactory& f = factory(name);
  return Family(f.create(), f.destroy);
}

}  // namespace

std::vector<std::string> tag_families() {
  std::vector<std::string> names;
  for (const auto& entry : factories()) names.push_back(entry.first);
  return names;
}

namespace {

/// libapriltag (3.3) starts its worker threads in a detector's first detection and
/// at once adds that detection's tasks to their list without its lock: a thread
/// that starts late can take a task the next addition has just moved (the list
/// grows by realloc) and call whatever the freed memory holds. An intermittent
/// crash: about 1 in 5 000 new detectors on an idle machine, more under load
/// (test_vision's WorkerThreadsStartSafely makes 2 000 from two threads: 3 of 8
/// runs crashed).
/// A first detection on a blank 8 x 8 image starts the threads with under 8
/// tasks per step, which the list holds without moving; after it, tasks are only
/// added while the threads wait for them. With it: no crash in 10 000 detectors
/// made one after another, nor in 6 runs of that test.
void start_worker_threads(apriltag_detector_t* detector) {
  if (detector->nthreads <= 1) return;
  std::array<uint8_t, 64> blank;
  blank.fill(128);
  image_u8_t image{8, 8, 8, blank.data()};
  apriltag_detections_destroy(apriltag_detector_detect(detector, &image));
}

}  // namespace

struct TagDetector::Impl {
  Family family;
  apriltag_detector_t* detector = nullptr;
};

TagDetector::TagDetector(const TagDetectorOptions& options) : options_(options), impl_(std::make_unique<Impl>()) {
  impl_->family = make_family(options.family);
  impl_->detector = apriltag_detector_create();
  apriltag_detector_add_family_bits(impl_->detector, impl_->family.get(), std::max(0, options.max_hamming));
  impl_->detector->quad_sigma = static_cast<float>(options.quad_sigma);
  impl_->detector->nthreads = std::max(1, options.threads);
  impl_->detector->refine_edges = options.refine_edges;
  start_worker_threads(impl_->detector);
}

TagDetector::~TagDetector() {
  if (impl_ && impl_->detector) apriltag_detector_destroy(impl_->detector);
}

std::vector<TagCorners> TagDetector::detect(const cv::Mat& gray) const {
  if (gray.type() != CV_8UC1) {
    throw HandEyeError(ErrorCode::MalformedFile, "the image is not 8-bit single-channel", "TagDetector::detect",
                       "convert it to mono8 first (cv_bridge does this for the node)");
  }
  cv::Mat contiguous = gray.isContinuous() ? gray : gray.clone();
  image_u8_t image{contiguous.cols, contiguous.rows, static_cast<int32_t>(contiguous.step), contiguous.data};
  impl_->detector->quad_decimate = static_cast<float>(
      options_.quad_decimate > 0.0 ? options_.quad_decimate : std::max(1, contiguous.cols / 640));
  zarray_t* found = apriltag_detector_detect(impl_->detector, &image);
  std::vector<TagCorners> tags;
  for (int i = 0; i < zarray_size(found); ++i) {
    apriltag_detection_t* det = nullptr;
    zarray_get(found, i, &det);
    if (det->hamming > options_.max_hamming || det->decision_margin < options_.min_decision_margin) continue;
    TagCorners tag;
    tag.id = det->id;
    tag.hamming = det->hamming;
    tag.decision_margin = det->decision_margin;
    // libapriltag puts pixel centres at +0.5 (a pixel spans [i, i + 1)); OpenCV
    // and CameraInfo put them at integers. Without the shift every pose is off
    // by half a pixel (0.4 mm sideways at 0.5 m here; test_vision sees it).
    for (int c = 0; c < 4; ++c) tag.corners[c] = Eigen::Vector2d(det->p[c][0] - 0.5, det->p[c][1] - 0.5);
    // libapriltag fits each edge once, from nearest-pixel samples about its
    // thresholded quad, and its corners share an offset of a few thousandths of a
    // pixel; refitting until the lines stop moving, the last passes within +-1 px,
    // takes most of it out (see refine_marker_edges). At the image border, where a
    // side has too few edge points, libapriltag's corners stay.
    if (options_.refine_edges) {
      std::array<Eigen::Vector2d, 4> refitted = tag.corners;
      if (refine_marker_edges(contiguous, refitted, 1.0, !impl_->family->reversed_border)) tag.corners = refitted;
    }
    tags.push_back(tag);
  }
  apriltag_detections_destroy(found);
  std::sort(tags.begin(), tags.end(), [](const TagCorners& a, const TagCorners& b) { return a.id < b.id; });
  return tags;
}

TagBitmap apriltag_bitmap(const std::string& family, int id) {
  const Family f = make_family(family);
  if (id < 0 || static_cast<uint32_t>(id) >= f->ncodes) {
    throw HandEyeError(ErrorCode::InvalidLayout,
                       "tag id " + std::to_string(id) + " does not exist in " + family + " (ids 0 to " +
                           std::to_string(f->ncodes - 1) + ")",
                       "tag layout", "use an id of the family, or change the family");
  }
  image_u8_t* image = apriltag_to_image(f.get(), id);
  TagBitmap bitmap;
  bitmap.pixels = cv::Mat(image->height, image->width, CV_8UC1, image->buf, image->stride).clone();
  bitmap.width_at_border = f->width_at_border;
  // Debian's libapriltag does not export image_u8_destroy; the image and its
  // buffer come from calloc (image_u8_create_stride), so free them the same way.
  free(image->buf);
  free(image);
  return bitmap;
}

}  // namespace handeye
