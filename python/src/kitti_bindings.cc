// stereodet._core's KITTI I/O: label and detection files as annotation dicts (annos.h),
// calibrations as a Calibration object, velodyne scans as (N, 4) float32 arrays.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "annos.h"
#include "common.h"
#include "stereodet/geometry/calibration.h"
#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/kitti/velodyne_io.h"

namespace stereodet::python {

namespace {

namespace fs = std::filesystem;

ObjectFileKind ParseKind(const std::string& kind) {
  if (kind == "label") return ObjectFileKind::kLabel;
  if (kind == "detection") return ObjectFileKind::kDetection;
  if (kind == "any") return ObjectFileKind::kAny;
  ThrowValueError("kind: unknown '" + kind + "' (label, detection, any)");
}

// The dict and the lenient mode's problems.
py::tuple ObjectFileToPython(const ObjectFile& file, ObjectFileKind kind) {
  bool with_score = kind == ObjectFileKind::kDetection;
  for (const Object& o : file.objects) with_score = with_score || o.score.has_value();
  py::list problems;
  for (const std::string& p : file.problems) problems.append(p);
  return py::make_tuple(AnnosFromObjects(file.objects, with_score), problems);
}

// The objects of a dict to be written: with a score exactly for kind "detection", or, for kind
// None, when the dict has a "score" key.
std::vector<Object> ObjectsToWrite(py::handle annos, const std::optional<std::string>& kind) {
  bool detections =
      PyMapping_Check(annos.ptr()) && PySequence_Contains(annos.ptr(), py::str("score").ptr()) == 1;
  if (kind.has_value()) {
    const ObjectFileKind k = ParseKind(*kind);
    if (k == ObjectFileKind::kAny) ThrowValueError("kind: 'any' is for reading (label, detection)");
    detections = k == ObjectFileKind::kDetection;
  }
  std::vector<Object> objects = ObjectsFromAnnos(annos, detections, "annos");
  if (!detections) {
    for (Object& o : objects) o.score.reset();
  }
  return objects;
}

// --- Calibration ---

// A calibration of NaN or inf would project every point to NaN pixels, and every consumer would
// drop them without a word: refused where it enters, naming the matrix and the element.
void CheckFinite(double v, const std::string& what, const std::string& where) {
  if (!std::isfinite(v)) ThrowValueError(what + ": element " + where + " is not finite");
}

template <int Rows, int Cols>
Eigen::Matrix<double, Rows, Cols> MatrixFrom(py::handle value, const std::string& what) {
  auto a = NumericArray<double>(value, what);
  if (a.ndim() != 2 || a.shape(0) != Rows || a.shape(1) != Cols) {
    ThrowValueError(what + ": expected shape (" + std::to_string(Rows) + ", " +
                    std::to_string(Cols) + "), got " + Describe(a));
  }
  Eigen::Matrix<double, Rows, Cols> m;
  for (int r = 0; r < Rows; ++r) {
    for (int c = 0; c < Cols; ++c) {
      m(r, c) = a.at(r, c);
      CheckFinite(m(r, c), what, "(" + std::to_string(r) + ", " + std::to_string(c) + ")");
    }
  }
  return m;
}

// A rigid transform from a (3, 4) [R | t] or a (4, 4) homogeneous matrix (last row 0 0 0 1).
Eigen::Isometry3d IsometryFrom(py::handle value, const std::string& what) {
  auto a = NumericArray<double>(value, what);
  if (a.ndim() != 2 || a.shape(1) != 4 || (a.shape(0) != 3 && a.shape(0) != 4)) {
    ThrowValueError(what + ": expected shape (3, 4) or (4, 4), got " + Describe(a));
  }
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      t.matrix()(r, c) = a.at(r, c);
      CheckFinite(a.at(r, c), what, "(" + std::to_string(r) + ", " + std::to_string(c) + ")");
    }
  }
  if (a.shape(0) == 4 &&
      !(a.at(3, 0) == 0 && a.at(3, 1) == 0 && a.at(3, 2) == 0 && a.at(3, 3) == 1)) {
    ThrowValueError(what + ": the last row of a (4, 4) transform must be 0 0 0 1");
  }
  return t;
}

py::array_t<double> Projections(const Calibration& c) {
  py::array_t<double> out({4, 3, 4});
  auto v = out.mutable_unchecked<3>();
  for (int i = 0; i < 4; ++i) {
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 4; ++k) v(i, r, k) = c.projection[i](r, k);
    }
  }
  return out;
}

void SetProjections(Calibration& c, py::handle value) {
  auto a = NumericArray<double>(value, "projection");
  if (a.ndim() != 3 || a.shape(0) != 4 || a.shape(1) != 3 || a.shape(2) != 4) {
    ThrowValueError("projection: expected shape (4, 3, 4) (P0..P3), got " + Describe(a));
  }
  for (int i = 0; i < 4; ++i) {
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 4; ++k) {
        CheckFinite(a.at(i, r, k), "projection",
                    "(" + std::to_string(i) + ", " + std::to_string(r) + ", " + std::to_string(k) +
                        ") of P" + std::to_string(i));
      }
    }
  }
  for (int i = 0; i < 4; ++i) {
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 4; ++k) c.projection[i](r, k) = a.at(i, r, k);
    }
  }
}

Eigen::Matrix<double, 3, 4> TopRows(const Eigen::Isometry3d& t) { return t.matrix().topRows<3>(); }

// (N, 3) points or (N, 2) pixels.
NumericArrayT<double> Rows(py::handle value, int cols, const std::string& what) {
  auto a = NumericArray<double>(value, what);
  if (a.ndim() != 2 || a.shape(1) != cols) {
    ThrowValueError(what + ": expected shape (N, " + std::to_string(cols) + "), got " +
                    Describe(a));
  }
  return a;
}

void CheckCamera(int camera) {
  if (camera < 0 || camera > 3)
    ThrowValueError("camera must be 0..3, got " + std::to_string(camera));
}

// --- Velodyne ---

py::array_t<float> PointsToArray(const std::vector<VeloPoint>& points) {
  py::array_t<float> out({static_cast<py::ssize_t>(points.size()), py::ssize_t{4}});
  if (!points.empty())
    std::memcpy(out.mutable_data(), points.data(), points.size() * sizeof(VeloPoint));
  return out;
}

std::vector<VeloPoint> PointsFromArray(py::handle value, const std::string& what) {
  auto a = NumericArray<float>(value, what);
  if (a.ndim() != 2 || a.shape(1) != 4) {
    ThrowValueError(what + ": expected shape (N, 4) (x, y, z, reflectance), got " + Describe(a));
  }
  std::vector<VeloPoint> points(a.shape(0));
  if (!points.empty()) {
    std::memcpy(static_cast<void*>(points.data()), a.data(), points.size() * sizeof(VeloPoint));
  }
  return points;
}

}  // namespace

void BindKitti(py::module_& m) {
  // --- Labels and detections. ---
  m.def(
      "_parse_objects",
      [](const std::string& text, const std::string& source, const std::string& kind,
         bool lenient) {
        ObjectParseOptions options;
        options.kind = ParseKind(kind);
        options.lenient = lenient;
        ObjectFile file;
        {
          ReleaseGil release;
          file = ParseObjects(text, source, options);
        }
        return ObjectFileToPython(file, options.kind);
      },
      py::arg("text"), py::arg("source"), py::arg("kind"), py::arg("lenient"));
  m.def(
      "_read_objects",
      [](const fs::path& path, const std::string& kind, bool lenient) {
        ObjectParseOptions options;
        options.kind = ParseKind(kind);
        options.lenient = lenient;
        ObjectFile file;
        {
          ReleaseGil release;
          file = ReadObjects(path, options);
        }
        return ObjectFileToPython(file, options.kind);
      },
      py::arg("path"), py::arg("kind"), py::arg("lenient"));
  m.def(
      "_format_objects",
      [](py::handle annos, const std::optional<std::string>& kind) {
        const std::vector<Object> objects = ObjectsToWrite(annos, kind);
        ReleaseGil release;
        return FormatObjects(objects);
      },
      py::arg("annos"), py::arg("kind"));
  m.def(
      "_write_objects",
      [](const fs::path& path, py::handle annos, const std::optional<std::string>& kind) {
        const std::vector<Object> objects = ObjectsToWrite(annos, kind);
        ReleaseGil release;
        WriteObjects(path, objects);
      },
      py::arg("path"), py::arg("annos"), py::arg("kind"));

  // --- Calibration. ---
  py::class_<Calibration>(m, "Calibration",
                          R"(A KITTI calibration: the four rectified cameras and the LiDAR.

Frames (as in the C++ library, geometry/calibration.h): velo (the Velodyne: x forward, y left,
z up), cam0 (the unrectified reference camera), rect (the rectified frame of camera 0, where
labels live: x right, y down, z forward), imu. Matrices are numpy float64 copies: assign a whole
matrix to change one.

  projection      (4, 3, 4)  P0..P3: rect -> homogeneous pixels of camera i   (KITTI's P0..P3)
  rect_from_cam0  (3, 3)     R0_rect
  cam0_from_velo  (4, 4)     Tr_velo_to_cam (set from (3, 4) or (4, 4))
  velo_from_imu   (4, 4)     Tr_imu_to_velo

Cameras 2 (left colour) and 3 (right colour) are the stereo pair. to_kitti_dict() and
from_kitti_dict() use KITTI's own key names. Calibrations pickle (exactly, through KITTI's text).)")
      .def(py::init([](py::object projection, py::object rect_from_cam0, py::object cam0_from_velo,
                       py::object velo_from_imu) {
             Calibration c;
             if (!projection.is_none()) SetProjections(c, projection);
             if (!rect_from_cam0.is_none()) {
               c.rect_from_cam0 = MatrixFrom<3, 3>(rect_from_cam0, "rect_from_cam0");
             }
             if (!cam0_from_velo.is_none())
               c.cam0_from_velo = IsometryFrom(cam0_from_velo, "cam0_from_velo");
             if (!velo_from_imu.is_none())
               c.velo_from_imu = IsometryFrom(velo_from_imu, "velo_from_imu");
             return c;
           }),
           py::kw_only(), py::arg("projection") = py::none(),
           py::arg("rect_from_cam0") = py::none(), py::arg("cam0_from_velo") = py::none(),
           py::arg("velo_from_imu") = py::none(),
           "Zero projections and identity transforms unless given.")
      .def_property("projection", &Projections, &SetProjections, "(4, 3, 4) P0..P3")
      .def_property(
          "rect_from_cam0",
          [](const Calibration& c) -> Eigen::Matrix3d { return c.rect_from_cam0; },
          [](Calibration& c, py::handle v) {
            c.rect_from_cam0 = MatrixFrom<3, 3>(v, "rect_from_cam0");
          },
          "(3, 3) R0_rect")
      .def_property(
          "cam0_from_velo",
          [](const Calibration& c) -> Eigen::Matrix4d { return c.cam0_from_velo.matrix(); },
          [](Calibration& c, py::handle v) {
            c.cam0_from_velo = IsometryFrom(v, "cam0_from_velo");
          },
          "(4, 4) Tr_velo_to_cam")
      .def_property(
          "velo_from_imu",
          [](const Calibration& c) -> Eigen::Matrix4d { return c.velo_from_imu.matrix(); },
          [](Calibration& c, py::handle v) { c.velo_from_imu = IsometryFrom(v, "velo_from_imu"); },
          "(4, 4) Tr_imu_to_velo")
      .def_property_readonly("focal_px", &Calibration::FocalPx, "P2(0, 0), pixels")
      .def_property_readonly(
          "principal_point_px",
          [](const Calibration& c) -> Eigen::Vector2d { return c.PrincipalPointPx(); },
          "(P2(0, 2), P2(1, 2)), pixels")
      .def_property_readonly(
          "baseline_m", &Calibration::BaselineM,
          "camera 3's centre minus camera 2's along rect x, metres (~0.54 on KITTI)")
      .def_property_readonly(
          "rect_from_velo",
          [](const Calibration& c) -> Eigen::Matrix4d { return c.RectFromVelo().matrix(); },
          "(4, 4) R0_rect * Tr_velo_to_cam")
      .def(
          "camera_centre_in_rect",
          [](const Calibration& c, int camera) -> Eigen::Vector3d {
            CheckCamera(camera);
            return c.CameraCentreInRect(camera);
          },
          py::arg("camera"), "Centre of camera 0..3 in the rect frame, metres.")
      .def(
          "project_rect_to_image",
          [](const Calibration& c, py::handle points, int camera) {
            CheckCamera(camera);
            auto p = Rows(points, 3, "points_in_rect");
            const py::ssize_t n = p.shape(0);
            py::array_t<double> pixels({n, py::ssize_t{2}}), depth(n);
            auto in = p.unchecked<2>();
            auto px = pixels.mutable_unchecked<2>();
            auto z = depth.mutable_unchecked<1>();
            for (py::ssize_t i = 0; i < n; ++i) {
              double depth_m = 0;
              const Eigen::Vector2d uv =
                  c.ProjectRectToImage({in(i, 0), in(i, 1), in(i, 2)}, camera, &depth_m);
              px(i, 0) = uv.x();
              px(i, 1) = uv.y();
              z(i) = depth_m;
            }
            return py::make_tuple(pixels, depth);
          },
          py::arg("points_in_rect"), py::arg("camera") = 2,
          "(N, 3) rect-frame points -> ((N, 2) pixels of `camera`, (N,) depth in front of it, m).\n"
          "Pixels of points with depth <= 0 (behind the camera) are meaningless.")
      .def(
          "unproject_image_to_rect",
          [](const Calibration& c, py::handle pixels, py::handle depth_m, int camera) {
            CheckCamera(camera);
            auto uv = Rows(pixels, 2, "pixels");
            auto z = NumericArray<double>(depth_m, "depth_m");
            const py::ssize_t n = uv.shape(0);
            if (z.ndim() != 1 || z.shape(0) != n) {
              ThrowValueError("depth_m: expected shape (" + std::to_string(n) + ",), got " +
                              Describe(z));
            }
            py::array_t<double> out({n, py::ssize_t{3}});
            auto o = out.mutable_unchecked<2>();
            for (py::ssize_t i = 0; i < n; ++i) {
              const Eigen::Vector3d p =
                  c.UnprojectImageToRect({uv.at(i, 0), uv.at(i, 1)}, z.at(i), camera);
              for (int k = 0; k < 3; ++k) o(i, k) = p[k];
            }
            return out;
          },
          py::arg("pixels"), py::arg("depth_m"), py::arg("camera") = 2,
          "(N, 2) pixels of `camera` at (N,) depths (m) -> (N, 3) rect-frame points.")
      .def("check_stereo", &Calibration::CheckStereo,
           "Raises ValueError if cameras 2 and 3 cannot serve as a stereo pair.")
      .def(
          "to_kitti_dict",
          [](const Calibration& c) {
            py::dict d;
            const char* keys[] = {"P0", "P1", "P2", "P3"};
            for (int i = 0; i < 4; ++i) d[keys[i]] = Eigen::Matrix<double, 3, 4>(c.projection[i]);
            d["R0_rect"] = Eigen::Matrix3d(c.rect_from_cam0);
            d["Tr_velo_to_cam"] = TopRows(c.cam0_from_velo);
            d["Tr_imu_to_velo"] = TopRows(c.velo_from_imu);
            return d;
          },
          "KITTI's keys: P0..P3 (3, 4), R0_rect (3, 3), Tr_velo_to_cam and Tr_imu_to_velo (3, 4).")
      .def_static(
          "from_kitti_dict",
          [](py::dict d) {
            Calibration c;
            const char* keys[] = {"P0", "P1", "P2", "P3"};
            for (int i = 0; i < 4; ++i) {
              const std::string key = keys[i];
              if (!d.contains(key)) ThrowValueError("missing key '" + key + "'");
              c.projection[i] = MatrixFrom<3, 4>(d[py::str(key)], key);
            }
            if (!d.contains("R0_rect")) ThrowValueError("missing key 'R0_rect'");
            c.rect_from_cam0 = MatrixFrom<3, 3>(d["R0_rect"], "R0_rect");
            if (!d.contains("Tr_velo_to_cam")) ThrowValueError("missing key 'Tr_velo_to_cam'");
            c.cam0_from_velo = IsometryFrom(d["Tr_velo_to_cam"], "Tr_velo_to_cam");
            if (d.contains("Tr_imu_to_velo")) {
              c.velo_from_imu = IsometryFrom(d["Tr_imu_to_velo"], "Tr_imu_to_velo");
            }
            return c;
          },
          py::arg("kitti"),
          "From KITTI's keys (to_kitti_dict's); Tr_imu_to_velo is optional (identity).")
      .def_static("kitti_like", &KittiLikeCalibration,
                  "The calibration of KITTI object frame 000000 (for tests and synthetic data).")
      .def("__eq__",
           [](const Calibration& a, const Calibration& b) {
             return a.projection == b.projection && a.rect_from_cam0 == b.rect_from_cam0 &&
                    a.cam0_from_velo.matrix() == b.cam0_from_velo.matrix() &&
                    a.velo_from_imu.matrix() == b.velo_from_imu.matrix();
           })
      .def("__repr__",
           [](const Calibration& c) {
             return "<stereodet.kitti.Calibration focal_px=" + std::to_string(c.FocalPx()) +
                    " baseline_m=" + std::to_string(c.BaselineM()) + ">";
           })
      .def(py::pickle([](const Calibration& c) { return FormatCalibration(c); },
                      [](const std::string& text) { return ParseCalibration(text, "<pickle>"); }));

  m.def(
      "_parse_calib",
      [](const std::string& text, const std::string& source) {
        ReleaseGil release;
        return ParseCalibration(text, source);
      },
      py::arg("text"), py::arg("source"));
  m.def(
      "_read_calib",
      [](const fs::path& path) {
        ReleaseGil release;
        return ReadCalibration(path);
      },
      py::arg("path"));
  m.def(
      "_format_calib",
      [](const Calibration& calib) {
        ReleaseGil release;
        return FormatCalibration(calib);
      },
      py::arg("calib"));
  m.def(
      "_write_calib",
      [](const fs::path& path, const Calibration& calib) {
        ReleaseGil release;
        WriteCalibration(path, calib);
      },
      py::arg("path"), py::arg("calib"));

  // --- Velodyne scans. ---
  m.def(
      "_read_velodyne",
      [](const fs::path& path) {
        std::vector<VeloPoint> points;
        {
          ReleaseGil release;
          points = ReadVelodyne(path);
        }
        return PointsToArray(points);
      },
      py::arg("path"));
  m.def(
      "_write_velodyne",
      [](const fs::path& path, py::handle points) {
        const std::vector<VeloPoint> p = PointsFromArray(points, "points");
        ReleaseGil release;
        WriteVelodyne(path, p);
      },
      py::arg("path"), py::arg("points"));
}

}  // namespace stereodet::python
