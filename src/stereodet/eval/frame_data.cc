#include "stereodet/eval/frame_data.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <optional>
#include <utility>
#include <vector>

#include "stereodet/eval/devkit_overlap_internal.h"
#include "stereodet/eval/frame_data_internal.h"
#include "stereodet/eval/let.h"
#include "stereodet/geometry/iou.h"
#include "stereodet/util/check.h"

namespace stereodet {

namespace {

// The devkit evaluates a detection lower than MIN_HEIGHT[difficulty] as "ignored" whatever its
// class; 40 px is the largest MIN_HEIGHT, so lower detections of other classes may matter.
constexpr double kLargestMinHeightPx = 40.0;

// The devkit's footprint polygon: corners (+-l/2, +-w/2) turned by rotation_y. With l and w both
// negative it is the same square as with |l|, |w| (a half turn); with one side <= 0 boost sees a
// degenerate or reversed ring, which we treat as having no area.
bool Footprint(const Box3D& box, Box3D* out) {
  *out = box;
  if (box.l < 0 && box.w < 0) {
    out->l = -box.l;
    out->w = -box.w;
  }
  return out->l > 0 && out->w > 0;
}

double FootprintIntersection(const Box3D& a, const Box3D& b) {
  Box3D fa, fb;
  if (!Footprint(a, &fa) || !Footprint(b, &fb)) return 0.0;
  // Most pairs of a frame are far apart. BevIntersectionArea returns 0 for them too, from its test
  // of the circumscribed circles, but that costs two hypot calls: a half-diagonal is at most half
  // the sum of the two sides, so centres farther apart than all four half sides along x or z, with
  // a margin far above the rounding of either test, are apart in that test as well (sizes kept well
  // inside double's range, so that no square there overflows or underflows).
  const double half_sides = (fa.l + fa.w + fb.l + fb.w) / 2;
  if (half_sides > 1e-100 && half_sides < 1e100) {
    const double reach = half_sides * (1 + 1e-9);
    if (std::abs(fb.location.x() - fa.location.x()) > reach ||
        std::abs(fb.location.z() - fa.location.z()) > reach) {
      return 0.0;
    }
  }
  return BevIntersectionArea(fa, fb);
}

struct ImageOverlapParts {
  double inter = 0.0, det_area = 0.0, label_area = 0.0;
};

// Same arithmetic as the devkit's imageBoxOverlap: returns false when the boxes do not overlap.
bool ImageOverlap(const Box2D& d, const Box2D& g, ImageOverlapParts* parts) {
  const double x1 = std::max(d.left, g.left);
  const double y1 = std::max(d.top, g.top);
  const double x2 = std::min(d.right, g.right);
  const double y2 = std::min(d.bottom, g.bottom);
  const double w = x2 - x1;
  const double h = y2 - y1;
  if (w <= 0 || h <= 0) return false;
  parts->inter = w * h;
  parts->det_area = (d.right - d.left) * (d.bottom - d.top);
  parts->label_area = (g.right - g.left) * (g.bottom - g.top);
  return true;
}

// The 3D intersection of d and g from their footprint intersection `inter_area`.
double IntersectionVolumeDevkit(double inter_area, const Box3D& d, const Box3D& g) {
  const double ymax = std::min(d.location.y(), g.location.y());
  const double ymin = std::max(d.location.y() - d.h, g.location.y() - g.h);
  return inter_area * std::max(0.0, ymax - ymin);
}

bool IsDontCare(const Object& o) { return EqualsIgnoreCase(o.type, "DontCare"); }

// Two footprints whose edges are parallel to within this (radians, modulo 90 degrees) may be ones
// boost 1.74 gets wrong: its integer grid makes nearly parallel edges exactly parallel (measured:
// rotations 1e-7 apart fail like equal ones, 1e-5 apart never did). KITTI's two-decimal rotations
// are either equal or at least 0.01 apart, so the margin costs nothing.
constexpr double kParallelRad = 1e-4;

bool SameFootprint(const Box3D& a, const Box3D& b) {
  return a.l == b.l && a.w == b.w && a.rotation_y == b.rotation_y &&
         a.location.x() == b.location.x() && a.location.z() == b.location.z();
}

// Sides below this (m) make boost's grid coarse against the footprint: on parallel footprints 1-30
// cm wide its overlaps strayed up to 3.4e-5 from the exact ones (2.9e-6 with every side >= 0.2 m).
constexpr double kParallelMinSideM = 0.2;

// Of two parallel footprints (`turn`: their rotation difference modulo 90 degrees, |turn| <=
// kParallelRad), whether every edge line of one lies clear of the parallel edge lines of the other:
// farther than (1e-4 + |turn|) times the sum of the four sides, i.e. well beyond boost's grid
// (~1e-7 of the extent) and the edges' divergence over their length. Boost 1.74 loses intersections
// only where edges are (nearly) collinear, which its grid makes exactly collinear (a footprint
// nested between common end lines); with all lines apart, its overlaps stayed within 2.9e-6 of the
// exact ones on 300,000 parallel pairs (FrameDataTest.ParallelFootprintsWithEdgeLinesApart...), so
// the exact value decides as boost's would. Footprints with a side below kParallelMinSideM are
// never "apart". Requires: both footprints proper (Footprint() true).
bool ParallelEdgeLinesApart(const Box3D& detection, const Box3D& label, double turn) {
  Box3D d, g;
  if (!Footprint(detection, &d) || !Footprint(label, &g)) return false;
  if (std::min({d.l, d.w, g.l, g.w}) < kParallelMinSideM) return false;
  // The detection's centre in the label's (length, width) axes: the devkit's corner (l/2, w/2) goes
  // to (x, z) = (cos ry * l/2 + sin ry * w/2, -sin ry * l/2 + cos ry * w/2).
  const double c = std::cos(g.rotation_y), s = std::sin(g.rotation_y);
  const double dx = d.location.x() - g.location.x(), dz = d.location.z() - g.location.z();
  const double along_l = dx * c - dz * s, along_w = dx * s + dz * c;
  // A quarter turn (odd number of them) puts the detection's length along the label's width.
  const bool quarter =
      std::lround((detection.rotation_y - label.rotation_y - turn) / (std::numbers::pi / 2)) % 2 !=
      0;
  const double det_half_l = (quarter ? d.w : d.l) / 2, det_half_w = (quarter ? d.l : d.w) / 2;
  const double margin = (1e-4 + std::abs(turn)) * (d.l + d.w + g.l + g.w);
  auto apart = [margin](double offset, double det_half, double label_half) {
    // |offset +- det_half -+ label_half| > margin for all four lines
    return std::abs(offset + det_half - label_half) > margin &&
           std::abs(offset + det_half + label_half) > margin &&
           std::abs(offset - det_half - label_half) > margin &&
           std::abs(offset - det_half + label_half) > margin;
  };
  return apart(along_l, det_half_l, g.l / 2) && apart(along_w, det_half_w, g.w / 2);
}

// Whether the devkit may decide `overlap > tau` (or its DontCare test) otherwise than
// KittiOverlap's value `overlap` does, so that its own arithmetic (~10 us, against 0.14 us) is
// worth running:
//  - near tau: our exact clipping and boost's rescaled polygons differ by up to ~1e-6, so an
//    overlap mathematically equal to tau (common with KITTI's two-decimal boxes: a shift by a third
//    of a length, identical footprints shifted in y) lands above tau in one and below in the other;
//  - parallel, non-identical footprints with (nearly) collinear edges: boost 1.74 sometimes returns
//    no intersection when one lies inside the other between common end lines (overlap 0 instead
//    of, say, 0.97). Identical footprints came out exactly 1 in both on 360,000 pairs, and are
//    skipped: evaluating labels against themselves stays fast; so are parallel footprints whose
//    edge lines are all apart (ParallelEdgeLinesApart), where boost stays within 3e-6.
// A zero overlap (apart, or a degenerate footprint the devkit would crash on) and NaN never
// qualify.
// `every_parallel`: every parallel, non-identical pair qualifies, edge lines apart or not (the
// values records report, KittiRecordedOverlap).
bool DevkitMayDecideOtherwise(OverlapKind kind, double overlap, double tau, const Box3D& detection,
                              const Box3D& label, bool every_parallel = false) {
  if (kind == OverlapKind::k2D || !(overlap > 0)) return false;
  if (std::abs(overlap - tau) <= kDevkitTieBand) return true;
  const double turn = std::remainder(detection.rotation_y - label.rotation_y, std::numbers::pi / 2);
  return std::abs(turn) <= kParallelRad && !SameFootprint(detection, label) &&
         (every_parallel || !ParallelEdgeLinesApart(detection, label, turn));
}

// KITTI's pass 2 gives a label the candidate of largest overlap (the first of equal ones). The
// devkit may order two overlaps within kDevkitTieBand of each other otherwise than we do (two
// detections shifted by the same distance either side of a label: ours may differ by an ulp where
// boost's are equal, or the other way round), so such overlaps of the label's edges [first, end)
// take the devkit's values; overlaps farther apart than both arithmetics' errors together compare
// alike in both. The label's `n` edges: ClassFrame::edge_det and edge_overlap from `edge_det` and
// `edge_overlap` on (the latter updated). `scratch` is reused across labels.
void UseDevkitForCloseCandidates(OverlapKind kind, const EvalFrame& frame, const Object& label,
                                 const ClassFrame& cf, const int32_t* edge_det,
                                 double* edge_overlap, size_t n,
                                 std::vector<std::pair<double, size_t>>* scratch) {
  std::vector<std::pair<double, size_t>>& by_overlap = *scratch;
  by_overlap.clear();
  for (size_t e = 0; e < n; ++e) by_overlap.emplace_back(edge_overlap[e], e);
  std::sort(by_overlap.begin(), by_overlap.end());
  for (size_t k = 0; k < by_overlap.size(); ++k) {
    const bool close_below =
        k > 0 && by_overlap[k].first - by_overlap[k - 1].first <= kDevkitTieBand;
    const bool close_above = k + 1 < by_overlap.size() &&
                             by_overlap[k + 1].first - by_overlap[k].first <= kDevkitTieBand;
    if (!close_below && !close_above) continue;
    const size_t e = by_overlap[k].second;
    const Object& det = frame.detections[cf.det_object[edge_det[e]]];
    edge_overlap[e] = DevkitBoxOverlap(kind, DevkitCriterion::kUnion, det.box3d, label.box3d)
                          .value_or(edge_overlap[e]);
  }
}

}  // namespace

namespace {

// KittiOverlap's BEV and 3D values from the pair's footprint intersection (FootprintIntersection),
// which the two share: PrepareClassFrame computes it once for both.
double BevOverlapFromFootprint(const Box3D& d, const Box3D& g, double footprint_intersection) {
  const double inter = footprint_intersection;
  if (inter <= 0) return 0.0;
  const double uni = d.l * d.w + g.l * g.w - inter;
  return inter / uni;
}

double ThreeDOverlapFromFootprint(const Box3D& d, const Box3D& g, double footprint_intersection) {
  const double inter = IntersectionVolumeDevkit(footprint_intersection, d, g);
  if (inter <= 0) return 0.0;
  return inter / (d.h * d.l * d.w + g.h * g.l * g.w - inter);
}

// KittiOverlap's BEV or 3D value from the footprint intersection.
double OverlapFromFootprint(OverlapKind kind, const Box3D& d, const Box3D& g,
                            double footprint_intersection) {
  return kind == OverlapKind::kBev ? BevOverlapFromFootprint(d, g, footprint_intersection)
                                   : ThreeDOverlapFromFootprint(d, g, footprint_intersection);
}

// KittiOverlapAtThreshold from KittiOverlap's value.
double OverlapAtThreshold(OverlapKind kind, double overlap, const Object& detection,
                          const Object& label, double tau) {
  if (!DevkitMayDecideOtherwise(kind, overlap, tau, detection.box3d, label.box3d)) return overlap;
  return DevkitBoxOverlap(kind, DevkitCriterion::kUnion, detection.box3d, label.box3d)
      .value_or(overlap);
}

}  // namespace

double KittiOverlap(OverlapKind kind, const Object& detection, const Object& label) {
  switch (kind) {
    case OverlapKind::k2D: {
      ImageOverlapParts p;
      if (!ImageOverlap(detection.box, label.box, &p)) return 0.0;
      return p.inter / (p.det_area + p.label_area - p.inter);
    }
    case OverlapKind::kBev:
    case OverlapKind::k3D:
      return OverlapFromFootprint(kind, detection.box3d, label.box3d,
                                  FootprintIntersection(detection.box3d, label.box3d));
    case OverlapKind::kLetBev:
    case OverlapKind::kLet3D:
      break;
  }
  STEREODET_CHECK(false) << "KittiOverlap: " << OverlapKindName(kind)
                         << " needs the LET tolerance (MatchOverlap)";
  return 0.0;
}

double MatchOverlap(OverlapKind kind, const Object& detection, const Object& label,
                    const LetOptions& let) {
  if (!IsLetKind(kind)) return KittiOverlap(kind, detection, label);
  if (!(LongitudinalAffinity(detection.box3d, label.box3d, let) > 0)) return 0.0;
  return LetOverlap(kind, detection.box3d, label.box3d, let);
}

double KittiBoxOverlap(OverlapKind kind, const Box3D& detection, const Box3D& label) {
  STEREODET_CHECK(kind == OverlapKind::kBev || kind == OverlapKind::k3D)
      << "KittiBoxOverlap: BEV or 3D, got " << OverlapKindName(kind);
  return OverlapFromFootprint(kind, detection, label, FootprintIntersection(detection, label));
}

double KittiDontCareOverlap(OverlapKind kind, const Object& detection, const Object& dontcare) {
  switch (PlainKind(kind)) {
    case OverlapKind::k2D: {
      ImageOverlapParts p;
      if (!ImageOverlap(detection.box, dontcare.box, &p)) return 0.0;
      return p.inter / p.det_area;
    }
    case OverlapKind::kBev: {
      const double inter = FootprintIntersection(detection.box3d, dontcare.box3d);
      if (inter <= 0) return 0.0;
      return inter / std::abs(detection.box3d.l * detection.box3d.w);
    }
    case OverlapKind::k3D: {
      const Box3D& d = detection.box3d;
      const double inter =
          IntersectionVolumeDevkit(FootprintIntersection(d, dontcare.box3d), d, dontcare.box3d);
      if (inter <= 0) return 0.0;
      return inter / (d.h * d.l * d.w);
    }
    case OverlapKind::kLetBev:  // not a PlainKind
    case OverlapKind::kLet3D:
      break;
  }
  return 0.0;
}

double KittiOverlapAtThreshold(OverlapKind kind, const Object& detection, const Object& label,
                               double tau) {
  return OverlapAtThreshold(kind, KittiOverlap(kind, detection, label), detection, label, tau);
}

double KittiDontCareOverlapAtThreshold(OverlapKind kind, const Object& detection,
                                       const Object& dontcare, double tau) {
  const double overlap = KittiDontCareOverlap(kind, detection, dontcare);
  if (!DevkitMayDecideOtherwise(kind, overlap, tau, detection.box3d, dontcare.box3d)) {
    return overlap;
  }
  return DevkitBoxOverlap(kind, DevkitCriterion::kDetectionSize, detection.box3d, dontcare.box3d)
      .value_or(overlap);
}

ClassFrameBuilder::ClassFrameBuilder(ClassFrame reuse) : own_(std::move(reuse)), cf_(&own_) {
  cf_->Clear();
}

ClassFrameBuilder::ClassFrameBuilder(ClassFrame* target) : cf_(target) { cf_->Clear(); }

void ClassFrameBuilder::AddLabels(const EvalFrame& frame, const ClassSpec& spec,
                                  bool exact_dontcare_name) {
  ClassFrame* cf = cf_;
  std::vector<const Object*>& dontcares = dontcares_;
  // At most every label: one allocation per list the first time, none when `cf` is reused.
  const size_t most = cf->label_object.size() + frame.labels.size();
  cf->label_object.reserve(most);
  cf->label_neighbour.reserve(most);
  cf->label_difficulty.reserve(most);
  cf->label_alpha.reserve(most);
  for (size_t i = 0; i < frame.labels.size(); ++i) {
    const Object& label = frame.labels[i];
    if (exact_dontcare_name ? label.type == "DontCare" : IsDontCare(label)) {
      dontcares.push_back(&label);
    }
    const bool is_class = EqualsIgnoreCase(label.type, spec.name);
    bool is_neighbour = false;
    if (!is_class) {
      for (const std::string& n : spec.neighbours) is_neighbour |= EqualsIgnoreCase(label.type, n);
      if (!is_neighbour) continue;
    }
    uint8_t bits = 0;
    const double height = label.box.bottom - label.box.top;
    for (int d = 0; d < kNumDifficulties; ++d) {
      const DifficultyLimits lim = KittiDifficultyLimits(static_cast<Difficulty>(d));
      // The official devkit's test (cleanData), written as it is: ignored if occluded > max ||
      // truncated > max || height <= min (the prclibo/kitti_eval fork has height < min).
      const bool ignore = label.occluded > lim.max_occlusion ||
                          label.truncated > lim.max_truncation || height <= lim.min_height_px;
      if (!ignore) bits |= static_cast<uint8_t>(1u << d);
    }
    cf->label_object.push_back(static_cast<int32_t>(i));
    cf->label_neighbour.push_back(is_neighbour ? 1 : 0);
    cf->label_difficulty.push_back(bits);
    cf->label_alpha.push_back(label.alpha);
  }
}

void ClassFrameBuilder::AddDetections(const EvalFrame& frame, const ClassSpec& spec,
                                      const std::function<bool(const Object&)>& in_dontcare) {
  ClassFrame* cf = cf_;
  const size_t most = cf->det_object.size() + frame.detections.size();
  cf->det_object.reserve(most);
  cf->det_is_class.reserve(most);
  cf->det_height.reserve(most);
  cf->det_score.reserve(most);
  cf->det_alpha.reserve(most);
  cf->det_dontcare.reserve(most);
  cf->det_state.reserve(most * kNumDifficulties);
  double min_height[kNumDifficulties];
  for (int d = 0; d < kNumDifficulties; ++d) {
    min_height[d] = KittiDifficultyLimits(static_cast<Difficulty>(d)).min_height_px;
  }
  for (size_t j = 0; j < frame.detections.size(); ++j) {
    const Object& det = frame.detections[j];
    STEREODET_CHECK(det.score.has_value())
        << "frame " << frame.id << ": detection " << j + 1 << " has no score";
    const bool is_class = EqualsIgnoreCase(det.type, spec.name);
    const double height = std::abs(det.box.top - det.box.bottom);
    if (!is_class && !(height < kLargestMinHeightPx)) continue;
    cf->det_object.push_back(static_cast<int32_t>(j));
    cf->det_is_class.push_back(is_class ? 1 : 0);
    cf->det_height.push_back(height);
    cf->det_score.push_back(*det.score);
    cf->det_alpha.push_back(det.alpha);
    cf->det_dontcare.push_back(is_class && in_dontcare(det) ? 1 : 0);
    const double truncated = std::trunc(height);
    for (int d = 0; d < kNumDifficulties; ++d) {
      cf->det_state.push_back(truncated < min_height[d] ? 1 : (is_class ? 0 : -1));
    }
  }
}

void ClassFrame::Clear() {
  label_object.clear();
  label_neighbour.clear();
  label_difficulty.clear();
  label_alpha.clear();
  det_object.clear();
  det_is_class.clear();
  det_height.clear();
  det_score.clear();
  det_alpha.clear();
  det_dontcare.clear();
  det_state.clear();
  edge_begin.clear();
  edge_det.clear();
  edge_overlap.clear();
  edge_affinity.clear();
  pair_footprint.clear();
  devkit_overlaps = false;
}

namespace {

// A LET kind's edges (`plain` its BEV or 3D): pairs with an affinity above 0 and LET-IoU >= tau,
// the affinity beside each. The affinity is the cheaper of the two and rules most pairs out.
void PrepareLetEdges(const EvalFrame& frame, OverlapKind plain, double tau, const LetOptions& let,
                     ClassFrame* cf) {
  cf->edge_begin.assign(1, 0);
  for (int i = 0; i < cf->num_labels(); ++i) {
    const Box3D& label = frame.labels[cf->label_object[i]].box3d;
    for (int j = 0; j < cf->num_dets(); ++j) {
      const Box3D& det = frame.detections[cf->det_object[j]].box3d;
      const double affinity = LongitudinalAffinity(det, label, let);
      if (!(affinity > 0)) continue;  // NaN fails
      const double overlap = LetOverlap(plain, det, label, let);
      if (overlap >= tau) {  // NaN fails
        cf->edge_det.push_back(j);
        cf->edge_overlap.push_back(overlap);
        cf->edge_affinity.push_back(affinity);
      }
    }
    cf->edge_begin.push_back(static_cast<int32_t>(cf->edge_det.size()));
  }
}

}  // namespace

ClassFrame PrepareClassFrame(const EvalFrame& frame, const ClassSpec& spec, OverlapKind kind,
                             OverlapArithmetic arithmetic, ClassFrame reuse, bool reuse_selection,
                             const LetOptions& let) {
  PrepareClassFrameInPlace(frame, spec, kind, arithmetic, reuse_selection, &reuse, let);
  return reuse;
}

void PrepareClassFrameInPlace(const EvalFrame& frame, const ClassSpec& spec, OverlapKind kind,
                              OverlapArithmetic arithmetic, bool reuse_selection,
                              ClassFrame* result, const LetOptions& let) {
  const double tau = spec.min_overlap[static_cast<int>(kind)];
  const bool let_kind = IsLetKind(kind);
  // The devkit has no LET overlaps: a LET kind under the KITTI matcher keeps its rules (> tau,
  // passes 1 and 2) on exact values, its DontCare test included.
  const bool devkit = arithmetic == OverlapArithmetic::kDevkit && !let_kind;
  const OverlapKind plain = PlainKind(kind);
  auto in_dontcare = [&](const Object& det, const std::vector<const Object*>& dontcares) {
    for (const Object* dc : dontcares) {
      const double overlap = devkit ? KittiDontCareOverlapAtThreshold(plain, det, *dc, tau)
                                    : KittiDontCareOverlap(plain, det, *dc);
      if (overlap > tau) return true;
    }
    return false;
  };

  ClassFrame& cf = *result;
  if (reuse_selection) {
    // The labels and detections of `cf` are this frame's for this class: only what depends on the
    // overlap kind is made anew (the DontCare flags here, the edges below).
    std::vector<const Object*> dontcares;
    for (const Object& label : frame.labels) {
      if (IsDontCare(label)) dontcares.push_back(&label);
    }
    for (int j = 0; j < cf.num_dets(); ++j) {
      cf.det_dontcare[j] =
          cf.det_is_class[j] && in_dontcare(frame.detections[cf.det_object[j]], dontcares) ? 1 : 0;
    }
    cf.edge_begin.clear();
    cf.edge_det.clear();
    cf.edge_overlap.clear();
    cf.edge_affinity.clear();
  } else {
    ClassFrameBuilder builder(&cf);
    builder.AddLabels(frame, spec, false);
    const std::vector<const Object*>* dontcares = &builder.dontcares();
    // One pointer captured: std::function keeps it without allocating.
    const auto dontcare_test = [&in_dontcare, dontcares](const Object& det) {
      return in_dontcare(det, *dontcares);
    };
    builder.AddDetections(frame, spec,
                          [test = &dontcare_test](const Object& det) { return (*test)(det); });
  }
  cf.min_overlap = tau;
  cf.devkit_overlaps = devkit;
  if (let_kind) {
    PrepareLetEdges(frame, plain, tau, let, &cf);
    return;
  }

  // BEV and 3D share each pair's footprint intersection: the first of them for this selection
  // keeps it in pair_footprint, the second reads it there.
  const bool footprint_kind = kind != OverlapKind::k2D;
  const size_t num_pairs = static_cast<size_t>(cf.num_labels()) * cf.num_dets();
  const bool have_footprints = footprint_kind && cf.pair_footprint.size() == num_pairs;
  if (footprint_kind && !have_footprints) cf.pair_footprint.resize(num_pairs);
  cf.edge_begin.assign(1, 0);
  std::vector<std::pair<double, size_t>> scratch;
  for (int i = 0; i < cf.num_labels(); ++i) {
    const Object& label = frame.labels[cf.label_object[i]];
    const size_t first = cf.edge_det.size();
    double* footprints = footprint_kind ? cf.pair_footprint.data() + i * cf.num_dets() : nullptr;
    for (int j = 0; j < cf.num_dets(); ++j) {
      const Object& det = frame.detections[cf.det_object[j]];
      double overlap;
      if (footprint_kind) {
        if (!have_footprints) footprints[j] = FootprintIntersection(det.box3d, label.box3d);
        overlap = OverlapFromFootprint(kind, det.box3d, label.box3d, footprints[j]);
      } else {
        overlap = KittiOverlap(kind, det, label);
      }
      if (devkit) overlap = OverlapAtThreshold(kind, overlap, det, label, tau);
      if (overlap >= tau) {  // NaN fails
        cf.edge_det.push_back(j);
        cf.edge_overlap.push_back(overlap);
      }
    }
    if (devkit && kind != OverlapKind::k2D && cf.edge_det.size() - first >= 2) {
      UseDevkitForCloseCandidates(kind, frame, label, cf, cf.edge_det.data() + first,
                                  cf.edge_overlap.data() + first, cf.edge_det.size() - first,
                                  &scratch);
    }
    cf.edge_begin.push_back(static_cast<int32_t>(cf.edge_det.size()));
  }
}

double KittiRecordedOverlap(OverlapKind kind, const EvalFrame& frame, const ClassFrame& cf,
                            int label_index, int edge) {
  if (!cf.devkit_overlaps || kind == OverlapKind::k2D) return cf.edge_overlap[edge];
  const Object& label = frame.labels[cf.label_object[label_index]];
  const int begin = cf.edge_begin[label_index], end = cf.edge_begin[label_index + 1];
  // The label's edges are the same whichever test chose the devkit's values (KittiRecordedOverlap
  // in frame_data_internal.h), so its overlaps are recomputed here edge for edge.
  std::vector<double> values(static_cast<size_t>(end - begin));
  for (int e = begin; e < end; ++e) {
    const Object& det = frame.detections[cf.det_object[cf.edge_det[e]]];
    double v = KittiOverlap(kind, det, label);
    if (DevkitMayDecideOtherwise(kind, v, cf.min_overlap, det.box3d, label.box3d,
                                 /*every_parallel=*/true)) {
      v = DevkitBoxOverlap(kind, DevkitCriterion::kUnion, det.box3d, label.box3d).value_or(v);
    }
    values[e - begin] = v;
  }
  if (values.size() >= 2) {
    std::vector<std::pair<double, size_t>> scratch;
    UseDevkitForCloseCandidates(kind, frame, label, cf, cf.edge_det.data() + begin, values.data(),
                                values.size(), &scratch);
  }
  return values[edge - begin];
}

bool HasEvaluableDetection(const std::vector<EvalFrame>& frames, const ClassSpec& spec,
                           OverlapKind kind) {
  for (const EvalFrame& frame : frames) {
    for (const Object& det : frame.detections) {
      if (!EqualsIgnoreCase(det.type, spec.name)) continue;
      switch (kind) {
        case OverlapKind::k2D:
          if (det.box.left >= 0) return true;
          break;
        // The official devkit's tests (loadDetections); the prclibo/kitti_eval fork tests only
        // x != -1000 (BEV) and y != -1000 (3D).
        case OverlapKind::kBev:
          if (det.box3d.location.x() != -1000 && det.box3d.location.z() != -1000 &&
              det.box3d.w > 0 && det.box3d.l > 0) {
            return true;
          }
          break;
        case OverlapKind::k3D:
        case OverlapKind::kLetBev:
        case OverlapKind::kLet3D:
          if (det.box3d.location.x() != -1000 && det.box3d.location.y() != -1000 &&
              det.box3d.location.z() != -1000 && det.box3d.h > 0 && det.box3d.w > 0 &&
              det.box3d.l > 0) {
            return true;
          }
          break;
      }
    }
  }
  return false;
}

bool AllAlphasValid(const std::vector<EvalFrame>& frames) {
  for (const EvalFrame& frame : frames) {
    for (const Object& det : frame.detections) {
      if (det.alpha == -10) return false;
    }
  }
  return true;
}

}  // namespace stereodet
