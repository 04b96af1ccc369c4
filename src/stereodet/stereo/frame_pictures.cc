#include "stereodet/stereo/frame_pictures.h"

#include <opencv2/core.hpp>
#include <utility>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/stereo/visualize.h"

namespace stereodet {

FramePicturesResult WriteFramePictures(const KittiDataset& dataset, const std::string& id,
                                       const std::filesystem::path& out,
                                       const StereoOptions& options) {
  StereoEncoder encoder(options);  // checks the options before any reading
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
  FramePicturesResult result;
  for (const auto& [name, picture] : pictures) {
    result.files.push_back(out / (id + "_" + name + ".png"));
    WriteImageAtomically(result.files.back(), picture);
  }
  result.stereo_pixels = cv::countNonZero(encoding.height_code);
  result.total_pixels = static_cast<int64_t>(encoding.height_code.total());
  result.points = static_cast<int64_t>(encoding.points.size());
  result.ground = encoding.ground;
  return result;
}

}  // namespace stereodet
