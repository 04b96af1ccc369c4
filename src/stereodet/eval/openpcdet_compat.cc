#include "stereodet/eval/openpcdet_compat.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/openpcdet_compat_internal.h"
#include "stereodet/util/check.h"

// This file is compiled with -ffp-contract=off (CMakeLists.txt): the rotated-box port below rounds
// every float32 and float64 operation where numpy does, and a fused multiply-add would round once
// instead of twice and move a corner by an ulp, which is what decides the degenerate cases.

namespace stereodet {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The kernel's local array int_pts holds 8 points (16 floats).
constexpr int kMaxPoints = 8;

// The numpy types of rotate_iou.py as the CUDA simulator runs it: local and shared arrays are
// float32, so every value stored into one is rounded to float32; arithmetic between two float32
// scalars is float32; a Python float or int (math.cos, math.sqrt, literals) with a float32 scalar
// gives float64. Each line below says which.

// rbbox_to_corners: corners (-l/2, -w/2), (-l/2, w/2), (l/2, w/2), (l/2, -w/2) turned by the angle,
// computed in float64 (math.cos is a Python float) and stored as float32.
void RboxToCorners(const float rbox[5], float corners[8]) {
  const double a_cos = std::cos(static_cast<double>(rbox[4]));
  const double a_sin = std::sin(static_cast<double>(rbox[4]));
  const float x_d = rbox[2], y_d = rbox[3];
  // -x_d / 2: float32 negation, float64 halving (exact), stored float32.
  const float cx[4] = {static_cast<float>(static_cast<double>(-x_d) / 2),
                       static_cast<float>(static_cast<double>(-x_d) / 2),
                       static_cast<float>(static_cast<double>(x_d) / 2),
                       static_cast<float>(static_cast<double>(x_d) / 2)};
  const float cy[4] = {static_cast<float>(static_cast<double>(-y_d) / 2),
                       static_cast<float>(static_cast<double>(y_d) / 2),
                       static_cast<float>(static_cast<double>(y_d) / 2),
                       static_cast<float>(static_cast<double>(-y_d) / 2)};
  for (int i = 0; i < 4; ++i) {
    corners[2 * i] =
        static_cast<float>(a_cos * cx[i] + a_sin * cy[i] + static_cast<double>(rbox[0]));
    corners[2 * i + 1] =
        static_cast<float>(-a_sin * cx[i] + a_cos * cy[i] + static_cast<double>(rbox[1]));
  }
}

// point_in_quadrilateral: float32 throughout.
bool PointInQuadrilateral(float pt_x, float pt_y, const float c[8]) {
  const float ab0 = c[2] - c[0], ab1 = c[3] - c[1];
  const float ad0 = c[6] - c[0], ad1 = c[7] - c[1];
  const float ap0 = pt_x - c[0], ap1 = pt_y - c[1];
  const float abab = ab0 * ab0 + ab1 * ab1;
  const float abap = ab0 * ap0 + ab1 * ap1;
  const float adad = ad0 * ad0 + ad1 * ad1;
  const float adap = ad0 * ap0 + ad1 * ap1;
  return abab >= abap && abap >= 0 && adad >= adap && adap >= 0;
}

// line_segment_intersection (the kernel's first version, the one it calls): float32 throughout.
bool LineSegmentIntersection(const float p1[8], const float p2[8], int i, int j, float out[2]) {
  const float a0 = p1[2 * i], a1 = p1[2 * i + 1];
  const float b0 = p1[2 * ((i + 1) % 4)], b1 = p1[2 * ((i + 1) % 4) + 1];
  const float c0 = p2[2 * j], c1 = p2[2 * j + 1];
  const float d0 = p2[2 * ((j + 1) % 4)], d1 = p2[2 * ((j + 1) % 4) + 1];
  const float ba0 = b0 - a0, ba1 = b1 - a1;
  const float da0 = d0 - a0, ca0 = c0 - a0;
  const float da1 = d1 - a1, ca1 = c1 - a1;
  const bool acd = da1 * ca0 > ca1 * da0;
  const bool bcd = (d1 - b1) * (c0 - b0) > (c1 - b1) * (d0 - b0);
  if (acd == bcd) return false;
  const bool abc = ca1 * ba0 > ba1 * ca0;
  const bool abd = da1 * ba0 > ba1 * da0;
  if (abc == abd) return false;
  const float dc0 = d0 - c0, dc1 = d1 - c1;
  const float abba = a0 * b1 - b0 * a1;
  const float cddc = c0 * d1 - d0 * c1;
  const float dh = ba1 * dc0 - ba0 * dc1;
  const float dx = abba * dc0 - ba0 * cddc;
  const float dy = abba * dc1 - ba1 * cddc;
  out[0] = dx / dh;
  out[1] = dy / dh;
  return true;
}

// quadrilateral_intersection: the corners of each inside the other (alternating, as the kernel
// does), then the edge crossings. Returns the number of points, or -1 past kMaxPoints.
int QuadrilateralIntersection(const float p1[8], const float p2[8], float pts[2 * kMaxPoints]) {
  int n = 0;
  auto add = [&](float x, float y) {
    if (n >= kMaxPoints) return false;
    pts[2 * n] = x;
    pts[2 * n + 1] = y;
    ++n;
    return true;
  };
  for (int i = 0; i < 4; ++i) {
    if (PointInQuadrilateral(p1[2 * i], p1[2 * i + 1], p2) && !add(p1[2 * i], p1[2 * i + 1]))
      return -1;
    if (PointInQuadrilateral(p2[2 * i], p2[2 * i + 1], p1) && !add(p2[2 * i], p2[2 * i + 1]))
      return -1;
  }
  float t[2];
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      if (LineSegmentIntersection(p1, p2, i, j, t) && !add(t[0], t[1])) return -1;
    }
  }
  return n;
}

// sort_vertex_in_convex_polygon: the key of a point is its direction from the centroid, cos-like
// in [-1, 1] above and -2 - cos below; insertion sort on it.
void SortVertices(float pts[2 * kMaxPoints], int n) {
  if (n <= 0) return;
  float center0 = 0, center1 = 0;
  for (int i = 0; i < n; ++i) {
    center0 += pts[2 * i];  // float32 += float32
    center1 += pts[2 * i + 1];
  }
  center0 = static_cast<float>(static_cast<double>(center0) / n);  // float32 / int: float64
  center1 = static_cast<float>(static_cast<double>(center1) / n);
  float vs[kMaxPoints];
  for (int i = 0; i < n; ++i) {
    float v0 = pts[2 * i] - center0;
    float v1 = pts[2 * i + 1] - center1;
    const double d = std::sqrt(static_cast<double>(v0 * v0 + v1 * v1));  // math.sqrt: float64
    v0 = static_cast<float>(static_cast<double>(v0) / d);
    v1 = static_cast<float>(static_cast<double>(v1) / d);
    if (v1 < 0) v0 = static_cast<float>(-2.0 - static_cast<double>(v0));
    vs[i] = v0;
  }
  for (int i = 1; i < n; ++i) {
    if (!(vs[i - 1] > vs[i])) continue;
    const float temp = vs[i];
    const float tx = pts[2 * i], ty = pts[2 * i + 1];
    int j = i;
    while (j > 0 && vs[j - 1] > temp) {
      vs[j] = vs[j - 1];
      pts[2 * j] = pts[2 * j - 2];
      pts[2 * j + 1] = pts[2 * j - 1];
      --j;
    }
    vs[j] = temp;
    pts[2 * j] = tx;
    pts[2 * j + 1] = ty;
  }
}

// trangle_area: float32 cross product, halved in float64.
double TriangleArea(const float* a, const float* b, const float* c) {
  const float cross = (a[0] - c[0]) * (b[1] - c[1]) - (a[1] - c[1]) * (b[0] - c[0]);
  return static_cast<double>(cross) / 2.0;
}

// area: a fan from the first point, float64 sum of absolute triangle areas.
double PolygonArea(const float pts[2 * kMaxPoints], int n) {
  double area = 0.0;
  for (int i = 0; i < n - 2; ++i) {
    area += std::abs(TriangleArea(pts, pts + 2 * i + 2, pts + 2 * i + 4));
  }
  return area;
}

void ToFloat32(const PcdetRotatedBox& b, float out[5]) {
  out[0] = static_cast<float>(b.x);
  out[1] = static_cast<float>(b.z);
  out[2] = static_cast<float>(b.l);
  out[3] = static_cast<float>(b.w);
  out[4] = static_cast<float>(b.rotation_y);
}

// The y overlap of two KITTI boxes (bottom at y, top at y - h), as d3_box_overlap_kernel.
double HeightOverlap(const Box3D& d, const Box3D& g) {
  return std::min(d.location.y(), g.location.y()) -
         std::max(d.location.y() - d.h, g.location.y() - g.h);
}

}  // namespace

PcdetRotatedBox PcdetFootprint(const Box3D& box) {
  return PcdetRotatedBox{box.location.x(), box.location.z(), box.l, box.w, box.rotation_y};
}

double PcdetIntersectionArea(const PcdetRotatedBox& rbox1, const PcdetRotatedBox& rbox2) {
  float r1[5], r2[5], c1[8], c2[8], pts[2 * kMaxPoints];
  ToFloat32(rbox1, r1);
  ToFloat32(rbox2, r2);
  RboxToCorners(r1, c1);
  RboxToCorners(r2, c2);
  const int n = QuadrilateralIntersection(c1, c2, pts);
  if (n < 0) return kNaN;
  SortVertices(pts, n);
  return PolygonArea(pts, n);
}

double PcdetOverlap(OverlapKind kind, const Object& detection, const Object& label) {
  switch (kind) {
    case OverlapKind::k2D:
      return KittiOverlap(kind, detection, label);
    case OverlapKind::kBev: {
      // devRotateIoUEval(rbox1 = label, rbox2 = detection): float32 areas and their float32 sum,
      // float64 ratio, stored float32.
      const PcdetRotatedBox g = PcdetFootprint(label.box3d), d = PcdetFootprint(detection.box3d);
      const double inter = PcdetIntersectionArea(g, d);
      const float area1 = static_cast<float>(g.l) * static_cast<float>(g.w);
      const float area2 = static_cast<float>(d.l) * static_cast<float>(d.w);
      const float sum = area1 + area2;
      return static_cast<float>(inter / (static_cast<double>(sum) - inter));
    }
    case OverlapKind::k3D: {
      // rotate_iou_gpu_eval(criterion 2) stores the intersection as float32; d3_box_overlap_kernel
      // then works in float64 on the detection (boxes) and the label (qboxes), volumes l * h * w.
      const double rinc = static_cast<float>(
          PcdetIntersectionArea(PcdetFootprint(label.box3d), PcdetFootprint(detection.box3d)));
      if (!(rinc > 0)) return rinc;  // 0, or NaN kept
      const Box3D& d = detection.box3d;
      const Box3D& g = label.box3d;
      const double iw = HeightOverlap(d, g);
      if (!(iw > 0)) return 0.0;
      const double area1 = d.l * d.h * d.w;
      const double area2 = g.l * g.h * g.w;
      const double inc = iw * rinc;
      return inc / (area1 + area2 - inc);
    }
    case OverlapKind::kLetBev:  // EvalOptions::Check refuses LET with --compat openpcdet
    case OverlapKind::kLet3D:
      break;
  }
  STEREODET_CHECK(false) << "OpenPCDet has no " << OverlapKindName(kind) << " overlap";
  return 0.0;
}

ClassSpec OpenPcdetClassSpec(const std::string& name, bool loose) {
  struct Row {
    const char* name;
    std::array<double, kNumOverlapKinds> strict, loose;
  };
  static constexpr Row kRows[] = {
      {"Car", {0.7, 0.7, 0.7}, {0.7, 0.5, 0.5}},
      {"Pedestrian", {0.5, 0.5, 0.5}, {0.5, 0.25, 0.25}},
      {"Cyclist", {0.5, 0.5, 0.5}, {0.5, 0.25, 0.25}},
      {"Van", {0.7, 0.7, 0.7}, {0.7, 0.5, 0.5}},
      {"Person_sitting", {0.5, 0.5, 0.5}, {0.5, 0.25, 0.25}},
      {"Truck", {0.7, 0.7, 0.7}, {0.5, 0.5, 0.5}},
  };
  const Row* found = nullptr;
  for (const Row& row : kRows) {
    if (EqualsIgnoreCase(name, row.name)) found = &row;
  }
  STEREODET_CHECK(found != nullptr)
      << "class '" << name
      << "': OpenPCDet's evaluation knows only Car, Pedestrian, Cyclist, Van, Person_sitting and "
         "Truck";
  ClassSpec spec;
  spec.name = found->name;
  if (EqualsIgnoreCase(name, "Car")) spec.neighbours = {"Van"};
  if (EqualsIgnoreCase(name, "Pedestrian")) spec.neighbours = {"Person_sitting"};
  spec.min_overlap = loose ? found->loose : found->strict;
  // (OpenPCDet has no LET kinds; EvalOptions::Check refuses them with --compat openpcdet. Their
  // thresholds follow BEV and 3D, as KittiClassSpec's.)
  spec.min_overlap[3] = spec.min_overlap[1];
  spec.min_overlap[4] = spec.min_overlap[2];
  return spec;
}

ClassFrame PrepareClassFrameOpenPcdet(const EvalFrame& frame, const ClassSpec& spec,
                                      OverlapKind kind, ClassFrame reuse) {
  const double tau = spec.min_overlap[static_cast<int>(kind)];

  // clean_data: labels of the class (valid unless ignored at the difficulty) or of a neighbour
  // class (always ignored); DontCare regions by their exact name.
  ClassFrameBuilder builder(std::move(reuse));
  builder.AddLabels(frame, spec, true);
  const std::vector<const Object*>& dontcares = builder.dontcares();

  // Detections: the class, or lower than 40 px (ignored at Easy whatever the class), as the devkit.
  // The DontCare test (intersection over the detection's area > tau) exists for 2D only.
  builder.AddDetections(frame, spec, [&](const Object& det) {
    if (kind != OverlapKind::k2D) return false;
    for (const Object* dc : dontcares) {
      if (KittiDontCareOverlap(OverlapKind::k2D, det, *dc) > tau) return true;
    }
    return false;
  });
  ClassFrame cf = builder.Take();
  cf.min_overlap = tau;

  cf.edge_begin.assign(1, 0);
  for (int i = 0; i < cf.num_labels(); ++i) {
    const Object& label = frame.labels[cf.label_object[i]];
    for (int j = 0; j < cf.num_dets(); ++j) {
      const double overlap = PcdetOverlap(kind, frame.detections[cf.det_object[j]], label);
      if (overlap >= tau) {  // NaN fails, as the tool's `overlap > min_overlap`
        cf.edge_det.push_back(j);
        cf.edge_overlap.push_back(overlap);
      }
    }
    cf.edge_begin.push_back(static_cast<int32_t>(cf.edge_det.size()));
  }
  return cf;
}

bool OpenPcdetComputesAos(const std::vector<EvalFrame>& frames) {
  for (const EvalFrame& frame : frames) {
    if (!frame.detections.empty()) return frame.detections.front().alpha != -10;
  }
  return false;
}

std::array<double, 41> OpenPcdetEnvelope(std::array<double, 41> c) {
  for (size_t i = 0; i < c.size(); ++i) {
    double m = c[i];
    for (size_t k = i; k < c.size(); ++k) {
      if (std::isnan(c[k])) {
        m = kNaN;
        break;
      }
      m = std::max(m, c[k]);
    }
    c[i] = m;
  }
  return c;
}

std::string FormatOpenPcdetResult(const EvalResult& strict, const EvalResult& loose) {
  std::string out;
  std::vector<std::string> classes;
  for (const ClassResult& r : strict.results) {
    if (std::find(classes.begin(), classes.end(), r.class_name) == classes.end()) {
      classes.push_back(r.class_name);
    }
  }
  const Difficulty kLevels[] = {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard};
  const OverlapKind kKinds[] = {OverlapKind::k2D, OverlapKind::kBev, OverlapKind::k3D};
  for (const std::string& name : classes) {
    for (const EvalResult* set : {&strict, &loose}) {
      auto find = [&](OverlapKind kind, Difficulty d) { return set->Find(name, kind, d); };
      double tau[3];
      for (int k = 0; k < 3; ++k) {
        const ClassResult* r = find(kKinds[k], Difficulty::kEasy);
        tau[k] = r != nullptr ? r->min_overlap : kNaN;
      }
      const bool aos = set->aos_computed;
      for (const bool r40 : {false, true}) {
        out += fmt::format("{} {}@{:.2f}, {:.2f}, {:.2f}:\n", name, r40 ? "AP_R40" : "AP", tau[0],
                           tau[1], tau[2]);
        auto ap = [&](OverlapKind kind, Difficulty d, bool orientation) {
          const ClassResult* r = find(kind, d);
          if (r == nullptr || !r->evaluated) return kNaN;
          if (orientation) return r40 ? r->aos_r40 : r->aos_r11;
          return r40 ? r->ap_r40 : r->ap_r11;
        };
        const char* labels[] = {"bbox AP:", "bev  AP:", "3d   AP:"};
        for (int k = 0; k < 3; ++k) {
          out +=
              fmt::format("{}{:.4f}, {:.4f}, {:.4f}\n", labels[k], ap(kKinds[k], kLevels[0], false),
                          ap(kKinds[k], kLevels[1], false), ap(kKinds[k], kLevels[2], false));
        }
        if (aos) {
          out += fmt::format(
              "aos  AP:{:.2f}, {:.2f}, {:.2f}\n", ap(OverlapKind::k2D, kLevels[0], true),
              ap(OverlapKind::k2D, kLevels[1], true), ap(OverlapKind::k2D, kLevels[2], true));
        }
      }
    }
  }
  return out;
}

std::string OpenPcdetPrintout(const std::vector<EvalFrame>& frames, const EvalOptions& options) {
  EvalOptions base;
  base.matcher = Matcher::kKitti;
  base.compat = EvalCompat::kOpenPcdet;
  base.num_threads = options.num_threads;
  EvalOptions strict = base, loose = base;
  strict.classes.clear();
  loose.classes.clear();
  for (const ClassSpec& c : options.classes) {
    strict.classes.push_back(OpenPcdetClassSpec(c.name, false));
    loose.classes.push_back(OpenPcdetClassSpec(c.name, true));
  }
  return FormatOpenPcdetResult(Evaluate(frames, strict), Evaluate(frames, loose));
}

}  // namespace stereodet
