// Every registered target kind (core/target.h target_kinds) through every layer:
// its example file config/targets/<name>.yaml, its file types and examples, each
// layer's table (detector, renderer, printer), an image rendered and detected,
// and its printed page detected. A kind added to the list is exercised here
// without a line of this file; a piece it lacks fails naming the kind.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <opencv2/imgcodecs.hpp>
#include <set>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/io/files.h"
#include "handeye_covariance/io/target_file.h"
#include "handeye_covariance/print/target_printer.h"
#include "handeye_covariance/simulation/pattern_renderer.h"
#include "handeye_covariance/vision/target.h"
#include "scratch_directory.h"

namespace handeye {
namespace {

std::string example_file(const TargetKind& kind) {
  return std::string(HANDEYE_SOURCE_DIR) + "/config/targets/" + kind.name() + ".yaml";
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(TargetKinds, EveryLayerHasEveryKindAndNoOther) {
  ASSERT_FALSE(target_kinds().empty());
  std::set<std::string> names, types;
  for (const TargetKind* kind : target_kinds()) {
    EXPECT_TRUE(names.insert(kind->name()).second) << "two kinds named " << kind->name();
    EXPECT_EQ(find_target_kind(kind->name()), kind);
    EXPECT_EQ(error_of([&] { vision_kind(kind->name()); }), "") << kind->name();
    EXPECT_EQ(error_of([&] { render_kind(kind->name()); }), "") << kind->name();
    EXPECT_EQ(error_of([&] { print::print_kind(kind->name()); }), "") << kind->name();
    EXPECT_FALSE(kind->file_types().empty()) << kind->name();
    for (const std::string& type : kind->file_types()) {
      EXPECT_TRUE(types.insert(type).second) << "two kinds read `type: " << type << "`";
      EXPECT_EQ(find_target_kind_of_type(type), kind) << type;
    }
  }
  // Each layer's table names registered kinds only, each once.
  const auto only_registered = [&](const std::vector<std::string>& layer, const std::string& what) {
    EXPECT_EQ(std::set<std::string>(layer.begin(), layer.end()).size(), layer.size()) << what << " lists a kind twice";
    for (const std::string& name : layer) EXPECT_TRUE(names.count(name)) << what << " has unregistered kind " << name;
  };
  std::vector<std::string> vision, render, printed;
  for (const VisionKind& k : vision_kinds()) vision.push_back(k.name);
  for (const RenderKind& k : render_kinds()) render.push_back(k.name);
  for (const print::PrintKind& k : print::print_kinds()) printed.push_back(k.name);
  only_registered(vision, "src/vision/target.cpp");
  only_registered(render, "src/simulation/pattern_renderer.cpp");
  only_registered(printed, "src/print/target_printer.cpp");

  // An unknown kind is refused naming the known ones, from the list.
  const std::string unknown = error_of([] { io::parse_target("{type: circle_grid}", "t.yaml"); });
  EXPECT_NE(unknown.find("unknown target type `circle_grid`"), std::string::npos) << unknown;
  for (const std::string& type : types) EXPECT_NE(unknown.find(type), std::string::npos) << unknown;
  EXPECT_NE(error_of([] { vision_kind("circle_grid"); }).find("src/vision/target.cpp"), std::string::npos);
}

TEST(TargetKinds, EachKindsExamplesParseAndScale) {
  for (const TargetKind* kind : target_kinds()) {
    for (const std::string& type : kind->file_types()) {
      // The example in every refusal's fix is itself a file of the kind.
      std::string example = kind->example(type);
      ASSERT_EQ(example.rfind("e.g. ", 0), 0u) << example;
      example = example.substr(5);
      Target target;
      ASSERT_EQ(error_of([&] { target = io::parse_target(example, type + ".yaml"); }), "") << example;
      EXPECT_EQ(target.kind_name(), kind->name()) << example;
      // --measured-square scales the kind's lengths: the ruler's among them.
      const Target scaled = io::parse_target(print::scaled_target_text(example, 2.0, "t.yaml"), "t.yaml");
      EXPECT_NEAR(scaled.kind().ruler_length(scaled), 2.0 * kind->ruler_length(target), 1e-12) << example;
    }
  }
}

TEST(TargetKinds, EachKindsFileIsRenderedDetectedAndPrinted) {
  for (const TargetKind* kind : target_kinds()) {
    const std::string file = example_file(*kind);
    ASSERT_TRUE(std::filesystem::exists(file)) << kind->name() << ": no example file " << file;
    const Target target = io::read_target(file);
    ASSERT_EQ(target.kind_name(), kind->name()) << file;
    EXPECT_FALSE(target.describe().empty());
    const TargetDetector detector(target);

    // Seen straight on from a distance that holds it, through the renderer.
    const PatternRenderer renderer(target, simulated_camera());
    const double distance = std::max(0.3, 2.2 * target_face_size(target).maxCoeff());
    const Eigen::Isometry3d T_face_camera =
        se3::make_pose(Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal(), Eigen::Vector3d(0.0, 0.0, distance));
    const Eigen::Isometry3d T_camera_pattern = (target_face(target) * T_face_camera).inverse();
    Rng rng(42);
    const ImageRectifier rectifier(simulated_camera());
    const TargetObservation rendered = detector.detect(renderer.render(T_camera_pattern, rng), rectifier);
    EXPECT_TRUE(rendered.points) << kind->name() << " rendered: " << rendered.refusal;

    // Printed on A4 at 150 dpi, found on the page.
    print::PrintOptions options;
    options.dpi = 150.0;
    options.target_text = io::read_file(file);
    const std::string png = test::scratch_directory() + "/" + kind->name() + ".png";
    ASSERT_EQ(error_of([&] { print::print_target(target, png, options); }), "") << kind->name();
    const cv::Mat page = cv::imread(png, cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(page.empty()) << png;
    const TargetObservation printed = detector.detect(page);
    EXPECT_TRUE(printed.points) << kind->name() << " printed: " << printed.refusal;
  }
}

}  // namespace
}  // namespace handeye
