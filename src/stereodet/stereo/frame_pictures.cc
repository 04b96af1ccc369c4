#include "stereodet/stereo/frame_pictures.h"

#include <fmt/format.h>

#include <opencv2/core.hpp>
#include <utility>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/stereo/visualize.h"
#include "stereodet/util/check.h"

namespace stereodet {

FramePicturesResult WriteFramePictures(const KittiDataset& dataset, const std::string& id,
                                       const std::filesystem::path& out,
                                       const StereoOptions& options) {
  StereoEncoder encoder(options);  // checks the options before any reading
  // The id becomes file names under --data and --out: "../../x" would read and write elsewhere.
  STEREODET_CHECK(IsFrameId(id)) << "--id '" << id << "' is not a frame id (digits only)";
  const FramePaths in = dataset.Paths(id);
  const cv::Mat left = ReadColourImage(in.image_left);
  const cv::Mat right = ReadColourImage(in.image_right);
  CheckStereoPairSize(left, right, in.image_left, in.image_right);
  CheckImageFitsMatcher(options.disparity, left.size(), in.image_left);
  const StereoGeometry geometry = StereoGeometry::FromCalibration(ReadCalibration(in.calib));
  const StereoEncoding encoding =
      encoder.Encode(left, right, geometry, {.rgbh = false, .depth = false, .points = true});
  std::filesystem::create_directories(out);
  const cv::Mat depth = DepthFromDisparity(encoding.disparity_px, geometry);
  const cv::Mat height =
      HeightFromDisparity(encoding.disparity_px, geometry, encoding.ground.plane);
  const std::vector<std::pair<std::string, cv::Mat>> pictures = {
      {"disparity", ColourizeDisparity(encoding.disparity_px, options.disparity.num_disparities)},
      {"depth", ColourizeDepth(depth)},
      {"height", ColourizeHeight(height, options.height.min_m, options.height.max_m)},
      {"bev", RenderBirdsEye(encoding.points)}};
  // The keys: where each colour sits on the turbo map, in the picture's units.
  auto linear = [](double lo, double hi, const char* unit) {
    std::vector<std::pair<double, std::string>> ticks;
    for (int i = 0; i <= 4; ++i) {
      ticks.push_back({i / 4.0, fmt::format("{:g} {}", lo + (hi - lo) * i / 4.0, unit)});
    }
    return ticks;
  };
  // Depth is drawn as inverse depth t = min / z (ColourizeDepth's default min, 3 m).
  constexpr double kMinDepthM = 3.0;
  std::vector<std::pair<double, std::string>> depth_ticks = {{0.0, "inf"}};
  for (const double z : {60.0, 30.0, 15.0, 6.0, kMinDepthM}) {
    depth_ticks.push_back({kMinDepthM / z, fmt::format("{:g} m", z)});
  }
  const BirdsEyeOptions bev;
  const std::vector<ColourBar> bars = {
      {fmt::format("{} disparity (px), left image; black: no stereo", id),
       linear(0, options.disparity.num_disparities, "px")},
      {fmt::format("{} depth (m), colour by 1/depth; black: no stereo", id), depth_ticks},
      {fmt::format("{} height above the ground plane (m); black: no stereo", id),
       linear(options.height.min_m, options.height.max_m, "m")},
      {fmt::format("{} stereo points from above, {:g} x {:g} m, rings every 10 m; colour: velo z",
                   id, bev.forward_m, 2 * bev.side_m),
       linear(bev.min_z_m, bev.max_z_m, "m")}};
  FramePicturesResult result;
  for (size_t i = 0; i < pictures.size(); ++i) {
    const auto& [name, picture] = pictures[i];
    result.files.push_back(out / (id + "_" + name + ".png"));
    WriteImageAtomically(result.files.back(), picture);
    result.keyed_files.push_back(out / (id + "_" + name + "_key.png"));
    WriteImageAtomically(result.keyed_files.back(), WithColourBar(picture, bars[i]));
  }
  result.stereo_pixels = cv::countNonZero(encoding.height_code);
  result.total_pixels = static_cast<int64_t>(encoding.height_code.total());
  result.points = static_cast<int64_t>(encoding.points.size());
  result.ground = encoding.ground;
  return result;
}

}  // namespace stereodet
