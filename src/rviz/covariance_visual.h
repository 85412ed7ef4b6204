// The Ogre objects that draw one calibration: a position ellipsoid, three
// orientation discs and a label, under a scene node placed at the parent frame.
#pragma once

#include <rviz/ogre_helpers/movable_text.h>
#include <rviz/ogre_helpers/shape.h>

#include <memory>

#include "covariance_property.h"
#include "handeye_covariance/core/ellipsoid.h"

namespace Ogre {
class SceneManager;
class SceneNode;
}  // namespace Ogre

namespace handeye {
namespace rviz_plugin {

class CalibrationCovarianceVisual {
 public:
  CalibrationCovarianceVisual(Ogre::SceneManager* scene_manager, Ogre::SceneNode* parent);
  ~CalibrationCovarianceVisual();

  /// Where the message's parent frame is, in the fixed frame.
  void set_frame(const Ogre::Vector3& position, const Ogre::Quaternion& orientation);
  /// X and its covariance in the parent frame. Throws HandEyeError for an
  /// invalid covariance (before anything is changed).
  void update(const PoseWithCovariance& X, const CalibrationCovarianceProperty& property);
  void set_visible(bool visible);

 private:
  Ogre::SceneManager* scene_manager_;
  Ogre::SceneNode* frame_node_;
  std::unique_ptr<rviz::Shape> position_;
  std::array<std::unique_ptr<rviz::Shape>, 3> discs_;
  std::unique_ptr<rviz::MovableText> label_;
  Ogre::SceneNode* label_node_;
};

}  // namespace rviz_plugin
}  // namespace handeye
