// stereodet._core: KITTI I/O and evaluation (no OpenCV, no LibTorch). The pure-Python package
// (python/stereodet/) is the documented interface; names here with a leading underscore are its
// internals.
#include <pybind11/stl.h>

#include <string>
#include <vector>

#include "common.h"
#include "stereodet/cli/commands.h"
#include "stereodet/util/version.h"

namespace stereodet::python {
void BindKitti(py::module_& m);
void BindEval(py::module_& m);
void BindCoco(py::module_& m);
}  // namespace stereodet::python

PYBIND11_MODULE(_core, m) {
  namespace py = pybind11;
  using namespace stereodet::python;
  m.doc() = "stereodet's C++ core: KITTI I/O and evaluation (use the stereodet package).";
  m.attr("__version__") = stereodet::StereodetVersion();

  // stereodet.ParseError: a bad line of an input file, with its file, line and field.
  py::object parse_error = py::reinterpret_steal<py::object>(
      PyErr_NewExceptionWithDoc("stereodet.ParseError",
                                "A bad line in an input file: a ValueError whose message is the "
                                "library's 'FILE:LINE: field F: message', with the parts in .file, "
                                ".line (1-based; 0 if not line-based), .field and .message.",
                                PyExc_ValueError, nullptr));
  m.attr("ParseError") = parse_error;
  RegisterErrorTranslation(parse_error);
  BindKitti(m);
  BindEval(m);
  BindCoco(m);

  m.def(
      "_run_cli",
      [](const std::vector<std::string>& args) {
        ReleaseGil release;
        return stereodet::cli::RunCommandInProcess(args, stereodet::cli::Program::kFrontEnd,
                                                   stereodet::cli::FrontEndCommands());
      },
      py::arg("args"),
      "`stereodet ARGS...` of a front-end command (info, eval, report, view) in this process, "
      "with the GIL released; returns its exit code (its output goes to this process's stdout "
      "and stderr). Used by stereodet.scale's in-process tasks.");
  m.def("_calls_in_progress", &CallsInProgress,
        "The number of threads now inside C++ work with the GIL released (for the tests).");
}
