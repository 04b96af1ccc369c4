#include "image.h"

namespace stereodet::python {

Image Image8(py::handle value, const std::string& what, bool allow_grey) {
  const std::string expected = allow_grey
                                   ? "a uint8 array of shape (H, W, 3) (OpenCV's BGR) or (H, W)"
                                   : "a uint8 array of shape (H, W, 3) (OpenCV's BGR)";
  const bool grey = allow_grey && py::isinstance<py::array>(value) &&
                    py::reinterpret_borrow<py::array>(value).ndim() == 2;
  Image image;
  image.array = grey ? ExactArray<uint8_t>(value, what, {-1, -1}, expected)
                     : ExactArray<uint8_t>(value, what, {-1, -1, 3}, expected);
  if (image.array.shape(0) == 0 || image.array.shape(1) == 0) {
    ThrowValueError(what + ": the image is empty, got " + Describe(value));
  }
  image.mat = View(image.array, grey ? CV_8UC1 : CV_8UC3);
  return image;
}

void CheckSameSize(const cv::Mat& a, const cv::Mat& b, const std::string& what_a,
                   const std::string& what_b) {
  if (a.size() != b.size()) {
    ThrowValueError(what_a + " and " + what_b + " differ in size: " + std::to_string(a.rows) +
                    " x " + std::to_string(a.cols) + " vs " + std::to_string(b.rows) + " x " +
                    std::to_string(b.cols));
  }
}

}  // namespace stereodet::python
