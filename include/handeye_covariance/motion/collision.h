// Collision checks for the view planner: the arm's own geometry (self-collision)
// and declared obstacles, by FCL on primitives. What is not declared is not
// checked: docs/motion.md says so.
//
// Padding: every moving shape of the arm is grown by `padding` (m). A joint-space
// path sampled so that no point of the arm moves more than 2 * padding between
// samples (view_planner.h) then clears the unpadded geometry everywhere along it:
// a point between two samples is within `padding` of where it was at one of them.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "handeye_covariance/motion/arm.h"

namespace handeye::motion {

/// A fixed obstacle in the arm's base frame.
struct Obstacle {
  enum class Kind { Box, Cylinder, Sphere, Plane };
  std::string name;
  Kind kind = Kind::Box;
  /// As Shape::size; unused for a plane.
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  /// T_base_obstacle. A plane is the half-space below its frame's x-y plane
  /// (the side its z axis points away from).
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

/// The default world: a table, the half-space below the base frame's x-y plane.
std::vector<Obstacle> table_plane();

/// An obstacles file (YAML):
///   obstacles:
///     - {name: table, type: plane, xyz: [0, 0, 0], rpy: [0, 0, 0]}
///     - {name: fixture, type: box, size: [0.3, 0.2, 0.1], xyz: [0.5, 0, 0.05]}
///     - {name: post, type: cylinder, radius: 0.05, length: 1.0, xyz: [...], rpy: [...]}
///     - {name: lamp, type: sphere, radius: 0.1, xyz: [...]}
/// in the arm's base frame, metres and radians (rpy: fixed-axis roll, pitch, yaw as
/// in URDF). Throws HandEyeError naming the file and the entry.
std::vector<Obstacle> read_obstacles(const std::string& path);
std::vector<Obstacle> parse_obstacles(const std::string& yaml_text, const std::string& where);

struct Contact {
  std::string first, second;  // body or obstacle names
  std::string text() const { return first + " touches " + second; }
};

struct CollisionOptions {
  double padding = 0.005;  // m, on every moving shape of the arm
  /// Self-collision pairs in contact in every one of this many random
  /// configurations are always touching (a joint's housing over its neighbour's),
  /// as MoveIt's setup assistant finds them, and are not checked.
  int always_touching_samples = 400;
  unsigned seed = 1;
};

class CollisionModel {
 public:
  /// Throws HandEyeError when the padding is not positive (the path check's
  /// guarantee rests on it).
  CollisionModel(const Arm& arm, std::vector<Obstacle> obstacles, const CollisionOptions& options = {});
  CollisionModel(const CollisionModel&) = delete;
  CollisionModel& operator=(const CollisionModel&) = delete;
  ~CollisionModel();

  /// The first contact at joints q, if any (not thread-safe: it moves the
  /// model's FCL objects): obstacles against every body that
  /// moves, and body pairs not adjacent (parent and child links in the URDF),
  /// rigidly joined (no movable joint between) or always touching.
  std::optional<Contact> contact(const Eigen::VectorXd& q) const;

  /// The body pairs checked against each other, and those left out with why.
  const std::vector<std::pair<int, int>>& checked_pairs() const { return checked_pairs_; }
  const std::vector<std::string>& unchecked_pairs() const { return unchecked_pairs_; }
  const std::vector<Obstacle>& obstacles() const { return obstacles_; }
  /// The arm it checks (with whatever was attached before the model was made).
  const Arm& arm() const { return arm_; }
  double padding() const { return options_.padding; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Arm arm_;
  std::vector<Obstacle> obstacles_;
  CollisionOptions options_;
  std::vector<std::pair<int, int>> checked_pairs_;
  std::vector<std::string> unchecked_pairs_;
};

}  // namespace handeye::motion
