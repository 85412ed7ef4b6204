#include "handeye_covariance/ros/target_params.h"

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/targets/markers.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/ros/params.h"

namespace handeye {

Target target_from_params(const ros::NodeHandle& pn) {
  const std::string kind = param<std::string>(pn, "target", "");
  const std::string target_file = param<std::string>(pn, "target_file", "");
  const std::string layout_file = param<std::string>(pn, "layout_file", "");
  const std::string where = pn.getNamespace();
  if (!kind.empty() && !find_target_kind(kind)) {
    throw HandEyeError(ErrorCode::MalformedFile, "~target is `" + kind + "`", where,
                       "use " + target_kind_names() + " (and ~target_file for all but apriltag)");
  }
  Target target;
  if (!target_file.empty()) {
    target = io::read_target(target_file);
  } else if (!layout_file.empty()) {
    target = make_target(io::read_tag_layout(layout_file));
  } else if (kind.empty() || kind == "apriltag") {
    target = make_target(single_tag_layout(param(pn, "tag_id", 0), param(pn, "tag_size", 0.1),
                                           param<std::string>(pn, "family", "tag36h11")));
  } else {
    throw HandEyeError(ErrorCode::MissingKey, "~target is " + kind + " but no ~target_file is given", where,
                       "give target_file:=<YAML>, e.g. {type: " + kind + ", ...} (docs/targets.md)");
  }
  if (!kind.empty() && target.kind_name() != kind) {
    throw HandEyeError(ErrorCode::MalformedFile,
                       "~target is " + kind + " but " + (target_file.empty() ? layout_file : target_file) + " holds " +
                           target.describe(),
                       where, "set target:=" + target.kind_name() + ", or give the " + kind + " target file");
  }
  return target;
}

}  // namespace handeye
