// Detector speed per image, every target kind at 640 x 480 and 1280 x 720, side by
// side in one process: what the node (target_detector) and `handeye images` do per
// image: rectify, detect, PnP with the covariance. The images are rendered once
// (a view at 0.5-0.6 m, blur, noise, lens distortion) before timing.
// Regenerate BENCHMARKS.md with ./scripts/bench.
#include <benchmark/benchmark.h>

#include <map>
#include <string>

#include "handeye_covariance/core/viewpoints.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/simulation/pattern_renderer.h"
#include "handeye_covariance/vision/target.h"

namespace handeye {
namespace {

const std::map<std::string, Target>& targets() {
  static const std::map<std::string, Target> all = {
      {"chessboard_9x6", make_target(ChessboardTarget{9, 6, 0.020})},
      {"charuco_6x5", make_target(CharucoTarget{6, 5, 0.030, 0.022, "DICT_5X5_100"})},
      {"aruco_single", make_target(single_tag_layout(7, 0.1, "DICT_4X4_50"))},
      {"apriltag_board_2x2", make_target(io::read_tag_layout(HANDEYE_SOURCE_DIR "/config/tag_board_2x2.yaml"))}};
  return all;
}

CameraModel camera_of(int width) {
  CameraModel camera = simulated_camera();  // 640 x 480, f = 600 px
  if (width == 1280) {
    camera.width = 1280;
    camera.height = 720;
    camera.K << 900.0, 0.0, 639.5, 0.0, 900.0, 359.5, 0.0, 0.0, 1.0;
  }
  return camera;
}

void BM_DetectAndEstimate(benchmark::State& state, const std::string& kind) {
  const Target& target = targets().at(kind);
  const CameraModel camera = camera_of(static_cast<int>(state.range(0)));
  const PatternRenderer renderer(target, camera);
  Rng rng(7);
  ViewpointOptions views;
  views.min_distance = 0.5;
  views.max_distance = 0.6;
  const cv::Mat image = renderer.render(random_view(rng, views) * target_face(target).inverse(), rng);
  const ImageRectifier rectifier(camera);
  const TargetDetector detector(target);
  PixelNoise noise;
  int found = 0;
  for (auto _ : state) {
    const TargetObservation seen = detector.detect(image, rectifier);  // as the node and handeye images
    if (seen.points) found += estimate_pose(rectifier.rectified(), *seen.points, noise).pose.has_value();
    benchmark::ClobberMemory();
  }
  if (found != static_cast<int>(state.iterations())) state.SkipWithError("the target was not found in every run");
}

BENCHMARK_CAPTURE(BM_DetectAndEstimate, chessboard, std::string("chessboard_9x6"))->Arg(640)->Arg(1280)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_DetectAndEstimate, charuco, std::string("charuco_6x5"))->Arg(640)->Arg(1280)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_DetectAndEstimate, aruco, std::string("aruco_single"))->Arg(640)->Arg(1280)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_DetectAndEstimate, apriltag, std::string("apriltag_board_2x2"))->Arg(640)->Arg(1280)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace handeye

BENCHMARK_MAIN();
