// Reading and writing the images of a KITTI-layout dataset, with errors that name the file.
#ifndef STEREODET_STEREO_IMAGE_IO_H_
#define STEREODET_STEREO_IMAGE_IO_H_

#include <filesystem>
#include <opencv2/core.hpp>

namespace stereodet {

// cv::imread(path, imread_flags), with every failure a std::runtime_error that names the path and
// `what` ("image", "disparity image"): a missing or unreadable file, and OpenCV's own errors (a PNG
// header claiming 100000 x 100000 px trips its 2^30-pixel limit inside imread).
cv::Mat ReadImage(const std::filesystem::path& path, int imread_flags, const char* what = "image");

// Reads an image as 8-bit, 3-channel BGR (grey files are expanded). Throws std::runtime_error
// naming the path if it is missing or not a readable image.
cv::Mat ReadColourImage(const std::filesystem::path& path);

// Throws std::runtime_error naming both files when the two images of a stereo pair differ in size
// (a rectified pair, KITTI's image_2 and image_3, is equal-sized); the matcher's own message would
// name neither file nor frame.
void CheckStereoPairSize(const cv::Mat& left, const cv::Mat& right,
                         const std::filesystem::path& left_path,
                         const std::filesystem::path& right_path);

// Writes `image` atomically (temp file + rename); the format follows the extension. Throws
// std::runtime_error naming the path on failure.
void WriteImageAtomically(const std::filesystem::path& path, const cv::Mat& image);

}  // namespace stereodet

#endif  // STEREODET_STEREO_IMAGE_IO_H_
