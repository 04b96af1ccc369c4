// Pictures a person can look at (`stereodet stereo frame`): colourized disparity, depth and height,
// and the point cloud from above. All return 8-bit BGR images; pixels without stereo are black.
#ifndef STEREODET_STEREO_VISUALIZE_H_
#define STEREODET_STEREO_VISUALIZE_H_

#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "stereodet/kitti/velodyne_io.h"

namespace stereodet {

// Disparity (CV_32FC1 px) with the turbo colour map over [0, max_disparity_px] (near = red).
cv::Mat ColourizeDisparity(const cv::Mat& disparity_px, double max_disparity_px);
// Depth (CV_32FC1 m, NaN invalid) as inverse depth over [min_depth_m, inf) (near = red).
cv::Mat ColourizeDepth(const cv::Mat& depth_m, double min_depth_m = 3.0);
// Height above ground (CV_32FC1 m, NaN invalid) over [min_m, max_m] (ground = blue, high = red).
cv::Mat ColourizeHeight(const cv::Mat& height_m, double min_m = -1.0, double max_m = 4.0);

struct BirdsEyeOptions {
  double forward_m = 80.0;               // velo x shown: [0, forward_m]
  double side_m = 40.0;                  // velo y shown: [-side_m, side_m]
  double resolution_m = 0.1;             // metres per pixel
  double min_z_m = -2.5, max_z_m = 1.5;  // velo z range of the colour map
  void Check() const;
};
// Velo points seen from above: forward is up, left is left; colour by velo z; range rings every 10
// m.
cv::Mat RenderBirdsEye(const std::vector<VeloPoint>& points, const BirdsEyeOptions& options = {});

// The key of a colourized picture: what the colours mean, in units. `ticks` are (t, text) with t in
// [0, 1] the position on the turbo map (0 = its blue end), e.g. {0, "0 px"}, {1, "128 px"}.
struct ColourBar {
  std::string caption;  // one line above the bar, e.g. "000000 disparity (px); black: no stereo"
  std::vector<std::pair<double, std::string>> ticks;
};
// The turbo colour at t in [0, 1] (clamped), as the Colourize functions map it (BGR).
cv::Vec3b TurboColour(double t);
// `picture` (8-bit BGR) with a white band below it of ColourBarBandHeight() px: the
// caption, the turbo bar from x = ColourBarMarginPx() to cols - ColourBarMarginPx() (t = 0 at the
// left end, 1 at the right end) with a tick and its text at each tick. The picture's pixels are
// unchanged (rows 0 .. picture.rows - 1). Throws std::invalid_argument for an empty picture, one
// narrower than 4 margins, or a tick outside [0, 1].
cv::Mat WithColourBar(const cv::Mat& picture, const ColourBar& bar);
int ColourBarBandHeight();
int ColourBarMarginPx();
// The bar's rows in WithColourBar's output, below the picture: [top, top + ColourBarHeightPx()).
int ColourBarTopPx(int picture_rows);
int ColourBarHeightPx();

}  // namespace stereodet

#endif  // STEREODET_STEREO_VISUALIZE_H_
