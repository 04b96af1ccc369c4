// stereodet._stereo: stereo features from numpy images (OpenCV), imported on the first use of
// stereodet.stereo so that `import stereodet` and an evaluation load no OpenCV.
//
// Images are numpy arrays in OpenCV's layout: (H, W, 3) uint8 BGR, or (H, W) uint8 grey where a
// grey image will do; float images (disparity px, depth m, height m) are (H, W) float32 (any
// numeric array converts); code images are (H, W) uint16. Inputs are read in place (no copy when
// C-contiguous), outputs are handed over without a copy. The options structs of the C++ library
// are classes here whose constructors take the fields as keyword arguments (nested options as
// dicts), and every function releases the GIL around the C++ work.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <cstring>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "common.h"
#include "image.h"
#include "stereodet/cli/commands.h"
#include "stereodet/geometry/calibration.h"
#include "stereodet/stereo/degradation.h"
#include "stereodet/stereo/disparity.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/stereo/point_cloud.h"
#include "stereodet/stereo/reprojection.h"
#include "stereodet/stereo/rgbh.h"
#include "stereodet/stereo/stereo_encoder.h"

namespace stereodet::python {

namespace {

// --- numpy <-> cv::Mat ---

// An (H, W) float32 image; any numeric array converts.
struct FloatImage {
  NumericArrayT<float> array;
  cv::Mat mat;
};
FloatImage Float32(py::handle value, const std::string& what) {
  FloatImage image;
  image.array = NumericArray<float>(value, what);
  if (image.array.ndim() != 2) {
    ThrowValueError(what + ": expected an array of shape (H, W), got " + Describe(value));
  }
  image.mat =
      cv::Mat(static_cast<int>(image.array.shape(0)), static_cast<int>(image.array.shape(1)),
              CV_32FC1, const_cast<float*>(image.array.data()));
  return image;
}

// An (H, W) uint16 code image.
struct CodeImage {
  py::array_t<uint16_t, py::array::c_style> array;
  cv::Mat mat;
};
CodeImage Codes(py::handle value, const std::string& what) {
  CodeImage image;
  image.array = ExactArray<uint16_t>(value, what, {-1, -1}, "a uint16 array of shape (H, W)");
  image.mat = View(image.array, CV_16UC1);
  return image;
}

// Hands `mat` to numpy without a copy: (rows, cols) or (rows, cols, channels).
py::array ToArray(cv::Mat mat) {
  if (!mat.isContinuous()) mat = mat.clone();
  py::dtype dtype;
  switch (mat.depth()) {
    case CV_8U:
      dtype = py::dtype::of<uint8_t>();
      break;
    case CV_16U:
      dtype = py::dtype::of<uint16_t>();
      break;
    case CV_16S:
      dtype = py::dtype::of<int16_t>();
      break;
    case CV_32F:
      dtype = py::dtype::of<float>();
      break;
    default:
      throw std::logic_error("ToArray: unexpected cv::Mat depth");
  }
  std::vector<py::ssize_t> shape = {mat.rows, mat.cols};
  if (mat.channels() > 1) shape.push_back(mat.channels());
  auto* owner = new cv::Mat(std::move(mat));
  py::capsule free_when_done(owner, [](void* p) { delete static_cast<cv::Mat*>(p); });
  return py::array(dtype, shape, owner->data, free_when_done);
}

py::array ToArray(const PlanarImage& image) {
  py::array_t<float> out({image.channels, image.rows, image.cols});
  std::copy(image.data.begin(), image.data.end(), out.mutable_data());
  return out;
}

py::array_t<float> PointsToArray(const std::vector<VeloPoint>& points) {
  py::array_t<float> out({static_cast<py::ssize_t>(points.size()), py::ssize_t{4}});
  if (!points.empty()) {
    std::memcpy(out.mutable_data(), points.data(), points.size() * sizeof(VeloPoint));
  }
  return out;
}

// --- Ground planes as dicts ---

py::dict GroundFitToDict(const GroundPlaneFit& fit) {
  py::dict d;
  d["normal_in_rect"] = Eigen::Vector3d(fit.plane.normal_in_rect);
  d["offset_m"] = fit.plane.offset_m;
  d["fitted"] = fit.fitted;
  d["reason"] = fit.reason;
  d["samples"] = fit.samples;
  d["inliers"] = fit.inliers;
  d["camera_height_m"] = fit.camera_height_m;
  d["tilt_deg"] = fit.tilt_deg;
  return d;
}

// None: the nominal plane (camera 1.65 m above a flat road); or any mapping with normal_in_rect
// and offset_m (fit_ground_plane's dict).
GroundPlane GroundFrom(py::handle value) {
  GroundPlane plane;
  if (value.is_none()) return plane;
  if (!PyMapping_Check(value.ptr()) || !py::hasattr(value, "keys")) {
    ThrowValueError("ground: expected None or a dict with normal_in_rect and offset_m, got " +
                    Describe(value));
  }
  py::object normal = value["normal_in_rect"];
  auto n = NumericArray<double>(normal, "ground['normal_in_rect']");
  if (n.size() != 3) {
    ThrowValueError("ground['normal_in_rect']: expected 3 numbers, got " + Describe(n));
  }
  plane.normal_in_rect = {n.data()[0], n.data()[1], n.data()[2]};
  plane.offset_m = py::cast<double>(value["offset_m"]);
  return plane;
}

StereoGeometry GeometryOf(const Calibration& calib) {
  return StereoGeometry::FromCalibration(calib);  // ValueError without a stereo pair
}

// --- Options classes ---

// Sets the fields of the options object `self` from keyword arguments; a dict for a nested
// options field updates that field's own fields. Unknown names raise TypeError, as a function
// given an unexpected keyword argument does.
void SetFields(py::object self, const py::dict& fields) {
  const py::tuple known = self.attr("_fields");
  for (auto item : fields) {
    const std::string key = py::str(item.first);
    bool found = false;
    for (py::handle k : known) found = found || k.cast<std::string>() == key;
    if (!found) {
      throw py::type_error(py::str(py::type::handle_of(self).attr("__name__")).cast<std::string>() +
                           "() got an unexpected keyword argument '" + key + "'");
    }
    py::object current = self.attr(key.c_str());
    if (py::isinstance<py::dict>(item.second) && py::hasattr(current, "_fields")) {
      SetFields(current, py::reinterpret_borrow<py::dict>(item.second));
    } else {
      self.attr(key.c_str()) = item.second;
    }
  }
}

// py::class_ for an options struct: fields in declaration order (`_fields`), a keyword
// constructor, a dict constructor (so a dict converts where the struct is expected), a repr with
// every value, and check() (the struct's Check(): ValueError on a bad setting).
template <typename T>
class OptionsClass {
 public:
  OptionsClass(py::module_& m, const char* name, const char* doc) : cls_(m, name, doc) {}

  template <typename M>
  OptionsClass& Field(const char* name, M T::*member, const char* doc) {
    cls_.def_readwrite(name, member, doc);
    fields_.push_back(name);
    return *this;
  }
  template <typename Get, typename Set>
  OptionsClass& Property(const char* name, Get get, Set set, const char* doc) {
    cls_.def_property(name, get, set, doc);
    fields_.push_back(name);
    return *this;
  }

  py::class_<T>& Finish() {
    py::tuple fields(fields_.size());
    for (size_t i = 0; i < fields_.size(); ++i) fields[i] = py::str(fields_[i]);
    cls_.attr("_fields") = fields;
    cls_.def(py::init([](const py::kwargs& kwargs) {
               py::object self = py::cast(T{});
               SetFields(self, kwargs);
               return self.cast<T>();
             }),
             "Defaults as in the C++ library; any field as a keyword argument.");
    cls_.def(py::init([](const py::dict& fields) {
               py::object self = py::cast(T{});
               SetFields(self, fields);
               return self.cast<T>();
             }),
             py::arg("fields"), "From a dict of fields.");
    py::implicitly_convertible<py::dict, T>();
    cls_.def("check", &T::Check, "Raises ValueError on a bad setting (the C++ Check()).");
    cls_.def("__repr__", [](py::object self) {
      std::string out =
          py::str(py::type::handle_of(self).attr("__name__")).cast<std::string>() + "(";
      const py::tuple fields = self.attr("_fields");
      for (size_t i = 0; i < fields.size(); ++i) {
        if (i > 0) out += ", ";
        const std::string key = fields[i].cast<std::string>();
        out += key + "=" + py::repr(self.attr(key.c_str())).cast<std::string>();
      }
      return out + ")";
    });
    return cls_;
  }

 private:
  py::class_<T> cls_;
  std::vector<std::string> fields_;
};

void BindOptions(py::module_& m) {
  OptionsClass<BlockMatchingOptions>(m, "BlockMatchingOptions", "OpenCV StereoBM's settings.")
      .Field("block_size", &BlockMatchingOptions::block_size, "odd, 5..255: SAD window side, px")
      .Field("xsobel_prefilter", &BlockMatchingOptions::xsobel_prefilter,
             "x-Sobel pre-filter (True) or normalized response (False)")
      .Field("prefilter_size", &BlockMatchingOptions::prefilter_size,
             "odd, 5..255; normalized-response pre-filter only")
      .Field("prefilter_cap", &BlockMatchingOptions::prefilter_cap, "1..63")
      .Field("texture_threshold", &BlockMatchingOptions::texture_threshold,
             ">= 0: windows with less texture are invalid")
      .Finish();
  OptionsClass<SemiGlobalOptions>(m, "SemiGlobalOptions", "OpenCV StereoSGBM's settings.")
      .Field("block_size", &SemiGlobalOptions::block_size, "odd, 1..255: window side, px")
      .Field("p1_per_pixel", &SemiGlobalOptions::p1_per_pixel,
             "P1 = p1_per_pixel * channels * block^2 unless p1")
      .Field("p2_per_pixel", &SemiGlobalOptions::p2_per_pixel,
             "P2 = p2_per_pixel * channels * block^2 unless p2 (> P1)")
      .Field("p1", &SemiGlobalOptions::p1, "OpenCV's P1 itself, or None (the per-pixel rule)")
      .Field("p2", &SemiGlobalOptions::p2, "OpenCV's P2 itself, or None (the per-pixel rule)")
      .Field("prefilter_cap", &SemiGlobalOptions::prefilter_cap, "1..1023")
      .Property(
          "mode", [](const SemiGlobalOptions& o) { return std::string(SgbmModeName(o.mode)); },
          [](SemiGlobalOptions& o, const std::string& name) {
            o.mode = ParseChoice([](const std::string& s) { return ParseSgbmMode(s); }, name,
                                 "mode", "sgbm, hh, sgbm3way, hh4");
          },
          "'sgbm' (MODE_SGBM, the default), 'hh', 'sgbm3way' or 'hh4'")
      .Field("colour", &SemiGlobalOptions::colour, "match the BGR images (3-channel costs)")
      .Finish();
  OptionsClass<WlsFilterOptions>(m, "WlsFilterOptions",
                                 "OpenCV ximgproc's DisparityWLSFilter post-filter.")
      .Field("enabled", &WlsFilterOptions::enabled, "False (the default): no post-filter")
      .Field("lambda_", &WlsFilterOptions::lambda, "> 0: OpenCV's lambda")
      .Field("sigma_color", &WlsFilterOptions::sigma_color, "> 0: OpenCV's sigmaColor")
      .Field("lrc_threshold", &WlsFilterOptions::lrc_threshold, ">= 0, 1/16 px: LRCthresh")
      .Field("depth_discontinuity_radius", &WlsFilterOptions::depth_discontinuity_radius,
             ">= 0, px")
      .Finish();
  OptionsClass<DisparityOptions>(m, "DisparityOptions",
                                 "Disparity settings (stereo/disparity.h, docs/stereo.md).")
      .Property(
          "method",
          [](const DisparityOptions& o) { return std::string(DisparityMethodName(o.method)); },
          [](DisparityOptions& o, const std::string& name) {
            o.method = ParseChoice([](const std::string& s) { return ParseDisparityMethod(s); },
                                   name, "method", "bm, sgbm");
          },
          "'bm' (StereoBM, the default) or 'sgbm'")
      .Field("num_disparities", &DisparityOptions::num_disparities,
             "> 0, multiple of 16: search range [min, min + num) px")
      .Field("min_disparity", &DisparityOptions::min_disparity, "px")
      .Field("uniqueness_ratio", &DisparityOptions::uniqueness_ratio, "0..100, percent")
      .Field("speckle_window_px", &DisparityOptions::speckle_window_px, ">= 0 (0 = off)")
      .Field("speckle_range_px", &DisparityOptions::speckle_range_px, ">= 0, px")
      .Field("left_right_max_diff_px", &DisparityOptions::left_right_max_diff_px,
             "left-right consistency, px (BM: < 0 disables)")
      .Field("bm", &DisparityOptions::bm, "BlockMatchingOptions (or a dict of its fields)")
      .Field("sgbm", &DisparityOptions::sgbm, "SemiGlobalOptions (or a dict of its fields)")
      .Field("wls", &DisparityOptions::wls, "WlsFilterOptions (or a dict of its fields)")
      .Field("match_scale", &DisparityOptions::match_scale,
             "0.1..1: match at this fraction of the image's size (1 = full resolution)")
      .Finish();
  OptionsClass<GroundPlaneOptions>(m, "GroundPlaneOptions",
                                   "RANSAC ground fit (stereo/reprojection.h).")
      .Field("roi_fraction", &GroundPlaneOptions::roi_fraction, "lower fraction of the rows")
      .Field("sample_step_px", &GroundPlaneOptions::sample_step_px, "every n-th row and column")
      .Field("min_depth_m", &GroundPlaneOptions::min_depth_m, "m")
      .Field("max_depth_m", &GroundPlaneOptions::max_depth_m, "m")
      .Field("max_lateral_m", &GroundPlaneOptions::max_lateral_m, "m (0 = no limit)")
      .Field("max_samples", &GroundPlaneOptions::max_samples, "points")
      .Field("iterations", &GroundPlaneOptions::iterations, "RANSAC iterations")
      .Field("inlier_threshold_m", &GroundPlaneOptions::inlier_threshold_m, "m")
      .Field("seed", &GroundPlaneOptions::seed, "RANSAC seed")
      .Field("min_inliers", &GroundPlaneOptions::min_inliers, "acceptance")
      .Field("min_inlier_fraction", &GroundPlaneOptions::min_inlier_fraction, "acceptance")
      .Field("max_tilt_deg", &GroundPlaneOptions::max_tilt_deg, "acceptance, degrees")
      .Field("min_camera_height_m", &GroundPlaneOptions::min_camera_height_m, "acceptance, m")
      .Field("max_camera_height_m", &GroundPlaneOptions::max_camera_height_m, "acceptance, m")
      .Field("nominal_camera_height_m", &GroundPlaneOptions::nominal_camera_height_m,
             "the fallback plane's camera height, m")
      .Field("enabled", &GroundPlaneOptions::enabled, "False: always the nominal plane")
      .Field("warn_tilt_deg", &GroundPlaneOptions::warn_tilt_deg,
             "an accepted fit tilted more is suspect, degrees")
      .Field("warn_camera_height_m", &GroundPlaneOptions::warn_camera_height_m,
             "an accepted fit this far from the nominal camera height is suspect, m")
      .Field("suspect_uses_prior", &GroundPlaneOptions::suspect_uses_prior,
             "True: the nominal plane replaces a suspect fit")
      .Finish();
  OptionsClass<HeightQuantization>(m, "HeightQuantization",
                                   "Height (m) -> codes 1..511: [min_m, max_m] linearly.")
      .Field("min_m", &HeightQuantization::min_m, "m")
      .Field("max_m", &HeightQuantization::max_m, "m")
      .Finish();
  OptionsClass<DepthQuantization>(m, "DepthQuantization",
                                  "Depth (m) -> codes 1..2^bits - 1: [min_m, max_m] linearly.")
      .Field("min_m", &DepthQuantization::min_m, "m")
      .Field("max_m", &DepthQuantization::max_m, "m")
      .Field("bits", &DepthQuantization::bits, "8..16")
      .Finish();
  OptionsClass<PointCloudOptions>(m, "PointCloudOptions",
                                  "Stereo point cloud truncation and LiDAR-like subsampling.")
      .Field("max_depth_m", &PointCloudOptions::max_depth_m, "m")
      .Field("min_height_m", &PointCloudOptions::min_height_m, "above the ground, m")
      .Field("max_height_m", &PointCloudOptions::max_height_m, "above the ground, m")
      .Field("beams", &PointCloudOptions::beams, "0 = every point")
      .Field("min_elevation_deg", &PointCloudOptions::min_elevation_deg, "degrees")
      .Field("max_elevation_deg", &PointCloudOptions::max_elevation_deg, "degrees")
      .Field("azimuth_step_deg", &PointCloudOptions::azimuth_step_deg, "degrees")
      .Finish();
  OptionsClass<BlurOptions>(m, "BlurOptions", "Gaussian blur of the network's image (defocus).")
      .Field("sigma_px", &BlurOptions::sigma_px, ">= 0, px; 0 = no blur")
      .Property(
          "mode", [](const BlurOptions& o) { return std::string(BlurModeName(o.mode)); },
          [](BlurOptions& o, const std::string& name) {
            o.mode = ParseChoice([](const std::string& s) { return ParseBlurMode(s); }, name,
                                 "mode", "image, both");
          },
          "'image' (only the network's image, the paper) or 'both' (before matching too)")
      .Finish();
  OptionsClass<StereoOptions>(m, "StereoOptions", "Everything encode() does (stereo_encoder.h).")
      .Field("disparity", &StereoOptions::disparity, "DisparityOptions")
      .Field("ground", &StereoOptions::ground, "GroundPlaneOptions")
      .Field("height", &StereoOptions::height, "HeightQuantization")
      .Field("depth", &StereoOptions::depth, "DepthQuantization")
      .Field("points", &StereoOptions::points, "PointCloudOptions")
      .Field("blur", &StereoOptions::blur, "BlurOptions")
      .Finish();
}

NetworkInput ParseLayout(const std::string& name) {
  return ParseChoice([](const std::string& s) { return ParseNetworkInput(s); }, name, "layout",
                     "rgbh, rgbh-fixed");
}

}  // namespace

}  // namespace stereodet::python

PYBIND11_MODULE(_stereo, m) {
  namespace py = pybind11;
  using namespace stereodet;
  using namespace stereodet::python;
  m.doc() = "stereodet's stereo features (use stereodet.stereo).";
  // The exception types are _core's (one stereodet.ParseError for the whole package), and the
  // Calibration class too.
  py::module_ core = py::module_::import("stereodet._core");
  RegisterErrorTranslation(core.attr("ParseError"));
  // OpenCV's own errors (e.g. an image too small for the matcher): ValueError with its message.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const cv::Exception& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });
  m.def("_calls_in_progress", &CallsInProgress,
        "The number of threads now inside C++ work with the GIL released (for the tests).");
  m.def(
      "_run_cli",
      [](const std::vector<std::string>& args) {
        ReleaseGil release;
        return stereodet::cli::RunCommandInProcess(args, stereodet::cli::Program::kVision,
                                                   stereodet::cli::VisionCommands());
      },
      py::arg("args"),
      "`stereodet ARGS...` of a stereodet-vision command (synth, stereo) in this process, with "
      "the GIL released; returns its exit code (its output goes to this process's stdout and "
      "stderr). Used by stereodet.scale's in-process tasks.");

  BindOptions(m);

  m.def(
      "read_image",
      [](const std::string& path) {
        cv::Mat image;
        {
          ReleaseGil release;
          image = ReadColourImage(path);
        }
        return ToArray(std::move(image));
      },
      py::arg("path"));
  m.def(
      "disparity",
      [](py::handle left, py::handle right, const DisparityOptions& options) {
        const Image l = Image8(left, "left", true), r = Image8(right, "right", true);
        CheckSameSize(l.mat, r.mat, "left", "right");
        if (l.mat.channels() != r.mat.channels()) {
          ThrowValueError("left and right differ in channels (one grey, one BGR)");
        }
        cv::Mat out;
        {
          ReleaseGil release;
          DisparityMatcher matcher(options);
          out = matcher.Compute(l.mat, r.mat);
        }
        return ToArray(std::move(out));
      },
      py::arg("left"), py::arg("right"), py::arg("options"));
  m.def(
      "depth_from_disparity",
      [](py::handle disparity, const Calibration& calib) {
        const FloatImage d = Float32(disparity, "disparity");
        const StereoGeometry geometry = GeometryOf(calib);
        cv::Mat out;
        {
          ReleaseGil release;
          out = DepthFromDisparity(d.mat, geometry);
        }
        return ToArray(std::move(out));
      },
      py::arg("disparity"), py::arg("calib"));
  m.def(
      "points_in_rect",
      [](py::handle disparity, const Calibration& calib) {
        const FloatImage d = Float32(disparity, "disparity");
        const StereoGeometry geometry = GeometryOf(calib);
        cv::Mat out;
        {
          ReleaseGil release;
          out = PointsInRectFromDisparity(d.mat, geometry);
        }
        return ToArray(std::move(out));
      },
      py::arg("disparity"), py::arg("calib"));
  m.def(
      "fit_ground_plane",
      [](py::handle disparity, const Calibration& calib, const GroundPlaneOptions& options) {
        const FloatImage d = Float32(disparity, "disparity");
        const StereoGeometry geometry = GeometryOf(calib);
        GroundPlaneFit fit;
        {
          ReleaseGil release;
          fit = FitGroundPlane(d.mat, geometry, options);
        }
        return GroundFitToDict(fit);
      },
      py::arg("disparity"), py::arg("calib"), py::arg("options"));
  m.def(
      "height_from_disparity",
      [](py::handle disparity, const Calibration& calib, py::handle ground) {
        const FloatImage d = Float32(disparity, "disparity");
        const StereoGeometry geometry = GeometryOf(calib);
        const GroundPlane plane = GroundFrom(ground);
        cv::Mat out;
        {
          ReleaseGil release;
          out = HeightFromDisparity(d.mat, geometry, plane);
        }
        return ToArray(std::move(out));
      },
      py::arg("disparity"), py::arg("calib"), py::arg("ground"));
  m.def(
      "quantize_height",
      [](py::handle height_m, const HeightQuantization& q) {
        const FloatImage h = Float32(height_m, "height_m");
        cv::Mat out;
        {
          ReleaseGil release;
          out = QuantizeHeight(h.mat, q);
        }
        return ToArray(std::move(out));
      },
      py::arg("height_m"), py::arg("quantization"));
  m.def(
      "quantize_depth",
      [](py::handle depth_m, const DepthQuantization& q) {
        const FloatImage d = Float32(depth_m, "depth_m");
        cv::Mat out;
        {
          ReleaseGil release;
          out = QuantizeDepth(d.mat, q);
        }
        return ToArray(std::move(out));
      },
      py::arg("depth_m"), py::arg("quantization"));
  m.def(
      "pack_rgbh",
      [](py::handle bgr, py::handle height_code) {
        const Image image = Image8(bgr, "bgr", false);
        const CodeImage codes = Codes(height_code, "height_code");
        CheckSameSize(image.mat, codes.mat, "bgr", "height_code");
        cv::Mat out;
        {
          ReleaseGil release;
          out = PackRgbh(image.mat, codes.mat);
        }
        return ToArray(std::move(out));
      },
      py::arg("bgr"), py::arg("height_code"));
  m.def(
      "unpack_rgbh",
      [](py::handle packed) {
        const Image image = Image8(packed, "packed", false);
        UnpackedRgbh out;
        {
          ReleaseGil release;
          out = UnpackRgbh(image.mat);
        }
        return py::make_tuple(ToArray(std::move(out.bgr5)), ToArray(std::move(out.height_code)));
      },
      py::arg("packed"));
  m.def(
      "rgb_planar",
      [](py::handle bgr) {
        const Image image = Image8(bgr, "bgr", false);
        PlanarImage out;
        {
          ReleaseGil release;
          out = RgbToPlanar(image.mat);
        }
        return ToArray(out);
      },
      py::arg("bgr"));
  m.def(
      "rgbh_planar",
      [](py::handle packed, const std::string& layout) {
        const Image image = Image8(packed, "packed", false);
        const NetworkInput input = ParseLayout(layout);
        if (input != NetworkInput::kRgbh && input != NetworkInput::kRgbhFixed) {
          ThrowValueError("layout: '" + layout + "' is not an RGB-H layout (rgbh, rgbh-fixed)");
        }
        PlanarImage out;
        {
          ReleaseGil release;
          out = RgbhToPlanar(image.mat, input);
        }
        return ToArray(out);
      },
      py::arg("packed"), py::arg("layout"));
  m.def(
      "rgbd_planar",
      [](py::handle bgr, py::handle depth_code, py::handle height_code,
         const DepthQuantization& depth) {
        const Image image = Image8(bgr, "bgr", false);
        const CodeImage d = Codes(depth_code, "depth_code"), h = Codes(height_code, "height_code");
        CheckSameSize(image.mat, d.mat, "bgr", "depth_code");
        CheckSameSize(image.mat, h.mat, "bgr", "height_code");
        PlanarImage out;
        {
          ReleaseGil release;
          out = RgbdToPlanar(image.mat, d.mat, h.mat, depth);
        }
        return ToArray(out);
      },
      py::arg("bgr"), py::arg("depth_code"), py::arg("height_code"), py::arg("depth"));
  m.def(
      "point_cloud",
      [](py::handle disparity, py::handle left, const Calibration& calib, py::handle ground,
         const PointCloudOptions& options) {
        const FloatImage d = Float32(disparity, "disparity");
        const Image image = Image8(left, "left", true);
        CheckSameSize(d.mat, image.mat, "disparity", "left");
        const StereoGeometry geometry = GeometryOf(calib);
        const GroundPlane plane = GroundFrom(ground);
        std::vector<VeloPoint> points;
        {
          ReleaseGil release;
          points = StereoPointCloud(d.mat, ToGrey(image.mat), geometry, plane, options);
        }
        return PointsToArray(points);
      },
      py::arg("disparity"), py::arg("left"), py::arg("calib"), py::arg("ground"),
      py::arg("options"));
  m.def(
      "encode",
      [](py::handle left, py::handle right, const Calibration& calib, const StereoOptions& options,
         bool rgbh, bool depth, bool points) {
        const Image l = Image8(left, "left", false), r = Image8(right, "right", false);
        CheckSameSize(l.mat, r.mat, "left", "right");
        const StereoGeometry geometry = GeometryOf(calib);
        StereoOutputs outputs;
        outputs.rgbh = rgbh;
        outputs.depth = depth;
        outputs.points = points;
        StereoEncoding e;
        {
          ReleaseGil release;
          StereoEncoder encoder(options);
          e = encoder.Encode(l.mat, r.mat, geometry, outputs);
          // The network image may share the caller's left image: a copy that outlives it.
          if (e.network_image.data == l.mat.data) e.network_image = e.network_image.clone();
        }
        py::dict out;
        out["network_image"] = ToArray(std::move(e.network_image));
        out["disparity"] = ToArray(std::move(e.disparity_px));
        out["ground"] = GroundFitToDict(e.ground);
        out["height_code"] = ToArray(std::move(e.height_code));
        if (depth) out["depth_code"] = ToArray(std::move(e.depth_code));
        if (rgbh) out["rgbh"] = ToArray(std::move(e.rgbh));
        if (points) out["points"] = PointsToArray(e.points);
        return out;
      },
      py::arg("left"), py::arg("right"), py::arg("calib"), py::arg("options"), py::arg("rgbh"),
      py::arg("depth"), py::arg("points"));
}
