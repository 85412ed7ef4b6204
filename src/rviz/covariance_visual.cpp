#include "covariance_visual.h"

#include <OgreSceneManager.h>
#include <OgreSceneNode.h>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/ros/covariance_markers.h"

namespace handeye {
namespace rviz_plugin {

namespace {
Ogre::Vector3 ogre(const Eigen::Vector3d& v) { return {float(v.x()), float(v.y()), float(v.z())}; }
Ogre::Quaternion ogre(const Eigen::Quaterniond& q) { return {float(q.w()), float(q.x()), float(q.y()), float(q.z())}; }

void place(rviz::Shape& shape, const Ellipsoid& e, const Eigen::Vector3d& center) {
  shape.setPosition(ogre(center));
  shape.setOrientation(ogre(e.orientation()));
  // A rank-deficient axis still shows as a thin disc.
  shape.setScale(ogre(Eigen::Vector3d((2.0 * e.radii).cwiseMax(1e-4))));
}
}  // namespace

CalibrationCovarianceVisual::CalibrationCovarianceVisual(Ogre::SceneManager* scene_manager, Ogre::SceneNode* parent)
    : scene_manager_(scene_manager), frame_node_(parent->createChildSceneNode()) {
  position_ = std::make_unique<rviz::Shape>(rviz::Shape::Sphere, scene_manager_, frame_node_);
  for (auto& disc : discs_) disc = std::make_unique<rviz::Shape>(rviz::Shape::Sphere, scene_manager_, frame_node_);
  label_node_ = frame_node_->createChildSceneNode();
  label_ = std::make_unique<rviz::MovableText>("", "Liberation Sans", 0.025f);
  label_->setTextAlignment(rviz::MovableText::H_CENTER, rviz::MovableText::V_BELOW);
  label_node_->attachObject(label_.get());
}

CalibrationCovarianceVisual::~CalibrationCovarianceVisual() {
  label_node_->detachAllObjects();
  position_.reset();
  for (auto& disc : discs_) disc.reset();
  scene_manager_->destroySceneNode(label_node_);
  scene_manager_->destroySceneNode(frame_node_);
}

void CalibrationCovarianceVisual::set_frame(const Ogre::Vector3& position, const Ogre::Quaternion& orientation) {
  frame_node_->setPosition(position);
  frame_node_->setOrientation(orientation);
}

void CalibrationCovarianceVisual::update(const PoseWithCovariance& X, const CalibrationCovarianceProperty& p) {
  // All geometry first: an invalid covariance throws before anything is drawn.
  const Eigen::Vector3d origin = X.pose.translation();
  const double drawn_sigmas = p.sigmas() * p.magnify();
  const Ellipsoid position = ellipsoid_from_covariance(X.covariance.topLeftCorner<3, 3>(), drawn_sigmas);
  std::array<Ellipsoid, 3> discs;
  std::array<Eigen::Vector3d, 3> tips;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d axis = p.orientation_frame() == CalibrationCovarianceProperty::Frame::Local
                                     ? Eigen::Vector3d(X.pose.linear().col(k))
                                     : Eigen::Vector3d::Unit(k);
    discs[k] = ellipsoid_from_covariance(
        axis_tip_covariance(X.covariance.bottomRightCorner<3, 3>(), axis, p.axis_length()), drawn_sigmas);
    tips[k] = origin + p.axis_length() * axis;
  }

  place(*position_, position, origin);
  const QColor c = p.position_color();
  position_->setColor(c.redF(), c.greenF(), c.blueF(), p.alpha());
  position_->getRootNode()->setVisible(p.position_enabled());
  const std::array<Ogre::ColourValue, 3> colours = {Ogre::ColourValue(1, 0, 0), Ogre::ColourValue(0, 1, 0),
                                                    Ogre::ColourValue(0, 0, 1)};
  for (int k = 0; k < 3; ++k) {
    place(*discs_[k], discs[k], tips[k]);
    discs_[k]->setColor(colours[k].r, colours[k].g, colours[k].b, p.alpha());
    discs_[k]->getRootNode()->setVisible(p.orientation_enabled());
  }
  std::string caption = sigma_label(X) + " (ellipsoids " + number_text(p.sigmas(), 2) + " sigma";
  caption += p.magnify() > 1.0f ? ", drawn x" + number_text(p.magnify(), 3) + ")" : ")";
  label_->setCaption(caption);
  label_node_->setPosition(ogre(Eigen::Vector3d(origin + Eigen::Vector3d(0, -0.6 * p.axis_length(), 0.5 * p.axis_length()))));
  label_node_->setVisible(p.label_enabled());
}

void CalibrationCovarianceVisual::set_visible(bool visible) { frame_node_->setVisible(visible); }

}  // namespace rviz_plugin
}  // namespace handeye
