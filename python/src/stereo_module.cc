// stereodet._stereo: stereo features from numpy images (OpenCV), imported on the first use of
// stereodet.stereo so that `import stereodet` and an evaluation load no OpenCV.
#include "common.h"

PYBIND11_MODULE(_stereo, m) {
  namespace py = pybind11;
  using namespace stereodet::python;
  m.doc() = "stereodet's stereo features (use stereodet.stereo).";
  // The exception types are _core's (one stereodet.ParseError for the whole package).
  py::module_ core = py::module_::import("stereodet._core");
  RegisterErrorTranslation(core.attr("ParseError"));
  m.def("_calls_in_progress", &CallsInProgress,
        "The number of threads now inside C++ work with the GIL released (for the tests).");
}
