// The view planner on the simulated arm (urdf/sim_arm.urdf): kinematics against
// the UR5's published DH parameters, the reach bound, collision checks, and
// seeded planning runs whose commanded trajectories this test checks with its
// own FCL queries on the unpadded geometry.
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/halfspace.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>
#include <gtest/gtest.h>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/motion/move_monitor.h"
#include "handeye_covariance/motion/auto_calibration.h"
#include "handeye_covariance/simulation/arm_rig.h"

using namespace handeye;
using namespace handeye::motion;

namespace {

const ArmRig& arm_rig() {
  static const ArmRig rig = ArmRig::load(std::string(HANDEYE_SOURCE_DIR) + "/urdf/sim_arm.urdf");
  return rig;
}

// The bare arm (no camera housing).
const Arm& sim_arm() {
  static const Arm arm = [] {
    std::ifstream in(std::string(HANDEYE_SOURCE_DIR) + "/urdf/sim_arm.urdf");
    std::stringstream text;
    text << in.rdbuf();
    return Arm::from_urdf(text.str(), "base_link", "tool0", "urdf/sim_arm.urdf");
  }();
  return arm;
}

// The UR5's forward kinematics from its published DH table, written out here
// independently of the URDF: T = prod_i Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i).
Eigen::Isometry3d ur5_dh(const Eigen::VectorXd& q) {
  const double d[6] = {0.089159, 0, 0, 0.10915, 0.09465, 0.0823};
  const double a[6] = {0, -0.425, -0.39225, 0, 0, 0};
  const double alpha[6] = {M_PI / 2, 0, 0, M_PI / 2, -M_PI / 2, 0};
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 6; ++i) {
    Eigen::Isometry3d Ti = Eigen::Isometry3d::Identity();
    Ti.rotate(Eigen::AngleAxisd(q(i), Eigen::Vector3d::UnitZ()));
    Ti.translate(Eigen::Vector3d(a[i], 0, d[i]).cwiseProduct(Eigen::Vector3d(0, 0, 1)));
    Ti.translate(Eigen::Vector3d(a[i], 0, 0));
    Ti.rotate(Eigen::AngleAxisd(alpha[i], Eigen::Vector3d::UnitX()));
    T = T * Ti;
  }
  return T;
}

Eigen::VectorXd random_joints(Rng& rng, const Arm& arm, double margin = 0.0) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Eigen::VectorXd q(arm.joints());
  for (int j = 0; j < arm.joints(); ++j) {
    const JointLimit& l = arm.limits()[j];
    q(j) = l.lower + margin + unit(rng) * (l.upper - l.lower - 2 * margin);
  }
  return q;
}

// The test's own collision query: FCL on the unpadded shapes, every pair of
// bodies but parent and child links and links with no movable joint between
// them (MoveIt's "adjacent" rule) and the pairs the model found always touching,
// and every moving body against every obstacle.
struct OwnQuery {
  const Arm& arm;
  std::vector<Obstacle> obstacles;
  std::vector<std::string> always;  // CollisionModel::unchecked_pairs(): "a / b: always touching", ...
  std::string contact(const Eigen::VectorXd& q) const {
    auto object = [](Shape::Kind kind, const Eigen::Vector3d& size, const Eigen::Isometry3d& pose) {
      std::shared_ptr<fcl::CollisionGeometryd> g;
      if (kind == Shape::Kind::Box) g = std::make_shared<fcl::Boxd>(size);
      if (kind == Shape::Kind::Cylinder) g = std::make_shared<fcl::Cylinderd>(size(0), size(1));
      if (kind == Shape::Kind::Sphere) g = std::make_shared<fcl::Sphered>(size(0));
      return fcl::CollisionObjectd(g, pose);
    };
    const auto poses = arm.body_poses(q);
    const auto& bodies = arm.bodies();
    auto hit = [](const fcl::CollisionObjectd& a, const fcl::CollisionObjectd& b) {
      fcl::CollisionRequestd req;
      fcl::CollisionResultd res;
      return fcl::collide(&a, &b, req, res) > 0;
    };
    for (std::size_t a = 0; a < bodies.size(); ++a) {
      for (const Shape& sa : bodies[a].shapes) {
        const auto oa = object(sa.kind, sa.size, poses[a] * sa.T_link_shape);
        if (bodies[a].joints_before > 0) {
          for (const Obstacle& o : obstacles) {
            std::shared_ptr<fcl::CollisionGeometryd> g;
            if (o.kind == Obstacle::Kind::Plane) g = std::make_shared<fcl::Halfspaced>(Eigen::Vector3d::UnitZ(), 0.0);
            if (o.kind == Obstacle::Kind::Box) g = std::make_shared<fcl::Boxd>(o.size);
            if (o.kind == Obstacle::Kind::Cylinder) g = std::make_shared<fcl::Cylinderd>(o.size(0), o.size(1));
            if (o.kind == Obstacle::Kind::Sphere) g = std::make_shared<fcl::Sphered>(o.size(0));
            if (hit(oa, fcl::CollisionObjectd(g, o.pose))) return bodies[a].name + " / " + o.name;
          }
        }
        for (std::size_t b = a + 1; b < bodies.size(); ++b) {
          if (b == a + 1 || bodies[a].joints_before == bodies[b].joints_before) continue;
          const std::string pair = bodies[a].name + " / " + bodies[b].name;
          if (std::find(always.begin(), always.end(), pair + ": always touching") != always.end()) continue;
          for (const Shape& sb : bodies[b].shapes)
            if (hit(oa, object(sb.kind, sb.size, poses[b] * sb.T_link_shape))) return pair;
        }
      }
    }
    return "";
  }
};

}  // namespace

TEST(Arm, ForwardKinematicsIsTheUr5sDhTable) {
  const Arm& arm = sim_arm();
  ASSERT_EQ(arm.joints(), 6);
  Rng rng(3);
  double worst = 0.0;
  for (int k = 0; k < 200; ++k) {
    const Eigen::VectorXd q = random_joints(rng, arm);
    worst = std::max(worst, se3::log(arm.forward(q).inverse() * ur5_dh(q)).norm());
  }
  EXPECT_LT(worst, 1e-9);
}

TEST(Arm, InverseKinematicsReachesAndPrefersTheNearestPosture) {
  const Arm& arm = sim_arm();
  Rng rng(4);
  int solved = 0, nearest_is_truth = 0, postures = 0;
  for (int k = 0; k < 100; ++k) {
    const Eigen::VectorXd truth = random_joints(rng, arm, 0.2);
    const Eigen::Isometry3d T = arm.forward(truth);
    // Start 0.05 rad from the truth: the nearest solution is the truth.
    const Eigen::VectorXd near = truth + Eigen::VectorXd::Constant(6, 0.05);
    const auto solutions = arm.inverse(T, near, 6, rng);
    if (solutions.empty()) continue;
    ++solved;
    postures += static_cast<int>(solutions.size());
    for (const auto& q : solutions) EXPECT_LT(se3::log(arm.forward(q).inverse() * T).norm(), 1e-6);
    nearest_is_truth += largest_joint_change(solutions.front(), truth) < 1e-4;
  }
  EXPECT_EQ(solved, 100);
  EXPECT_EQ(nearest_is_truth, 100);
  EXPECT_GT(postures, 200) << "several postures per pose (a UR5 has up to 8)";
}

TEST(Arm, ReachBoundsHowFarAnyPointMoves) {
  const Arm& arm = arm_rig().arm;
  const std::vector<double> reach = arm.reach();
  Rng rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  double tightest = 0.0;
  for (int k = 0; k < 300; ++k) {
    const Eigen::VectorXd q = random_joints(rng, arm);
    Eigen::VectorXd dq(6);
    for (int j = 0; j < 6; ++j) dq(j) = 0.01 * normal(rng);
    double bound = 0.0;
    for (int j = 0; j < 6; ++j) bound += reach[j] * std::abs(dq(j));
    const auto a = arm.body_poses(q), b = arm.body_poses(q + dq);
    // The shapes' corners and ends (boxes: 8 corners; cylinders: rim points).
    double moved = 0.0;
    for (std::size_t i = 0; i < arm.bodies().size(); ++i) {
      for (const Shape& s : arm.bodies()[i].shapes) {
        for (int c = 0; c < 8; ++c) {
          const Eigen::Vector3d sign((c & 1) ? 1 : -1, (c & 2) ? 1 : -1, (c & 4) ? 1 : -1);
          Eigen::Vector3d p = s.kind == Shape::Kind::Box ? Eigen::Vector3d(0.5 * s.size.cwiseProduct(sign))
                              : s.kind == Shape::Kind::Cylinder
                                  ? Eigen::Vector3d(sign.x() * s.size(0), 0.0, 0.5 * sign.z() * s.size(1))
                                  : Eigen::Vector3d(sign.x() * s.size(0), 0.0, 0.0);
          moved = std::max(moved, ((b[i] * s.T_link_shape * p) - (a[i] * s.T_link_shape * p)).norm());
        }
      }
    }
    ASSERT_LE(moved, bound * (1 + 1e-9));
    tightest = std::max(tightest, moved / bound);
  }
  EXPECT_GT(tightest, 0.3) << "the bound is not uselessly loose";
}

TEST(Collision, TheTableTheArmAndDeclaredObstacles) {
  const Arm& arm = arm_rig().arm;
  // Upright, the forearm level, the flange pointing down: clear.
  Eigen::VectorXd ready(6);
  ready << 0.0, -M_PI / 2, M_PI / 2, -M_PI / 2, -M_PI / 2, 0.0;
  CollisionModel table(arm, table_plane());
  EXPECT_FALSE(table.contact(ready)) << table.contact(ready)->text();
  // The shoulder lifted down through the table.
  Eigen::VectorXd down = ready;
  down(1) = 0.3;
  auto contact = table.contact(down);
  ASSERT_TRUE(contact);
  EXPECT_EQ(contact->second, "table");
  // A box where the flange is.
  const Eigen::Vector3d flange = arm.forward(ready).translation();
  auto box = parse_obstacles("obstacles: [{name: fixture, type: box, size: [0.1, 0.1, 0.1], xyz: [" +
                                 std::to_string(flange.x()) + ", " + std::to_string(flange.y()) + ", " +
                                 std::to_string(flange.z()) + "]}]",
                             "test");
  CollisionModel with_box(arm, box);
  ASSERT_TRUE(with_box.contact(ready));
  EXPECT_EQ(with_box.contact(ready)->second, "fixture");
  // The wrist folded back onto the base: a self-collision, not adjacent.
  Eigen::VectorXd folded(6);
  folded << 0.0, -M_PI / 2, 2.8, -M_PI / 2, -M_PI / 2, 0.0;
  CollisionModel none(arm, {});
  const auto self = none.contact(folded);
  ASSERT_TRUE(self);
  // Adjacent pairs and always-touching pairs are named as not checked.
  bool adjacent = false;
  for (const auto& pair : none.unchecked_pairs()) adjacent = adjacent || pair.find("adjacent") != std::string::npos;
  EXPECT_TRUE(adjacent);
  EXPECT_GE(none.checked_pairs().size(), 8u);
}

// What a URDF may hold beyond the chain, and chains that are not one.
TEST(Arm, FixedLinksBelowTheChainAreItsShapesAndAChainMustGoDown) {
  std::ifstream in(std::string(HANDEYE_SOURCE_DIR) + "/urdf/sim_arm.urdf");
  std::stringstream text;
  text << in.rdbuf();
  std::string urdf = text.str();
  // A camera bolted under tool0, 15 cm out along its z, in a 6 cm box.
  urdf.replace(urdf.rfind("</robot>"), 8,
               "<joint name=\"camera_joint\" type=\"fixed\"><parent link=\"tool0\"/><child link=\"camera_link\"/>"
               "<origin xyz=\"0 0 0.15\"/></joint><link name=\"camera_link\"><collision><geometry>"
               "<box size=\"0.06 0.06 0.06\"/></geometry></collision></link></robot>");
  const Arm arm = Arm::from_urdf(urdf, "base_link", "tool0", "test");
  ASSERT_EQ(arm.bodies().back().name, "tool0");
  ASSERT_EQ(arm.bodies().back().shapes.size(), 1u);
  EXPECT_NEAR(arm.bodies().back().shapes[0].T_link_shape.translation().z(), 0.15, 1e-12);
  EXPECT_GT(arm.reach().back(), 0.15 + 0.05) << "the reach counts the bolted-on box";
  // The camera's box meets an obstacle that the bare arm does not reach.
  const Eigen::VectorXd ready = arm_rig().ready;
  const Eigen::Vector3d box = arm.forward(ready) * Eigen::Vector3d(0, 0, 0.15);
  const auto world = parse_obstacles("obstacles: [{name: post, type: sphere, radius: 0.01, xyz: [" + std::to_string(box.x()) +
                                         ", " + std::to_string(box.y()) + ", " + std::to_string(box.z()) + "]}]",
                                     "test");
  EXPECT_TRUE(CollisionModel(arm, world).contact(ready));
  EXPECT_FALSE(CollisionModel(sim_arm(), world).contact(ready));
  // Up the tree (base below the tip) and a padding of 0 are refused.
  try {
    Arm::from_urdf(urdf, "tool0", "base_link", "test");
    ADD_FAILURE() << "a chain up the tree was accepted";
  } catch (const HandEyeError& e) {
    EXPECT_NE(std::string(e.what()).find("not an ancestor"), std::string::npos) << e.what();
  }
  EXPECT_THROW(CollisionModel(arm, {}, CollisionOptions{0.0, 10, 1}), HandEyeError);
}

TEST(Collision, ObstacleFilesAreCheckedWithTheirEntryNamed) {
  const auto ok = parse_obstacles(
      "obstacles:\n - {name: table, type: plane}\n - {name: post, type: cylinder, radius: 0.05, length: 1, xyz: [0.5, "
      "0.5, 0.5], rpy: [0, 1.5707963, 0]}\n - {name: lamp, type: sphere, radius: 0.1, xyz: [0, 0, 2]}\n",
      "f.yaml");
  ASSERT_EQ(ok.size(), 3u);
  EXPECT_NEAR(ok[1].pose.linear().col(2).x(), 1.0, 1e-6) << "rpy as in URDF: pitch turns z towards x";
  auto code = [](const std::string& text) {
    try {
      parse_obstacles(text, "f.yaml");
    } catch (const HandEyeError& e) {
      return std::string(to_string(e.code())) + ": " + e.what();
    }
    return std::string("accepted");
  };
  EXPECT_NE(code("obstacles: [{type: box, size: [1, 2]}]").find("WrongLength"), std::string::npos);
  EXPECT_NE(code("obstacles: [{type: box, size: [1, 2]}]").find("obstacles[0]"), std::string::npos);
  EXPECT_NE(code("obstacles: [{type: cone}]").find("box, cylinder, sphere, plane"), std::string::npos);
  EXPECT_NE(code("obstacles: [{type: sphere, radius: -1}]").find("positive"), std::string::npos);
  EXPECT_NE(code("boxes: []").find("MissingKey"), std::string::npos);
  EXPECT_NE(code("obstacles: [{type: sphere, radius: x}]").find("MalformedFile"), std::string::npos);
  EXPECT_EQ(code("obstacles: []"), "accepted");
}

TEST(Trajectory, QuinticMoveKeepsToTheSpeedFraction) {
  const Arm& arm = sim_arm();
  Eigen::VectorXd a = Eigen::VectorXd::Zero(6), b = a;
  b(0) = 1.0, b(4) = -0.5;
  const auto points = timed_move(arm, a, b, 0.1);
  ASSERT_GE(points.size(), 3u);
  EXPECT_LT((points.front().position - a).norm(), 1e-12);
  EXPECT_LT((points.back().position - b).norm(), 1e-12);
  EXPECT_LT(points.back().velocity.norm(), 1e-12);
  double peak = 0.0;
  for (const auto& p : points) peak = std::max(peak, std::abs(p.velocity(0)));
  EXPECT_LE(peak, 0.1 * arm.limits()[0].velocity * (1 + 1e-9));
  EXPECT_GT(peak, 0.09 * arm.limits()[0].velocity);
}

namespace {

// A box on the table near the arm; every other one beside the board, where the
// camera's moves pass.
Obstacle random_box(Rng& rng, const Eigen::Vector3d& board, bool beside_board) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Obstacle box;
  box.name = beside_board ? "box beside the board" : "box";
  box.kind = Obstacle::Kind::Box;
  box.size = Eigen::Vector3d(0.05 + 0.2 * unit(rng), 0.05 + 0.2 * unit(rng), 0.1 + 0.4 * unit(rng));
  const double angle = 2 * M_PI * unit(rng);
  const Eigen::Vector3d centre = beside_board ? Eigen::Vector3d(board.x() + 0.3 * std::cos(angle), board.y() + 0.3 * std::sin(angle), 0)
                                              : Eigen::Vector3d((0.3 + 0.5 * unit(rng)) * std::cos(angle),
                                                                (0.3 + 0.5 * unit(rng)) * std::sin(angle), 0);
  box.pose.translation() = centre + Eigen::Vector3d(0, 0, 0.5 * box.size.z());
  box.pose.linear() = Eigen::AngleAxisd(2 * M_PI * unit(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return box;
}

}  // namespace

// 100 seeded runs: random boxes near the arm and a random start view; the plan's
// commanded trajectory is checked here, densely (no joint moves more than 0.002
// rad between checks) on the unpadded geometry with this test's own FCL query.
TEST(ViewPlanner, CommandedMovesStayInLimitsStepsAndFreeSpace) {
  const ArmRig& setup = arm_rig();
  const Arm& arm = setup.arm;
  const PlannerOptions options;
  std::array<int, kRefusals> refused{};
  int planned = 0, outside_limits = 0, in_collision = 0, too_far = 0, checked_configurations = 0, runs = 0;
  for (unsigned seed = 1; runs < 100; ++seed) {
    Rng rng(seed);
    std::vector<Obstacle> world = table_plane();
    std::uniform_int_distribution<int> count(1, 3);
    for (int b = count(rng); b > 0; --b) world.push_back(random_box(rng, setup.Y.translation(), b % 2 == 1));
    CollisionModel model(arm, world);
    const std::optional<Eigen::VectorXd> start = setup.random_start(rng, model, options);
    if (!start) continue;  // the boxes left no start view: draw again
    ++runs;
    std::vector<ViewCandidate> candidates;
    for (int c = 0; c < 150; ++c) candidates.push_back(setup.random_candidate(rng));
    const ViewPlan plan = plan_view(model, setup.rig, std::nullopt, *start, candidates, options);
    for (int r = 0; r < kRefusals; ++r) refused[r] += plan.refused[r];
    if (!plan.found()) continue;
    ++planned;
    EXPECT_LT(se3::log(arm.forward(plan.goal).inverse() * candidates[plan.chosen].T_base_effector).norm(), 1e-6);
    const OwnQuery own{arm, world, model.unchecked_pairs()};
    const auto trajectory = timed_move(arm, *start, plan.goal, 0.1);
    too_far += largest_joint_change(plan.goal, *start) > options.max_joint_step;
    for (std::size_t k = 0; k + 1 < trajectory.size(); ++k) {
      const Eigen::VectorXd& a = trajectory[k].position;
      const Eigen::VectorXd& b = trajectory[k + 1].position;
      const int steps = std::max(1, static_cast<int>(std::ceil(largest_joint_change(a, b) / 0.002)));
      for (int s = 0; s <= steps; ++s) {
        const Eigen::VectorXd q = a + (b - a) * (static_cast<double>(s) / steps);
        ++checked_configurations;
        for (int j = 0; j < 6; ++j)
          outside_limits += q(j) < arm.limits()[j].lower + options.joint_margin - 1e-12 ||
                            q(j) > arm.limits()[j].upper - options.joint_margin + 1e-12;
        const std::string contact = own.contact(q);
        in_collision += !contact.empty();
        if (!contact.empty()) ADD_FAILURE() << "seed " << seed << ": " << contact;
      }
    }
  }
  std::printf("[ planner  ] %d of 100 runs planned a view; %d commanded configurations checked\n", planned,
              checked_configurations);
  std::printf("[ planner  ] outside the limits less the margin: %d, in collision: %d, joint steps above %.0f deg: %d\n",
              outside_limits, in_collision, options.max_joint_step * 180 / M_PI, too_far);
  std::printf("[ planner  ] refused candidates:");
  for (int r = 0; r < kRefusals; ++r) std::printf(" %s %d%s", to_string(static_cast<Refusal>(r)), refused[r],
                                                 r + 1 < kRefusals ? "," : "\n");
  EXPECT_EQ(outside_limits, 0);
  EXPECT_EQ(in_collision, 0);
  EXPECT_EQ(too_far, 0);
  EXPECT_GE(planned, 90);
  // The checks fire: the boxes and the arm refuse some views on the way.
  EXPECT_GT(refused[static_cast<int>(Refusal::CollisionAtGoal)] + refused[static_cast<int>(Refusal::CollisionOnPath)], 0);
}

// Small thin plates (100 x 100 x 2 mm), some grazed, some crossed, some missed, between two free configurations: whenever this test's dense
// query finds a contact on the straight joint-space path, check_path finds one too
// (it samples so that nothing moves more than 2 * padding between checks).
TEST(ViewPlanner, PathCheckMissesNoThinObstacle) {
  const Arm& arm = arm_rig().arm;
  Rng rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int crossing = 0, missed = 0, pairs = 0;
  for (int draws = 0; pairs < 300; ++draws) {
    ASSERT_LT(draws, 3000) << "the draws find no free start and goal";
    Obstacle plate;
    plate.name = "plate";
    plate.kind = Obstacle::Kind::Box;
    plate.size = Eigen::Vector3d(0.002, 0.1, 0.1);
    // Across the sweep of the pan joint, somewhere along the arm at the middle of the move.
    const double angle = 2 * M_PI * unit(rng);
    Eigen::VectorXd middle(6);
    middle << angle, -1.2, 1.2, -1.5, -1.57, 0.0;
    const Eigen::Vector3d flange = arm.forward(middle).translation();
    const Eigen::Vector3d radial = Eigen::Vector3d(flange.x(), flange.y(), 0).normalized();
    plate.pose.translation() = (0.2 + 0.9 * unit(rng)) * Eigen::Vector3d(flange.x(), flange.y(), 0) +
                               Eigen::Vector3d(0, 0, flange.z() + 0.6 * (unit(rng) - 0.5));
    plate.pose.linear().col(0) = Eigen::Vector3d::UnitZ().cross(radial);  // the plate's normal: along the sweep
    plate.pose.linear().col(1) = radial;
    plate.pose.linear().col(2) = Eigen::Vector3d::UnitZ();
    const std::vector<Obstacle> world{plate};
    CollisionModel model(arm, world);
    Eigen::VectorXd a = middle, b = middle;
    a(0) -= 0.6, b(0) += 0.6;
    for (int j = 1; j < 6; ++j) b(j) += 0.3 * (unit(rng) - 0.5), a(j) += 0.3 * (unit(rng) - 0.5);
    if (model.contact(a) || model.contact(b)) continue;
    ++pairs;
    const OwnQuery own{arm, world, model.unchecked_pairs()};
    bool hits = false;
    const int steps = static_cast<int>(std::ceil(largest_joint_change(a, b) / 0.0005));
    for (int s = 0; s <= steps && !hits; ++s) hits = !own.contact(a + (b - a) * (double(s) / steps)).empty();
    crossing += hits;
    missed += hits && !check_path(model, a, b).contact;
  }
  std::printf("[ path     ] %d of %d moves cross a 2 mm plate; check_path missed %d\n", crossing, pairs, missed);
  EXPECT_GT(crossing, 50);
  EXPECT_LT(crossing, 250);
  EXPECT_EQ(missed, 0);
}

// A controller that follows the commanded trajectory (joint states every 10 ms),
// one that stops short, and joint states that stop.
TEST(MoveMonitor, ArrivalTimeoutAndStalledJointStates) {
  const Arm& arm = sim_arm();
  Eigen::VectorXd a = arm_rig().ready, b = a;
  b(0) += 0.5, b(3) -= 0.2;
  const auto trajectory = timed_move(arm, a, b, 0.1);
  const double duration = trajectory.back().time;
  auto follow = [&](double t, double fraction_reached) {
    const double tau = std::min(1.0, t / duration);
    return Eigen::VectorXd(a + std::min(fraction_reached, tau) * (b - a));
  };
  {
    MoveMonitor monitor(trajectory, 100.0);
    double t = 100.0;
    MoveStatus status = MoveStatus::Moving;
    for (; status == MoveStatus::Moving && t < 200.0; t += 0.01) {
      monitor.joint_state(t, follow(t - 100.0, 1.0));
      status = monitor.update(t);
    }
    EXPECT_EQ(status, MoveStatus::Arrived);
    EXPECT_GE(t - 100.0, duration) << "not arrived while the trajectory still moves";
    EXPECT_NEAR(t - 100.0, duration, 0.05);
    EXPECT_EQ(monitor.reason(), "");
  }
  {
    MoveMonitor monitor(trajectory, 0.0);
    double t = 0.0;
    MoveStatus status = MoveStatus::Moving;
    for (; status == MoveStatus::Moving && t < 100.0; t += 0.01) {
      monitor.joint_state(t, follow(t, 0.8));
      status = monitor.update(t);
    }
    EXPECT_EQ(status, MoveStatus::TimedOut);
    EXPECT_NEAR(t, monitor.deadline(), 0.02);
    EXPECT_NE(monitor.reason().find("did not arrive"), std::string::npos) << monitor.reason();
  }
  {
    MoveMonitor monitor(trajectory, 0.0);
    double t = 0.0;
    MoveStatus status = MoveStatus::Moving;
    for (; status == MoveStatus::Moving && t < 100.0; t += 0.01) {
      if (t < 1.0) monitor.joint_state(t, follow(t, 1.0));
      monitor.joint_state(t, Eigen::VectorXd::Zero(3));  // another chain's joints: ignored
      status = monitor.update(t);
    }
    EXPECT_EQ(status, MoveStatus::JointStatesStalled);
    EXPECT_NEAR(t, 1.0 + MoveLimits{}.joint_states_timeout, 0.03);
    EXPECT_EQ(monitor.update(t + 100.0), MoveStatus::JointStatesStalled) << "once stopped, it stays";
  }
  const auto hold = hold_trajectory(b);
  ASSERT_EQ(hold.size(), 1u);
  EXPECT_EQ(hold[0].position, b);
  EXPECT_EQ(hold[0].velocity.norm(), 0.0);
}

// The robot moving itself on the simulated arm (motion/auto_calibration.h): the
// first moves keep the board in view without knowing X, then the session's
// ranking through the planner, until target_progress says the target is reached.
namespace {

struct AutoRun {
  bool reached = false;
  int samples = 0;
  double nees = 0.0;  // X against the truth where it stopped
  int first_moves = 0, first_moves_lost = 0;
  std::string failure;  // no start pose, or no move found: why
};

// `stated`: the session is told the drawn noise; else it estimates it from the residuals.
AutoRun auto_run(const ArmRig& setup, const CollisionModel& model, unsigned seed, const MeasurementNoise& noise,
                 bool stated) {
  Rng rng(seed);
  const auto start = setup.random_start(rng, model, PlannerOptions{});
  AutoRun run;
  if (!start) {
    run.failure = "seed " + std::to_string(seed) + ": no start pose";
    return run;
  }
  SessionSettings settings;
  settings.rig = setup.rig;
  if (stated) settings.noise = noise;
  settings.suggest.views = setup.views;
  settings.honesty.splits = 0;
  CalibrationSession session(settings);
  const AutoCalibration automatic(model, std::nullopt);
  std::vector<PoseSample> samples;
  std::vector<Eigen::Isometry3d> failed;
  Eigen::VectorXd q = *start;
  for (int move = 0; move <= 15 && !run.reached; ++move) {
    if (move > 0) {
      const NextMove next = automatic.next(session, session.snapshot(), q, failed);
      if (!next.found) {
        run.failure = "seed " + std::to_string(seed) + ": " + next.reason;
        return run;
      }
      q = next.plan.goal;
      EXPECT_LT(largest_joint_change(q, next.trajectory.back().position), 1e-12);
      run.first_moves += next.bootstrap;
      const Eigen::Isometry3d P = setup.rig.predicted_view(setup.arm.forward(q), setup.X, setup.Y);
      if (view_problem(setup.rig, std::nullopt, P, PlannerOptions{})) {
        run.first_moves_lost += next.bootstrap;
        failed.push_back(setup.arm.forward(q));
        continue;
      }
    }
    samples.push_back(setup.sample_at(rng, q, noise));
    session.replace(samples, "sample");
    if (samples.size() < 3) continue;
    try {
      const Calibration c = session.calibrate(session.snapshot());
      run.reached = target_progress(c, 1e-3, 0.7).reached;
      run.samples = static_cast<int>(samples.size());
      const Vector6d e = pose_error(c.T_parent_camera, setup.X);
      run.nees = e.dot(c.pose_covariance.ldlt().solve(e));
    } catch (const HandEyeError&) {
    }
  }
  return run;
}

MeasurementNoise camera_noise() {  // rig_simulator's defaults
  MeasurementNoise noise;
  noise.camera.translation = std::pow(0.3e-3, 2) * Eigen::Matrix3d::Identity();
  noise.camera.rotation = std::pow(0.05 * M_PI / 180.0, 2) * Eigen::Matrix3d::Identity();
  return noise;
}

}  // namespace

TEST(AutoCalibration, ReachesOneMillimetreFromOneStartWithTheBoardInView) {
  const ArmRig& setup = arm_rig();
  const CollisionModel model(setup.arm, table_plane());
  MeasurementNoise noise = camera_noise();
  noise.robot.translation = std::pow(0.05e-3, 2) * Eigen::Matrix3d::Identity();
  noise.robot.rotation = std::pow(0.005 * M_PI / 180.0, 2) * Eigen::Matrix3d::Identity();
  int reached = 0, first_moves = 0, first_moves_lost = 0, runs = 0;
  double nees = 0.0;
  std::vector<int> samples_needed;
  for (unsigned seed = 1; seed <= 8; ++seed) {
    const AutoRun run = auto_run(setup, model, seed, noise, true);
    ASSERT_EQ(run.failure, "");
    ++runs;
    first_moves += run.first_moves, first_moves_lost += run.first_moves_lost;
    if (!run.reached) continue;
    ++reached;
    samples_needed.push_back(run.samples);
    nees += run.nees;
  }
  std::sort(samples_needed.begin(), samples_needed.end());
  std::printf("[ auto     ] reached 1 mm at 0.7 m in %d of %d runs, median %d samples; first moves %d, %d of them "
              "without the board; mean NEES %.2f\n",
              reached, runs, samples_needed.empty() ? 0 : samples_needed[samples_needed.size() / 2], first_moves,
              first_moves_lost, reached ? nees / reached : 0.0);
  EXPECT_GE(reached, 7);
  ASSERT_FALSE(samples_needed.empty());
  EXPECT_LE(samples_needed[samples_needed.size() / 2], 8);
  EXPECT_LE(first_moves_lost, first_moves / 5) << "the first moves keep the board in view";
  EXPECT_LT(nees / reached, 12.0) << "stopping at a sigma does not make X's covariance dishonest";
}

// The node's own configuration (simulated_arm.launch): detections without a covariance,
// the robot exact from TF, so the noise is estimated from the residuals. Stopping at the
// first count whose estimated sigma meets the target picked the sessions whose noise came
// out small by chance (stopped at 5 samples: NEES of X 11.0 over 110 of 1000 runs; the CI
// run of 599af19 drew 28.0); target_progress waits for kTargetMinimumSamplesEstimatedNoise.
TEST(AutoCalibration, WithTheNoiseEstimatedStopsWhereTheCovarianceIsHonest) {
  const ArmRig& setup = arm_rig();
  const CollisionModel model(setup.arm, table_plane());
  std::map<int, std::vector<double>> by_count;  // samples at the stop -> NEES of X
  std::vector<double> nees;
  int runs = 0;
  for (unsigned seed = 1; seed <= 200; ++seed, ++runs) {
    const AutoRun run = auto_run(setup, model, 1000 + seed, camera_noise(), false);
    if (!run.reached) continue;
    by_count[run.samples].push_back(run.nees);
    nees.push_back(run.nees);
  }
  ASSERT_GE(nees.size(), 170u);
  const double mean = std::accumulate(nees.begin(), nees.end(), 0.0) / nees.size();
  const auto beyond = static_cast<double>(std::count_if(nees.begin(), nees.end(), [](double n) { return n > 22.46; }));
  std::printf("[ auto     ] noise estimated: reached 1 mm in %zu of %d runs; NEES of X where it stopped %.2f, beyond "
              "chi2(6)'s 99.9%% point in %.1f%%; by the count it stopped at:",
              nees.size(), runs, mean, 100.0 * beyond / nees.size());
  for (const auto& [count, values] : by_count)
    std::printf(" %d: %zu runs, %.2f", count, values.size(),
                std::accumulate(values.begin(), values.end(), 0.0) / values.size());
  std::printf("\n");
  EXPECT_GE(by_count.begin()->first, kTargetMinimumSamplesEstimatedNoise);
  // An estimated noise's NEES has a heavier tail than chi2(6) (an F-like one) and a mean a
  // little above 6: at a fixed 7 samples 6.40, beyond 22.46 in about 1%.
  EXPECT_LT(mean, 7.5) << "X's covariance where auto stops (6 for an honest one; 6.34 +- 0.05 over 10 000 runs)";
  for (const auto& [count, values] : by_count) {
    if (values.size() < 10) continue;
    EXPECT_LT(std::accumulate(values.begin(), values.end(), 0.0) / values.size(), 8.0)
        << "the sessions that stop at " << count << " samples are not the lucky ones";
  }
  EXPECT_LE(beyond / nees.size(), 0.03);
}
