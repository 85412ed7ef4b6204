#include "handeye_covariance/motion/collision.h"

#include <fstream>
#include <sstream>

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/halfspace.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>
#include <yaml-cpp/yaml.h>

#include "handeye_covariance/core/errors.h"

namespace handeye::motion {
namespace {

std::shared_ptr<fcl::CollisionGeometryd> geometry(Shape::Kind kind, const Eigen::Vector3d& size, double padding) {
  switch (kind) {
    case Shape::Kind::Box:
      return std::make_shared<fcl::Boxd>(size + Eigen::Vector3d::Constant(2.0 * padding));
    case Shape::Kind::Cylinder:
      return std::make_shared<fcl::Cylinderd>(size(0) + padding, size(1) + 2.0 * padding);
    case Shape::Kind::Sphere:
      return std::make_shared<fcl::Sphered>(size(0) + padding);
  }
  return nullptr;
}

Eigen::Isometry3d pose_from(const YAML::Node& entry, const std::string& where) {
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero(), rpy = Eigen::Vector3d::Zero();
  for (const auto& [key, value] : {std::pair<const char*, Eigen::Vector3d*>{"xyz", &xyz}, {"rpy", &rpy}}) {
    if (!entry[key]) continue;
    if (!entry[key].IsSequence() || entry[key].size() != 3)
      throw HandEyeError(ErrorCode::WrongLength, std::string("'") + key + "' must be 3 numbers", where,
                         std::string("write ") + key + ": [a, b, c]");
    for (int k = 0; k < 3; ++k) (*value)(k) = entry[key][k].as<double>();
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  // URDF's rpy: fixed axes x, then y, then z: R = Rz(yaw) Ry(pitch) Rx(roll).
  T.linear() = (Eigen::AngleAxisd(rpy(2), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy(1), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rpy(0), Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = xyz;
  return T;
}

double positive(const YAML::Node& entry, const char* key, const std::string& where) {
  if (!entry[key])
    throw HandEyeError(ErrorCode::MissingKey, std::string("no '") + key + "'", where,
                       std::string("give the obstacle's ") + key + " in metres");
  const double value = entry[key].as<double>();
  if (!(value > 0.0) || !std::isfinite(value))
    throw HandEyeError(ErrorCode::MalformedFile, std::string("'") + key + "' must be a positive length", where,
                       "give it in metres");
  return value;
}

}  // namespace

std::vector<Obstacle> table_plane() {
  Obstacle table;
  table.name = "table";
  table.kind = Obstacle::Kind::Plane;
  return {table};
}

std::vector<Obstacle> parse_obstacles(const std::string& text, const std::string& where) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw HandEyeError(ErrorCode::MalformedFile, std::string("not YAML: ") + e.what(), where,
                       "see docs/motion.md for the obstacles file's format");
  }
  if (!root || !root["obstacles"] || !root["obstacles"].IsSequence())
    throw HandEyeError(ErrorCode::MissingKey, "no 'obstacles' list", where,
                       "write obstacles: [ {name: table, type: plane}, ... ] (an empty list declares none)");
  std::vector<Obstacle> obstacles;
  int index = 0;
  for (const YAML::Node& entry : root["obstacles"]) {
    const std::string at = where + ": obstacles[" + std::to_string(index++) + "]";
    try {
      Obstacle o;
      o.name = entry["name"] ? entry["name"].as<std::string>() : "obstacle " + std::to_string(index - 1);
      const std::string type = entry["type"] ? entry["type"].as<std::string>() : "";
      if (type == "box") {
        o.kind = Obstacle::Kind::Box;
        if (!entry["size"] || !entry["size"].IsSequence() || entry["size"].size() != 3)
          throw HandEyeError(ErrorCode::WrongLength, "a box needs 'size: [x, y, z]'", at, "give its full sizes in metres");
        for (int k = 0; k < 3; ++k) o.size(k) = entry["size"][k].as<double>();
        if (!(o.size.minCoeff() > 0.0) || !o.size.allFinite())
          throw HandEyeError(ErrorCode::MalformedFile, "a box's sizes must be positive", at, "give them in metres");
      } else if (type == "cylinder") {
        o.kind = Obstacle::Kind::Cylinder;
        o.size = Eigen::Vector3d(positive(entry, "radius", at), positive(entry, "length", at), 0.0);
      } else if (type == "sphere") {
        o.kind = Obstacle::Kind::Sphere;
        o.size = Eigen::Vector3d(positive(entry, "radius", at), 0.0, 0.0);
      } else if (type == "plane") {
        o.kind = Obstacle::Kind::Plane;
      } else {
        throw HandEyeError(ErrorCode::MalformedFile, "unknown type '" + type + "'", at,
                           "use one of: box, cylinder, sphere, plane");
      }
      o.pose = pose_from(entry, at);
      obstacles.push_back(o);
    } catch (const YAML::Exception& e) {
      throw HandEyeError(ErrorCode::MalformedFile, std::string("a value of the wrong type: ") + e.what(), at,
                         "numbers in metres and radians, names as text");
    }
  }
  return obstacles;
}

std::vector<Obstacle> read_obstacles(const std::string& path) {
  std::ifstream in(path);
  if (!in)
    throw HandEyeError(ErrorCode::IoError, "cannot open the obstacles file", path,
                       "give an existing file (config/obstacles.yaml is an example)");
  std::stringstream text;
  text << in.rdbuf();
  return parse_obstacles(text.str(), path);
}

struct CollisionModel::Impl {
  struct Part {
    int body;
    Eigen::Isometry3d T_body_shape;
    std::unique_ptr<fcl::CollisionObjectd> object;
  };
  std::vector<Part> parts;                       // the arm's shapes
  std::vector<std::vector<int>> parts_of_body;   // indices into parts
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> obstacles;

  void place(const std::vector<Eigen::Isometry3d>& body_poses) {
    for (Part& part : parts) {
      part.object->setTransform(body_poses[part.body] * part.T_body_shape);
      part.object->computeAABB();
    }
  }
  bool touch(const fcl::CollisionObjectd& a, const fcl::CollisionObjectd& b) const {
    fcl::CollisionRequestd request;
    fcl::CollisionResultd result;
    return fcl::collide(&a, &b, request, result) > 0;
  }
  bool bodies_touch(int a, int b) const {
    for (int i : parts_of_body[a])
      for (int j : parts_of_body[b])
        if (touch(*parts[i].object, *parts[j].object)) return true;
    return false;
  }
};

CollisionModel::CollisionModel(const Arm& arm, std::vector<Obstacle> obstacles, const CollisionOptions& options)
    : impl_(std::make_unique<Impl>()), arm_(arm), obstacles_(std::move(obstacles)), options_(options) {
  if (!(options_.padding > 0.0) || !std::isfinite(options_.padding))
    throw HandEyeError(ErrorCode::MalformedFile, "the collision padding " + number_text(options_.padding) + " m is not positive",
                       "CollisionOptions::padding",
                       "give a positive padding (default 0.005 m): paths are checked at twice its spacing");
  const std::vector<Body>& bodies = arm_.bodies();
  impl_->parts_of_body.resize(bodies.size());
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const double padding = bodies[b].joints_before > 0 ? options_.padding : 0.0;
    for (const Shape& shape : bodies[b].shapes) {
      impl_->parts_of_body[b].push_back(static_cast<int>(impl_->parts.size()));
      impl_->parts.push_back({static_cast<int>(b), shape.T_link_shape,
                              std::make_unique<fcl::CollisionObjectd>(geometry(shape.kind, shape.size, padding))});
    }
  }
  for (const Obstacle& o : obstacles_) {
    std::shared_ptr<fcl::CollisionGeometryd> g =
        o.kind == Obstacle::Kind::Plane
            ? std::make_shared<fcl::Halfspaced>(Eigen::Vector3d::UnitZ(), 0.0)
            : geometry(o.kind == Obstacle::Kind::Box        ? Shape::Kind::Box
                       : o.kind == Obstacle::Kind::Cylinder ? Shape::Kind::Cylinder
                                                            : Shape::Kind::Sphere,
                       o.size, 0.0);
    auto object = std::make_unique<fcl::CollisionObjectd>(g, o.pose);
    object->computeAABB();
    impl_->obstacles.push_back(std::move(object));
  }

  // Pairs to check: not rigidly joined, not adjacent, and not always touching.
  std::vector<std::pair<int, int>> candidates;
  for (std::size_t a = 0; a < bodies.size(); ++a) {
    for (std::size_t b = a + 1; b < bodies.size(); ++b) {
      if (impl_->parts_of_body[a].empty() || impl_->parts_of_body[b].empty()) continue;
      // Rigidly joined: no movable joint between them. Adjacent: parent and child links
      // in the URDF (consecutive bodies of the chain), as MoveIt leaves them out.
      const bool rigid = bodies[a].joints_before == bodies[b].joints_before;
      if (rigid || b == a + 1) {
        unchecked_pairs_.push_back(bodies[a].name + " / " + bodies[b].name + (rigid ? ": rigidly joined" : ": adjacent"));
        continue;
      }
      candidates.emplace_back(static_cast<int>(a), static_cast<int>(b));
    }
  }
  std::vector<int> touching(candidates.size(), 0);
  Rng rng(options_.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Eigen::VectorXd q(arm_.joints());
  for (int s = 0; s < options_.always_touching_samples; ++s) {
    for (int j = 0; j < arm_.joints(); ++j)
      q(j) = arm_.limits()[j].lower + unit(rng) * (arm_.limits()[j].upper - arm_.limits()[j].lower);
    impl_->place(arm_.body_poses(q));
    for (std::size_t k = 0; k < candidates.size(); ++k)
      touching[k] += impl_->bodies_touch(candidates[k].first, candidates[k].second);
  }
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    if (options_.always_touching_samples > 0 && touching[k] == options_.always_touching_samples) {
      unchecked_pairs_.push_back(bodies[candidates[k].first].name + " / " + bodies[candidates[k].second].name +
                                 ": always touching");
    } else {
      checked_pairs_.push_back(candidates[k]);
    }
  }
}

CollisionModel::~CollisionModel() = default;

std::optional<Contact> CollisionModel::contact(const Eigen::VectorXd& q) const {
  impl_->place(arm_.body_poses(q));
  const std::vector<Body>& bodies = arm_.bodies();
  for (const auto& part : impl_->parts) {
    if (bodies[part.body].joints_before == 0) continue;  // a fixed body meets a fixed obstacle the same everywhere
    for (std::size_t o = 0; o < impl_->obstacles.size(); ++o)
      if (impl_->touch(*part.object, *impl_->obstacles[o])) return Contact{bodies[part.body].name, obstacles_[o].name};
  }
  for (const auto& [a, b] : checked_pairs_)
    if (impl_->bodies_touch(a, b)) return Contact{bodies[a].name, bodies[b].name};
  return std::nullopt;
}

}  // namespace handeye::motion
