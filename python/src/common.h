// What every binding file shares: the GIL release around C++ work, the translation of the
// library's exceptions into Python's, and checks of numpy arguments that raise ValueError (never
// crash) on a wrong dtype or shape.
#ifndef STEREODET_PYTHON_COMMON_H_
#define STEREODET_PYTHON_COMMON_H_

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace stereodet::python {

namespace py = pybind11;

// Releases the GIL for the C++ work of a call (the arguments are converted before, the results
// after) and counts the calls inside such a section, so that a test can see, without a clock,
// that another Python thread ran while one was there (python/tests/test_threads.py).
class ReleaseGil {
 public:
  ReleaseGil();
  ~ReleaseGil();
  ReleaseGil(const ReleaseGil&) = delete;
  ReleaseGil& operator=(const ReleaseGil&) = delete;

 private:
  py::gil_scoped_release release_;
};
// The number of threads now inside a ReleaseGil section (of this extension).
int CallsInProgress();

// Translates the library's exceptions, for every extension module of the package:
//   stereodet::ParseError        -> `parse_error` (stereodet.ParseError, a ValueError) with
//                                   .file, .line, .field and .message;
//   std::invalid_argument        -> ValueError (a bad argument, as the CLI's "error: ..." line);
//   std::runtime_error, filesystem errors -> OSError (files and the outside world).
// The message is the library's, so the same "FILE:LINE: field F: ..." text as the CLI prints.
void RegisterErrorTranslation(py::object parse_error);

// Raises ValueError with `message`.
[[noreturn]] void ThrowValueError(const std::string& message);

// "float64 array of shape (3, 4)" / "list": what a wrong argument was, for error messages.
std::string Describe(py::handle value);

// `value` as a C-contiguous array of T. Any numeric array (or nested sequence) converts (numpy's
// unsafe casting, e.g. float32 -> float64), but no text or objects: ValueError naming `what`.
template <typename T>
using NumericArrayT = py::array_t<T, py::array::c_style | py::array::forcecast>;
template <typename T>
NumericArrayT<T> NumericArray(py::handle value, const std::string& what);

// A C-contiguous array that must have `dtype` T exactly (images: no silent conversion of a float
// image into uint8), of `ndim` dimensions; `shape` entries < 0 are free. ValueError naming `what`
// and `expected` ("a uint8 array of shape (H, W, 3)") otherwise. A non-contiguous array is copied.
template <typename T>
py::array_t<T, py::array::c_style> ExactArray(py::handle value, const std::string& what,
                                              const std::vector<py::ssize_t>& shape,
                                              const std::string& expected);

template <typename T>
struct IsOptional : std::false_type {};
template <typename T>
struct IsOptional<std::optional<T>> : std::true_type {};

// A name parsed by one of the library's ParseX functions, whether it returns std::optional<X> or
// X (throwing std::invalid_argument itself): ValueError "what: unknown 'text' (choices)" if none.
template <typename Parse>
auto ParseChoice(Parse parse, const std::string& text, const std::string& what,
                 const std::string& choices) {
  auto parsed = parse(text);
  if constexpr (IsOptional<decltype(parsed)>::value) {
    if (!parsed.has_value()) {
      ThrowValueError(what + ": unknown '" + text + "' (" + choices + ")");
    }
    return *parsed;
  } else {
    return parsed;
  }
}

// --- Implementation of the templates. ---

template <typename T>
NumericArrayT<T> NumericArray(py::handle value, const std::string& what) {
  py::array any = py::array::ensure(value);
  if (!any) {
    PyErr_Clear();
    ThrowValueError(what + ": expected numbers, got " + Describe(value));
  }
  const char kind = any.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u' && kind != 'b') {
    ThrowValueError(what + ": expected numbers, got " + Describe(value));
  }
  auto out = NumericArrayT<T>::ensure(any);
  if (!out) {
    PyErr_Clear();
    ThrowValueError(what + ": cannot convert " + Describe(value) + " to numbers");
  }
  return out;
}

template <typename T>
py::array_t<T, py::array::c_style> ExactArray(py::handle value, const std::string& what,
                                              const std::vector<py::ssize_t>& shape,
                                              const std::string& expected) {
  if (!py::isinstance<py::array>(value)) {
    ThrowValueError(what + ": expected " + expected + ", got " + Describe(value));
  }
  py::array any = py::reinterpret_borrow<py::array>(value);
  bool ok =
      py::isinstance<py::array_t<T>>(any) && any.ndim() == static_cast<py::ssize_t>(shape.size());
  for (size_t i = 0; ok && i < shape.size(); ++i) {
    ok = shape[i] < 0 || any.shape(static_cast<py::ssize_t>(i)) == shape[i];
  }
  if (!ok) ThrowValueError(what + ": expected " + expected + ", got " + Describe(value));
  auto out = py::array_t<T, py::array::c_style>::ensure(any);
  if (!out) ThrowValueError(what + ": cannot read " + Describe(value));
  return out;
}

}  // namespace stereodet::python

#endif  // STEREODET_PYTHON_COMMON_H_
