#include "common.h"

#include <atomic>
#include <exception>
#include <filesystem>
#include <stdexcept>

#include "stereodet/util/check.h"

namespace stereodet::python {

namespace {
std::atomic<int> calls_in_progress{0};
// stereodet.ParseError, held for the life of the process (the translator outlives any module).
PyObject* parse_error_type = nullptr;
}  // namespace

// The counter moves while the GIL is released, so that a thread that holds the GIL can only see a
// positive count if another thread really is in C++ without it.
ReleaseGil::ReleaseGil() { calls_in_progress.fetch_add(1); }
ReleaseGil::~ReleaseGil() { calls_in_progress.fetch_sub(1); }

int CallsInProgress() { return calls_in_progress.load(); }

void RegisterErrorTranslation(py::object parse_error) {
  parse_error_type = parse_error.release().ptr();
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const py::builtin_exception&) {
      throw;  // pybind11's own (value_error, type_error, ...): its translator
    } catch (const py::error_already_set&) {
      throw;
    } catch (const ParseError& e) {
      py::object error = py::reinterpret_borrow<py::object>(parse_error_type)(UserMessage(e));
      error.attr("file") = e.file();
      error.attr("line") = e.line();
      error.attr("field") = e.field();
      error.attr("message") = DebugMessages() ? e.message() : StripSourceTags(e.message());
      PyErr_SetObject(parse_error_type, error.ptr());
    } catch (const std::invalid_argument& e) {
      PyErr_SetString(PyExc_ValueError, UserMessage(e).c_str());
    } catch (const std::filesystem::filesystem_error& e) {
      PyErr_SetString(PyExc_OSError, UserMessage(e).c_str());
    } catch (const std::runtime_error& e) {
      PyErr_SetString(PyExc_OSError, UserMessage(e).c_str());
    }
  });
}

void ThrowValueError(const std::string& message) { throw py::value_error(message); }

std::string Describe(py::handle value) {
  if (py::isinstance<py::array>(value)) {
    py::array a = py::reinterpret_borrow<py::array>(value);
    std::string shape = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) {
      if (i > 0) shape += ", ";
      shape += std::to_string(a.shape(i));
    }
    if (a.ndim() == 1) shape += ",";
    shape += ")";
    return py::str(a.dtype()).cast<std::string>() + " array of shape " + shape;
  }
  return py::str(py::type::handle_of(value).attr("__name__")).cast<std::string>();
}

}  // namespace stereodet::python
