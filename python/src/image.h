// numpy images <-> cv::Mat, for the extensions that link OpenCV (_stereo, _detector).
#ifndef STEREODET_PYTHON_IMAGE_H_
#define STEREODET_PYTHON_IMAGE_H_

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

#include "common.h"

namespace stereodet::python {

// A view of a C-contiguous array (kept alive by the caller for the call).
template <typename T>
cv::Mat View(const py::array_t<T, py::array::c_style>& a, int type) {
  return cv::Mat(static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)), type,
                 const_cast<T*>(a.data()));
}

// An (H, W, 3) BGR or, with `allow_grey`, an (H, W) grey uint8 image: `mat` views `array`, no
// copy when the array is C-contiguous. ValueError naming `what` for another dtype or shape, or an
// empty image. Requires the GIL.
struct Image {
  py::array_t<uint8_t, py::array::c_style> array;
  cv::Mat mat;
};
Image Image8(py::handle value, const std::string& what, bool allow_grey);

// ValueError "WHAT_A and WHAT_B differ in size: H x W vs H x W" unless they have one size.
void CheckSameSize(const cv::Mat& a, const cv::Mat& b, const std::string& what_a,
                   const std::string& what_b);

}  // namespace stereodet::python

#endif  // STEREODET_PYTHON_IMAGE_H_
