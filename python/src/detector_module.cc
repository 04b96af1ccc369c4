// stereodet._detector: the trained detectors of every family on frames held in numpy arrays
// (models/detector.h), imported on the first use of stereodet.Detector, so that `import stereodet`
// loads no LibTorch (python/tests/test_package.py). Images are OpenCV's (H, W, 3) uint8 BGR, read
// in place; the objects come back as one frame's annotation dict (annos.h: OpenPCDet's keys); the
// GIL is released while the detector runs.
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "annos.h"
#include "common.h"
#include "image.h"
#include "stereodet/geometry/calibration.h"
#include "stereodet/models/detector.h"

namespace stereodet::python {

namespace {

// `calib`: a stereodet.kitti.Calibration, or a pair (P2, P3) of 3 x 4 projection matrices (the
// rectified left and right cameras; every other transform the identity).
std::optional<Calibration> CalibrationFrom(py::handle calib) {
  if (calib.is_none()) return std::nullopt;
  if (py::isinstance<Calibration>(calib)) return calib.cast<Calibration>();
  if (py::isinstance<py::sequence>(calib) && !py::isinstance<py::str>(calib) &&
      py::len(calib) == 2) {
    Calibration c;
    const py::sequence pair = py::reinterpret_borrow<py::sequence>(calib);
    for (int camera : {2, 3}) {
      const std::string what = camera == 2 ? "calib P2" : "calib P3";
      const NumericArrayT<double> p = NumericArray<double>(pair[camera - 2], what);
      if (p.ndim() != 2 || p.shape(0) != 3 || p.shape(1) != 4) {
        ThrowValueError(what + ": expected a (3, 4) matrix, got " + Describe(pair[camera - 2]));
      }
      for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 4; ++k) c.projection[camera](r, k) = p.at(r, k);
      }
    }
    c.projection[0] = c.projection[2];
    c.projection[0].col(3).setZero();
    return c;
  }
  ThrowValueError(
      "calib: expected a stereodet.kitti.Calibration or a pair (P2, P3) of (3, 4) "
      "matrices, got " +
      Describe(calib));
}

// (N, 4) float32 points (x, y, z m, reflectance) in the velodyne frame.
std::vector<VeloPoint> PointsFrom(py::handle value) {
  const NumericArrayT<float> a = NumericArray<float>(value, "points");
  if (a.ndim() != 2 || a.shape(1) != 4) {
    ThrowValueError("points: expected an array of shape (N, 4) (x, y, z, reflectance), got " +
                    Describe(value));
  }
  std::vector<VeloPoint> points(static_cast<size_t>(a.shape(0)));
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    points[i] = {a.at(i, 0), a.at(i, 1), a.at(i, 2), a.at(i, 3)};
  }
  return points;
}

// One frame from Python's arguments; `keep` holds the arrays the images view.
StereoFrame FrameFrom(py::handle left, py::handle right, py::handle calib, py::handle points,
                      const std::string& id, std::vector<Image>& keep) {
  StereoFrame frame;
  frame.id = id;
  if (!left.is_none()) {
    keep.push_back(Image8(left, "left", false));
    frame.left = keep.back().mat;
  }
  if (!right.is_none()) {
    keep.push_back(Image8(right, "right", false));
    frame.right = keep.back().mat;
    if (!frame.left.empty()) CheckSameSize(frame.left, frame.right, "left", "right");
  }
  frame.calib = CalibrationFrom(calib);
  if (!points.is_none()) frame.points = PointsFrom(points);
  return frame;
}

py::dict ResultDict(const DetectResult& result) {
  py::dict annos = AnnosFromObjects(result.objects, /*with_score=*/true);
  annos["frame_id"] = result.id;
  py::dict times;
  times["stereo_s"] = result.times.stereo_s;
  times["encode_s"] = result.times.encode_s;
  times["network_s"] = result.times.network_s;
  times["decode_s"] = result.times.decode_s;
  annos["times"] = times;
  return annos;
}

}  // namespace

}  // namespace stereodet::python

PYBIND11_MODULE(_detector, m) {
  namespace py = pybind11;
  using namespace stereodet;
  using namespace stereodet::python;
  m.doc() = "stereodet's trained detectors on numpy frames (use stereodet.Detector).";
  // One stereodet.ParseError and one Calibration class for the whole package: _core's.
  py::module_ core = py::module_::import("stereodet._core");
  RegisterErrorTranslation(core.attr("ParseError"));
  m.def("_calls_in_progress", &CallsInProgress,
        "The number of threads now inside C++ work with the GIL released (for the tests).");

  py::class_<Detector>(m, "Detector", R"(A trained detector of any family (ssd, rpn, det3d), opened
from its model folder (model.json names the family; model.pt is checked against it).

    detector = stereodet.Detector("models/ssd-rgbh-learned", threads=2)
    annos = detector.detect(left, right, calib)   # OpenPCDet's annotation dict of the frame

Images are (H, W, 3) uint8 BGR arrays (OpenCV's layout), the rectified pair; `calib` a
stereodet.kitti.Calibration or a pair (P2, P3) of (3, 4) matrices; `points` (N, 4) float32 in the
velodyne frame (the LiDAR scan of a LiDAR 3D model; a stereo 3D model computes its points from the
pair when not given). What a model does not need may be None (`needs` says what it reads; a LiDAR
3D model still takes `left` for the image's size, to keep the objects inside it). The
objects are those `stereodet detect` writes for the same frame. One thread at a time per Detector
(the GIL is released while it runs; two Detectors on two threads run in parallel).)")
      .def(py::init([](const std::string& model_dir, const std::string& device, int threads,
                       double blur_sigma_px, const std::string& calibration) {
             DetectorOptions options;
             options.device = device;
             options.threads = threads;
             options.blur_sigma_px = blur_sigma_px;
             options.calibration = calibration;
             ReleaseGil release;
             return std::make_unique<Detector>(Detector::Open(model_dir, options));
           }),
           py::arg("model_dir"), py::kw_only(), py::arg("device") = "cpu", py::arg("threads") = 0,
           py::arg("blur_sigma_px") = 0.0, py::arg("calibration") = "",
           "Opens the model folder. threads: LibTorch's (0 = all cores); blur_sigma_px: Gaussian "
           "blur of the network's image only (the paper's degradation); calibration: a score "
           "calibration file of `stereodet calibrate --fit` (scores become calibrated "
           "probabilities, as `stereodet detect --calibration` writes them; '' = raw scores).")
      .def_property_readonly(
          "family", [](const Detector& d) { return d.family(); }, "ssd, rpn or det3d")
      .def_property_readonly(
          "input", [](const Detector& d) { return d.input(); },
          "rgb, rgbh-fixed, rgbh-learned, rgbd, lidar or stereo")
      .def_property_readonly(
          "classes", [](const Detector& d) { return d.classes(); }, "the class names it detects")
      .def_property_readonly(
          "model_dir", [](const Detector& d) { return d.model_dir().string(); }, "its folder")
      .def_property_readonly(
          "needs",
          [](const Detector& d) {
            py::dict needs;
            needs["left"] = d.needs().left_image;
            needs["right"] = d.needs().right_image;
            needs["calib"] = d.needs().calibration;
            needs["points"] = d.needs().points;
            return needs;
          },
          "what detect() reads of a frame: {'left', 'right', 'calib', 'points'} -> bool")
      .def(
          "detect",
          [](Detector& d, py::handle left, py::handle right, py::handle calib, py::handle points,
             const std::string& frame_id) {
            std::vector<Image> keep;
            keep.reserve(2);
            const StereoFrame frame = FrameFrom(left, right, calib, points, frame_id, keep);
            DetectResult result;
            {
              ReleaseGil release;
              result = d.Detect(frame);
            }
            return ResultDict(result);
          },
          py::arg("left"), py::arg("right") = py::none(), py::arg("calib") = py::none(),
          py::kw_only(), py::arg("points") = py::none(), py::arg("frame_id") = "",
          "One frame: its annotation dict (name, bbox, score, alpha, dimensions (l, h, w), "
          "location, rotation_y; 3D fields -1 / -1000 / -10 for 2D models), with 'frame_id' and "
          "'times' (stereo_s, encode_s, network_s, decode_s).")
      .def(
          "detect_batch",
          [](Detector& d, const py::list& frames) {
            std::vector<Image> keep;
            keep.reserve(2 * py::len(frames));
            std::vector<StereoFrame> batch;
            for (size_t i = 0; i < py::len(frames); ++i) {
              py::dict f = frames[i].cast<py::dict>();
              auto get = [&](const char* key) -> py::handle {
                return f.contains(key) ? py::handle(f[key]) : py::handle(py::none());
              };
              const std::string id =
                  f.contains("frame_id") ? f["frame_id"].cast<std::string>() : std::to_string(i);
              batch.push_back(
                  FrameFrom(get("left"), get("right"), get("calib"), get("points"), id, keep));
            }
            std::vector<DetectResult> results;
            {
              ReleaseGil release;
              results = d.DetectBatch(batch);
            }
            py::list out;
            for (const DetectResult& r : results) out.append(ResultDict(r));
            return out;
          },
          py::arg("frames"),
          "Several frames in one network pass: a list of dicts with the keys of detect()'s "
          "arguments ('left', 'right', 'calib', 'points', 'frame_id'); their annotation dicts in "
          "order. The same objects as detect() on each frame inside a batch of this size.");
}
