#include "handeye_covariance/motion/arm.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include <kdl/chain.hpp>
#include <kdl/chainiksolverpos_lma.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>
#include <urdf_parser/urdf_parser.h>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/lie.h"

namespace handeye::motion {
namespace {

Eigen::Isometry3d to_eigen(const KDL::Frame& f) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) T.linear()(r, c) = f.M(r, c);
    T.translation()(r) = f.p(r);
  }
  return T;
}

KDL::Frame to_kdl(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d& R = T.linear();
  return KDL::Frame(KDL::Rotation(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)),
                    KDL::Vector(T.translation().x(), T.translation().y(), T.translation().z()));
}

Eigen::Isometry3d to_eigen(const urdf::Pose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return T;
}

std::vector<Shape> link_shapes(const urdf::Link& link, const std::string& where) {
  std::vector<Shape> shapes;
  std::vector<urdf::CollisionSharedPtr> collisions = link.collision_array;
  if (collisions.empty() && link.collision) collisions.push_back(link.collision);
  for (const auto& collision : collisions) {
    if (!collision || !collision->geometry) continue;
    Shape shape;
    shape.T_link_shape = to_eigen(collision->origin);
    switch (collision->geometry->type) {
      case urdf::Geometry::BOX: {
        const auto& box = static_cast<const urdf::Box&>(*collision->geometry);
        shape.kind = Shape::Kind::Box;
        shape.size = Eigen::Vector3d(box.dim.x, box.dim.y, box.dim.z);
        break;
      }
      case urdf::Geometry::CYLINDER: {
        const auto& cylinder = static_cast<const urdf::Cylinder&>(*collision->geometry);
        shape.kind = Shape::Kind::Cylinder;
        shape.size = Eigen::Vector3d(cylinder.radius, cylinder.length, 0.0);
        break;
      }
      case urdf::Geometry::SPHERE: {
        const auto& sphere = static_cast<const urdf::Sphere&>(*collision->geometry);
        shape.kind = Shape::Kind::Sphere;
        shape.size = Eigen::Vector3d(sphere.radius, 0.0, 0.0);
        break;
      }
      default:
        throw HandEyeError(ErrorCode::MalformedFile,
                           "link '" + link.name + "' has mesh collision geometry, which the view planner does not check",
                           where,
                           "give the link box, cylinder or sphere collision elements that enclose the mesh (a URDF "
                           "link may have several), or a robot_description for planning with them");
    }
    shapes.push_back(shape);
  }
  return shapes;
}

}  // namespace

Arm::Arm() : chain_(std::make_unique<KDL::Chain>()) {}
Arm::Arm(const Arm& other)
    : chain_(std::make_unique<KDL::Chain>(*other.chain_)),
      limits_(other.limits_),
      bodies_(other.bodies_),
      base_link_(other.base_link_),
      tip_link_(other.tip_link_) {}
Arm& Arm::operator=(const Arm& other) {
  if (this != &other) *this = Arm(other);
  return *this;
}
Arm::Arm(Arm&&) noexcept = default;
Arm& Arm::operator=(Arm&&) noexcept = default;
Arm::~Arm() = default;

Arm Arm::from_urdf(const std::string& text, const std::string& base_link, const std::string& tip_link,
                   const std::string& where) {
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(text);
  if (!model)
    throw HandEyeError(ErrorCode::MalformedFile, "the robot description is not a URDF that urdfdom can parse", where,
                       "check it with `check_urdf` (liburdfdom-tools) and pass the robot's URDF text");
  for (const std::string& link : {base_link, tip_link}) {
    if (!model->getLink(link))
      throw HandEyeError(ErrorCode::MissingKey, "the URDF of '" + model->getName() + "' has no link '" + link + "'",
                         where, "set the session's base and effector frames to links of the URDF");
  }
  // KDL would also build a chain that climbs the tree (reversed segments, whose
  // axes and limits flip): the base must be an ancestor of the tip.
  std::vector<std::string> chain_links{tip_link};
  for (urdf::LinkConstSharedPtr link = model->getLink(tip_link); link->name != base_link;) {
    link = link->getParent();
    if (!link)
      throw HandEyeError(ErrorCode::MalformedFile,
                         "'" + base_link + "' is not an ancestor of '" + tip_link + "' in the URDF", where,
                         "give the robot's base link as the base frame and a link below it as the effector frame");
    chain_links.push_back(link->name);
  }
  KDL::Tree tree;
  if (!kdl_parser::treeFromUrdfModel(*model, tree))
    throw HandEyeError(ErrorCode::MalformedFile, "kdl_parser could not build a kinematic tree from the URDF", where,
                       "check the URDF's joints (every joint needs a parent and a child link)");
  Arm arm;
  arm.base_link_ = base_link;
  arm.tip_link_ = tip_link;
  if (!tree.getChain(base_link, tip_link, *arm.chain_) || arm.chain_->getNrOfJoints() == 0)
    throw HandEyeError(ErrorCode::MalformedFile,
                       "no chain with a movable joint from '" + base_link + "' to '" + tip_link + "' in the URDF", where,
                       "the base frame must be an ancestor of the effector frame in the URDF");

  // A body's shapes: its link's, and those of the links fixed below it off the
  // chain (a camera or a gripper bolted on), placed by their joints' origins.
  auto body_shapes = [&](const std::string& name) {
    std::vector<Shape> shapes;
    std::function<void(const urdf::Link&, const Eigen::Isometry3d&)> add = [&](const urdf::Link& link,
                                                                              const Eigen::Isometry3d& T_body_link) {
      for (Shape shape : link_shapes(link, where)) {
        shape.T_link_shape = T_body_link * shape.T_link_shape;
        shapes.push_back(shape);
      }
      for (const urdf::JointSharedPtr& joint : link.child_joints) {
        if (joint->type != urdf::Joint::FIXED) continue;
        if (std::find(chain_links.begin(), chain_links.end(), joint->child_link_name) != chain_links.end()) continue;
        add(*model->getLink(joint->child_link_name), T_body_link * to_eigen(joint->parent_to_joint_origin_transform));
      }
    };
    add(*model->getLink(name), Eigen::Isometry3d::Identity());
    return shapes;
  };
  Body base;
  base.name = base_link;
  base.shapes = body_shapes(base_link);
  arm.bodies_.push_back(base);
  int movable = 0;
  for (unsigned i = 0; i < arm.chain_->getNrOfSegments(); ++i) {
    const KDL::Segment& segment = arm.chain_->getSegment(i);
    const KDL::Joint& joint = segment.getJoint();
    if (joint.getType() != KDL::Joint::Fixed) {
      const urdf::JointConstSharedPtr urdf_joint = model->getJoint(joint.getName());
      JointLimit limit;
      limit.name = joint.getName();
      if (urdf_joint->type == urdf::Joint::CONTINUOUS) {
        limit.lower = -2.0 * M_PI, limit.upper = 2.0 * M_PI;
        limit.velocity = urdf_joint->limits ? urdf_joint->limits->velocity : 0.0;
      } else if (urdf_joint->limits && urdf_joint->limits->upper > urdf_joint->limits->lower) {
        limit.lower = urdf_joint->limits->lower, limit.upper = urdf_joint->limits->upper;
        limit.velocity = urdf_joint->limits->velocity;
      } else {
        throw HandEyeError(ErrorCode::MissingKey, "joint '" + limit.name + "' has no position limits", where,
                           "give it <limit lower=... upper=... velocity=...>");
      }
      if (!(limit.velocity > 0.0))
        throw HandEyeError(ErrorCode::MissingKey, "joint '" + limit.name + "' has no velocity limit", where,
                           "give its <limit> a velocity (rad/s): trajectories are timed from it");
      arm.limits_.push_back(limit);
      ++movable;
    }
    Body body;
    body.name = segment.getName();
    body.segment = static_cast<int>(i) + 1;
    body.joints_before = movable;
    body.shapes = body_shapes(body.name);
    arm.bodies_.push_back(body);
  }
  return arm;
}

void Arm::attach(const std::string& link, const Shape& shape) {
  for (Body& body : bodies_) {
    if (body.name == link) {
      body.shapes.push_back(shape);
      return;
    }
  }
  throw HandEyeError(ErrorCode::MissingKey, "the arm has no link '" + link + "' between '" + base_link_ + "' and '" +
                                                tip_link_ + "'",
                     "Arm::attach", "attach the shape to a link of the chain");
}

Eigen::Isometry3d Arm::forward(const Eigen::VectorXd& q) const { return body_poses(q).back(); }

std::vector<Eigen::Isometry3d> Arm::body_poses(const Eigen::VectorXd& q) const {
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(bodies_.size());
  KDL::Frame T = KDL::Frame::Identity();
  poses.push_back(Eigen::Isometry3d::Identity());
  int j = 0;
  for (unsigned i = 0; i < chain_->getNrOfSegments(); ++i) {
    const KDL::Segment& segment = chain_->getSegment(i);
    const bool movable = segment.getJoint().getType() != KDL::Joint::Fixed;
    T = T * segment.pose(movable ? q(j++) : 0.0);
    poses.push_back(to_eigen(T));
  }
  return poses;
}

std::vector<double> Arm::reach() const {
  auto extent = [](const Shape& shape) {
    const double half = shape.kind == Shape::Kind::Box        ? 0.5 * shape.size.norm()
                        : shape.kind == Shape::Kind::Cylinder ? std::hypot(shape.size(0), 0.5 * shape.size(1))
                                                              : shape.size(0);
    return shape.T_link_shape.translation().norm() + half;
  };
  auto prismatic = [](const KDL::Joint& joint) {
    return joint.getType() == KDL::Joint::TransAxis || joint.getType() == KDL::Joint::TransX ||
           joint.getType() == KDL::Joint::TransY || joint.getType() == KDL::Joint::TransZ;
  };
  // KDL puts segment i's joint axis through its child body's origin (body i + 1).
  // From the tip: D bounds the distance from body i + 1's origin of every shape at
  // or after it; `carried` is segment i + 1's length plus D of body i + 2.
  std::vector<double> reach(joints(), 0.0);
  double carried = 0.0;
  int j = joints();
  for (int i = static_cast<int>(chain_->getNrOfSegments()) - 1; i >= 0; --i) {
    const KDL::Segment& segment = chain_->getSegment(i);
    double D = carried;
    for (const Shape& shape : bodies_[i + 1].shapes) D = std::max(D, extent(shape));
    const KDL::Joint& joint = segment.getJoint();
    double length = segment.pose(0.0).p.Norm();  // the same at every angle of a revolute joint
    if (joint.getType() != KDL::Joint::Fixed) {
      --j;
      reach[j] = prismatic(joint) ? 1.0 : D;
      if (prismatic(joint)) length += std::max(std::abs(limits_[j].lower), std::abs(limits_[j].upper));
    }
    carried = length + D;
  }
  return reach;
}

double largest_joint_change(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

std::vector<Eigen::VectorXd> Arm::inverse(const Eigen::Isometry3d& T_base_tip, const Eigen::VectorXd& near,
                                          int seeds, Rng& rng) const {
  // Weights 1 on metres and radians; solved to rounding, then checked to 1e-6 below.
  KDL::ChainIkSolverPos_LMA solver(*chain_, Eigen::Matrix<double, 6, 1>::Ones(), 1e-12, 500);
  const KDL::Frame goal = to_kdl(T_base_tip);
  const int n = joints();
  std::vector<Eigen::VectorXd> found;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int attempt = 0; attempt <= seeds; ++attempt) {
    KDL::JntArray start(n), result(n);
    for (int j = 0; j < n; ++j) {
      start(j) = attempt == 0 ? near(j) : limits_[j].lower + unit(rng) * (limits_[j].upper - limits_[j].lower);
    }
    if (solver.CartToJnt(start, goal, result) < 0) continue;
    Eigen::VectorXd q = result.data;
    // The same posture nearest the current joints: 2 pi turns within the limits.
    for (int j = 0; j < n; ++j) {
      const double nearest = q(j) + 2.0 * M_PI * std::round((near(j) - q(j)) / (2.0 * M_PI));
      double best = nearest;
      bool best_inside = false;
      for (const double candidate : {nearest, nearest - 2.0 * M_PI, nearest + 2.0 * M_PI}) {
        const bool inside = candidate >= limits_[j].lower && candidate <= limits_[j].upper;
        if (inside && (!best_inside || std::abs(candidate - near(j)) < std::abs(best - near(j)))) {
          best = candidate;
          best_inside = true;
        }
      }
      q(j) = best;
    }
    // Keep only true solutions (the solver may stop at a local minimum).
    const Eigen::Isometry3d reached = forward(q);
    if ((reached.translation() - T_base_tip.translation()).norm() > 1e-6 ||
        so3::log(reached.linear() * T_base_tip.linear().transpose()).norm() > 1e-6)
      continue;
    bool known = false;
    for (const Eigen::VectorXd& other : found) known = known || largest_joint_change(q, other) < 1e-3;
    if (!known) found.push_back(q);
  }
  std::sort(found.begin(), found.end(), [&](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    return largest_joint_change(a, near) < largest_joint_change(b, near);
  });
  return found;
}

}  // namespace handeye::motion
