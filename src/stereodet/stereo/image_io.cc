#include "stereodet/stereo/image_io.h"

#include <opencv2/imgcodecs.hpp>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"

namespace stereodet {

cv::Mat ReadColourImage(const std::filesystem::path& path) {
  cv::Mat image = cv::imread(path.string(), cv::IMREAD_COLOR);
  STEREODET_CHECK_IO(!image.empty()) << "cannot read image " << path.string();
  return image;
}

void WriteImageAtomically(const std::filesystem::path& path, const cv::Mat& image) {
  AtomicPath out(path);
  STEREODET_CHECK_IO(cv::imwrite(out.temp_path().string(), image))
      << "cannot write " << path.string();
  out.Commit();
}

}  // namespace stereodet
