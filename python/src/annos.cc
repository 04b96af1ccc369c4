#include "annos.h"

#include <cmath>
#include <limits>

namespace stereodet::python {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string Quote(const std::string& key) { return "['" + key + "']"; }

// The class names as Python strings: a numpy array of str (or bytes) or any sequence of str. An
// empty array of any dtype (OpenPCDet's np.zeros(0) for a frame without predictions) is no names.
std::vector<std::string> Names(py::handle value, const std::string& what) {
  std::vector<std::string> names;
  if (py::isinstance<py::array>(value) && py::reinterpret_borrow<py::array>(value).size() == 0) {
    return names;
  }
  if (py::isinstance<py::str>(value) || !py::hasattr(value, "__len__")) {
    ThrowValueError(what + ": expected a sequence of class names, got " + Describe(value));
  }
  if (py::isinstance<py::array>(value) && py::reinterpret_borrow<py::array>(value).ndim() != 1) {
    ThrowValueError(what + ": expected one name per object (N,), got " + Describe(value));
  }
  py::object items = py::hasattr(value, "tolist") ? value.attr("tolist")()
                                                  : py::reinterpret_borrow<py::object>(value);
  names.reserve(py::len(items));
  for (py::handle item : items) {
    if (py::isinstance<py::str>(item)) {
      names.push_back(item.cast<std::string>());
    } else if (py::isinstance<py::bytes>(item)) {
      names.push_back(py::reinterpret_borrow<py::bytes>(item).cast<std::string>());
    } else {
      ThrowValueError(what + "[" + std::to_string(names.size()) +
                      "]: expected a class name (str), got " + Describe(item));
    }
  }
  return names;
}

// A (n, cols) float64 view of annos[key] (a (n,) array for cols == 0). Any size-0 array is
// accepted for n == 0 (OpenPCDet writes np.array([]) for an empty frame's boxes too).
class Column {
 public:
  Column(py::handle annos, const std::string& key, py::ssize_t n, int cols, const std::string& what)
      : name_(what + Quote(key)), cols_(cols == 0 ? 1 : cols) {
    array_ = NumericArray<double>(annos[py::str(key)], name_);
    if (n == 0 && array_.size() == 0) return;
    const bool ok = cols == 0
                        ? array_.ndim() == 1 && array_.shape(0) == n
                        : array_.ndim() == 2 && array_.shape(0) == n && array_.shape(1) == cols;
    if (!ok) {
      const std::string shape = cols == 0
                                    ? "(" + std::to_string(n) + ",)"
                                    : "(" + std::to_string(n) + ", " + std::to_string(cols) + ")";
      ThrowValueError(name_ + ": expected shape " + shape + " (one row per name), got " +
                      Describe(array_));
    }
    data_ = array_.data();
  }

  // Element (row, col); ValueError unless finite.
  double At(py::ssize_t row, int col = 0) const {
    const double value = data_[row * cols_ + col];
    if (!std::isfinite(value)) {
      ThrowValueError(Where(row, col) + ": " + py::str(py::float_(value)).cast<std::string>() +
                      " is not a finite number");
    }
    return value;
  }
  std::string Where(py::ssize_t row, int col) const {
    return name_ + "[" + std::to_string(row) + (cols_ > 1 ? ", " + std::to_string(col) : "") + "]";
  }

 private:
  std::string name_;
  int cols_;
  NumericArrayT<double> array_;
  const double* data_ = nullptr;
};

bool Has(py::handle annos, const char* key) {
  return PySequence_Contains(annos.ptr(), py::str(key).ptr()) == 1;
}

}  // namespace

std::vector<Object> ObjectsFromAnnos(py::handle annos, bool detections, const std::string& what) {
  if (!PyMapping_Check(annos.ptr()) || !py::hasattr(annos, "keys")) {
    ThrowValueError(what + ": expected an annotation dict (name, bbox, ...), got " +
                    Describe(annos));
  }
  const char* required[] = {"name", "alpha", "bbox", "dimensions", "location", "rotation_y"};
  for (const char* key : required) {
    if (!Has(annos, key)) ThrowValueError(what + ": missing key '" + key + "'");
  }
  for (const char* key : {"truncated", "occluded"}) {
    if (!detections && !Has(annos, key)) ThrowValueError(what + ": missing key '" + key + "'");
  }
  if (detections && !Has(annos, "score")) ThrowValueError(what + ": missing key 'score'");

  const std::vector<std::string> names = Names(annos[py::str("name")], what + Quote("name"));
  const auto n = static_cast<py::ssize_t>(names.size());
  const Column alpha(annos, "alpha", n, 0, what), bbox(annos, "bbox", n, 4, what),
      dimensions(annos, "dimensions", n, 3, what), location(annos, "location", n, 3, what),
      rotation_y(annos, "rotation_y", n, 0, what);
  std::optional<Column> truncated, occluded, score;
  if (Has(annos, "truncated")) truncated.emplace(annos, "truncated", n, 0, what);
  if (Has(annos, "occluded")) occluded.emplace(annos, "occluded", n, 0, what);
  if (detections) score.emplace(annos, "score", n, 0, what);

  std::vector<Object> objects(names.size());
  for (py::ssize_t i = 0; i < n; ++i) {
    Object& o = objects[i];
    o.type = names[i];
    if (truncated) o.truncated = truncated->At(i);
    if (occluded) {
      const double value = occluded->At(i);
      const bool integral = value == std::trunc(value) && std::abs(value) < 1e9;
      if (!integral && !detections) {
        ThrowValueError(occluded->Where(i, 0) + ": " + std::to_string(value) +
                        " is not an integer (0, 1, 2, 3, or -1 for DontCare)");
      }
      o.occluded = integral ? static_cast<int>(value) : -1;
    }
    o.alpha = alpha.At(i);
    o.box = Box2D{bbox.At(i, 0), bbox.At(i, 1), bbox.At(i, 2), bbox.At(i, 3)};
    // OpenPCDet's (l, h, w) to the file's h, w, l.
    o.box3d.l = dimensions.At(i, 0);
    o.box3d.h = dimensions.At(i, 1);
    o.box3d.w = dimensions.At(i, 2);
    for (int k = 0; k < 3; ++k) {
      const double d = dimensions.At(i, k);
      if (d < 0 && d != -1.0) {
        ThrowValueError(dimensions.Where(i, k) + ": " + std::to_string(d) +
                        " is negative (dimensions are >= 0, or -1 for KITTI's \"not estimated\")");
      }
    }
    o.box3d.location = {location.At(i, 0), location.At(i, 1), location.At(i, 2)};
    o.box3d.rotation_y = rotation_y.At(i);
    if (score) o.score = score->At(i);
  }
  return objects;
}

py::dict AnnosFromObjects(const std::vector<Object>& objects, bool with_score) {
  const auto n = static_cast<py::ssize_t>(objects.size());
  py::list names;
  py::array_t<double> truncated(n), alpha(n), rotation_y(n), score(n);
  py::array_t<int64_t> occluded(n);
  py::array_t<double> bbox({n, py::ssize_t{4}}), dimensions({n, py::ssize_t{3}}),
      location({n, py::ssize_t{3}});
  double* t = truncated.mutable_data();
  double* a = alpha.mutable_data();
  double* r = rotation_y.mutable_data();
  double* s = score.mutable_data();
  int64_t* occ = occluded.mutable_data();
  double* b = bbox.mutable_data();
  double* d = dimensions.mutable_data();
  double* l = location.mutable_data();
  for (py::ssize_t i = 0; i < n; ++i) {
    const Object& o = objects[i];
    names.append(py::str(o.type));
    t[i] = o.truncated;
    occ[i] = o.occluded;
    a[i] = o.alpha;
    b[4 * i] = o.box.left;
    b[4 * i + 1] = o.box.top;
    b[4 * i + 2] = o.box.right;
    b[4 * i + 3] = o.box.bottom;
    d[3 * i] = o.box3d.l;
    d[3 * i + 1] = o.box3d.h;
    d[3 * i + 2] = o.box3d.w;
    for (int k = 0; k < 3; ++k) l[3 * i + k] = o.box3d.location[k];
    r[i] = o.box3d.rotation_y;
    s[i] = o.score.value_or(kNaN);
  }
  py::module_ np = py::module_::import("numpy");
  py::dict out;
  out["name"] = np.attr("array")(names, py::arg("dtype") = np.attr("str_"));
  out["truncated"] = truncated;
  out["occluded"] = occluded;
  out["alpha"] = alpha;
  out["bbox"] = bbox;
  out["dimensions"] = dimensions;
  out["location"] = location;
  out["rotation_y"] = rotation_y;
  if (with_score) out["score"] = score;
  return out;
}

}  // namespace stereodet::python
