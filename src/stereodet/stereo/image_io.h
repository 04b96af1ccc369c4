// Reading and writing the images of a KITTI-layout dataset, with errors that name the file.
#ifndef STEREODET_STEREO_IMAGE_IO_H_
#define STEREODET_STEREO_IMAGE_IO_H_

#include <filesystem>

#include <opencv2/core.hpp>

namespace stereodet {

// Reads an image as 8-bit, 3-channel BGR (grey files are expanded). Throws std::runtime_error naming
// the path if it is missing or not a readable image.
cv::Mat ReadColourImage(const std::filesystem::path& path);

// Writes `image` atomically (temp file + rename); the format follows the extension. Throws
// std::runtime_error naming the path on failure.
void WriteImageAtomically(const std::filesystem::path& path, const cv::Mat& image);

}  // namespace stereodet

#endif  // STEREODET_STEREO_IMAGE_IO_H_
