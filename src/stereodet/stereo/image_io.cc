#include "stereodet/stereo/image_io.h"

#include <limits>
#include <opencv2/imgcodecs.hpp>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"

namespace stereodet {

cv::Mat ReadImage(const std::filesystem::path& path, int imread_flags, const char* what) {
  // Through ReadFile, not cv::imread: imread opens a FIFO (or a device) and blocks forever, and
  // reads a huge file without a bound; ReadFile refuses both, naming the file. Decoding from the
  // bytes costs what imread's own read would.
  const std::string bytes = ReadFile(path, std::numeric_limits<int>::max(), what);
  cv::Mat image;
  try {
    const cv::Mat buffer(1, static_cast<int>(bytes.size()), CV_8U, const_cast<char*>(bytes.data()));
    if (!bytes.empty()) image = cv::imdecode(buffer, imread_flags);
  } catch (const cv::Exception& e) {
    STEREODET_THROW_IO() << "cannot read " << what << " " << path.string() << ": " << e.err;
  }
  STEREODET_CHECK_IO(!image.empty()) << "cannot read " << what << " " << path.string()
                                     << ": not a decodable image (empty, truncated or corrupt)";
  return image;
}

cv::Mat ReadColourImage(const std::filesystem::path& path) {
  return ReadImage(path, cv::IMREAD_COLOR);
}

void CheckStereoPairSize(const cv::Mat& left, const cv::Mat& right,
                         const std::filesystem::path& left_path,
                         const std::filesystem::path& right_path) {
  STEREODET_CHECK_IO(left.size() == right.size())
      << "a stereo pair must have equal sizes: " << left_path.string() << " is " << left.cols << "x"
      << left.rows << " px, " << right_path.string() << " is " << right.cols << "x" << right.rows
      << " px";
}

void WriteImageAtomically(const std::filesystem::path& path, const cv::Mat& image) {
  AtomicPath out(path);
  STEREODET_CHECK_IO(cv::imwrite(out.temp_path().string(), image))
      << "cannot write " << path.string();
  out.Commit();
}

}  // namespace stereodet
