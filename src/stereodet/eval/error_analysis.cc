#include "stereodet/eval/error_analysis.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "stereodet/eval/frame_data_internal.h"
#include "stereodet/util/check.h"
#include "stereodet/util/strings.h"

namespace stereodet {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool IsDontCareLabel(const Object& o) { return EqualsIgnoreCase(o.type, "DontCare"); }

bool IsClassOrNeighbour(const std::string& type, const ClassSpec& spec) {
  if (EqualsIgnoreCase(type, spec.name)) return true;
  for (const std::string& n : spec.neighbours) {
    if (EqualsIgnoreCase(type, n)) return true;
  }
  return false;
}

// The matcher's own test: the devkit matches on overlap > tau, the exact matchers on >= tau.
bool Matchable(Matcher matcher, double overlap, double tau) {
  return matcher == Matcher::kKitti ? overlap > tau : overlap >= tau;
}

// The overlap the matcher decides on. The KITTI matcher uses the devkit's BEV / 3D value near tau
// and for parallel footprints (where boost 1.74 can lose an intersection), so that a detection the
// devkit saw as overlapping nothing is not classified by an overlap the matcher never saw.
double DecidingOverlap(Matcher matcher, OverlapKind kind, const Object& det, const Object& label,
                       double tau, const LetOptions& let) {
  if (matcher == Matcher::kKitti && !IsLetKind(kind)) {
    return KittiOverlapAtThreshold(kind, det, label, tau);
  }
  return MatchOverlap(kind, det, label, let);
}

// What the association at score -inf says of the labels of one class in one frame.
enum LabelState : int8_t { kNotOfClass = -1, kUnused = 0, kUsed = 1 };

struct ClassAssociation {
  std::vector<std::vector<Outcome>> det_outcome;  // [frame][detection]; kNone: not of the class
  std::vector<std::vector<int8_t>> label_state;   // [frame][label]
};

ClassAssociation FromRecords(const std::vector<EvalFrame>& frames, const ClassSpec& spec,
                             const std::vector<MatchRecord>& records) {
  ClassAssociation a;
  a.det_outcome.resize(frames.size());
  a.label_state.resize(frames.size());
  for (size_t f = 0; f < frames.size(); ++f) {
    a.det_outcome[f].assign(frames[f].detections.size(), Outcome::kNone);
    a.label_state[f].assign(frames[f].labels.size(), kNotOfClass);
    for (size_t i = 0; i < frames[f].labels.size(); ++i) {
      // Every label of the class or a neighbour has a row; "used" until its row says otherwise.
      if (IsClassOrNeighbour(frames[f].labels[i].type, spec)) a.label_state[f][i] = kUsed;
    }
  }
  for (const MatchRecord& r : records) {
    if (r.detection >= 0) {
      // Rows of other classes' detections (the devkit's low detections of any class) are skipped:
      // they are never this class's FPs.
      if (!EqualsIgnoreCase(frames[r.frame].detections[r.detection].type, spec.name)) continue;
      a.det_outcome[r.frame][r.detection] = r.outcome;
      if (r.outcome == Outcome::kTp) a.label_state[r.frame][r.label] = kUsed;
    } else {
      a.label_state[r.frame][r.label] = r.outcome == Outcome::kFn ? kUnused : kUsed;
    }
  }
  return a;
}

// The one-cell options the fixed frames are evaluated with: nothing but the AP is needed.
EvalOptions CellOptions(const EvalOptions& options, const ClassSpec& spec, OverlapKind kind,
                        Difficulty difficulty) {
  EvalOptions o = options;
  o.classes = {spec};
  o.metrics = {kind};
  o.difficulties = {difficulty};
  o.keep_records = false;
  o.filter = FilterOptions{};
  o.breakdowns.clear();
  o.breakdown_naive = false;
  o.compute_aos = false;
  // A fix may remove every detection of the class; its AP is then 0, not "not evaluated".
  o.require_detections = false;
  return o;
}

void CheckRequirements(const EvalOptions& options, OverlapKind kind,
                       const ErrorAnalysisOptions& ea) {
  options.Check();
  ea.Check();
  STEREODET_CHECK(options.compat == EvalCompat::kDevkit)
      << "error analysis: --compat " << EvalCompatName(options.compat)
      << " is not supported (its overlaps and label rules are not those the classification uses)";
  for (size_t a = 0; a < options.classes.size(); ++a) {
    const ClassSpec& spec = options.classes[a];
    STEREODET_CHECK(ea.background_overlap < spec.min_overlap[static_cast<int>(kind)])
        << "error analysis: background overlap " << ea.background_overlap << " must be below the "
        << OverlapKindName(kind) << " threshold of " << spec.name << " ("
        << spec.min_overlap[static_cast<int>(kind)] << ")";
    for (size_t b = 0; b < a; ++b) {
      STEREODET_CHECK(!EqualsIgnoreCase(options.classes[b].name, spec.name))
          << "error analysis: class " << spec.name << " is listed twice";
    }
  }
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// One cell from a classification: counts, AP as is, and the dAPs of its fixed frames.
ErrorAnalysis AnalyzeClass(const std::vector<EvalFrame>& frames, const EvalOptions& options,
                           const ErrorClassification& c, int k) {
  const auto start = std::chrono::steady_clock::now();
  const ClassSpec& spec = c.classes[k];
  const ClassResult& cell = c.cells[k];
  ErrorAnalysis a;
  a.class_name = spec.name;
  a.kind = c.kind;
  a.difficulty = c.difficulty;
  a.matcher = c.matcher;
  a.min_overlap = spec.min_overlap[static_cast<int>(c.kind)];
  a.background_overlap = c.background_overlap;
  a.num_valid_labels = cell.num_valid_labels;
  a.tp = cell.at_threshold.tp;
  a.fp = cell.at_threshold.fp;
  a.fn = cell.at_threshold.fn;
  a.count = c.Count(k);
  for (const ClassifiedError& e : c.errors) {
    if (e.type == ErrorType::kCls && e.target_class == k && e.class_index != k && e.fixable) {
      ++a.cls_incoming;
    }
  }
  a.evaluated = !options.require_detections || HasEvaluableDetection(frames, spec, c.kind);
  if (!a.evaluated) {
    a.ap_r40 = a.ap_r11 = kNaN;
    a.delta_ap_r40.fill(kNaN);
    a.delta_ap_r11.fill(kNaN);
    a.delta_fp_r40 = a.delta_fp_r11 = a.delta_fn_r40 = a.delta_fn_r11 = kNaN;
    a.seconds = Seconds(start);
    return a;
  }
  a.ap_r40 = cell.ap_r40;
  a.ap_r11 = cell.ap_r11;

  const EvalOptions cell_options = CellOptions(options, spec, c.kind, c.difficulty);
  // AP_R40 and AP_R11 of the fixed frames minus the cell's.
  auto delta = [&](const std::vector<EvalFrame>& fixed) -> std::pair<double, double> {
    const EvalResult r = Evaluate(fixed, cell_options);
    STEREODET_CHECK_EQ(r.results.size(), 1u);
    return {r.results[0].ap_r40 - a.ap_r40, r.results[0].ap_r11 - a.ap_r11};
  };
  for (int t = 0; t < kNumErrorTypes; ++t) {
    const ErrorType type = static_cast<ErrorType>(t);
    // Nothing to fix leaves the frames as they are: dAP 0 without evaluating them again.
    const bool any = a.count[t] > 0 || (type == ErrorType::kCls && a.cls_incoming > 0);
    if (!any) continue;
    std::tie(a.delta_ap_r40[t], a.delta_ap_r11[t]) = delta(FixErrors(frames, c, k, {type}));
  }
  if (a.fp > 0) {
    std::tie(a.delta_fp_r40, a.delta_fp_r11) =
        delta(FixSpecialError(frames, c, k, SpecialError::kFalsePositives));
  }
  if (a.fn > 0) {
    std::tie(a.delta_fn_r40, a.delta_fn_r11) =
        delta(FixSpecialError(frames, c, k, SpecialError::kFalseNegatives));
  }
  a.seconds = Seconds(start);
  return a;
}

// Copies `frames` leaving out the marked labels and detections (order kept).
std::vector<EvalFrame> Compact(std::vector<EvalFrame> out,
                               const std::vector<std::vector<uint8_t>>& remove_label,
                               const std::vector<std::vector<uint8_t>>& remove_det) {
  for (size_t f = 0; f < out.size(); ++f) {
    auto keep = [](std::vector<Object>& objects, const std::vector<uint8_t>& removed) {
      if (removed.empty()) return;
      size_t n = 0;
      for (size_t i = 0; i < objects.size(); ++i) {
        if (removed[i]) continue;
        if (n != i) objects[n] = std::move(objects[i]);  // (no self-move: it empties strings)
        ++n;
      }
      objects.resize(n);
    };
    keep(out[f].labels, remove_label[f]);
    keep(out[f].detections, remove_det[f]);
  }
  return out;
}

void CheckFixArguments(const std::vector<EvalFrame>& frames, const ErrorClassification& c,
                       int class_index) {
  STEREODET_CHECK_EQ(frames.size(), c.num_frames)
      << ": the classification was made from other frames";
  STEREODET_CHECK(class_index >= 0 && class_index < static_cast<int>(c.classes.size()))
      << "error analysis: class index " << class_index << " outside the " << c.classes.size()
      << " analysed classes";
}

}  // namespace

void ErrorAnalysisOptions::Check() const {
  STEREODET_CHECK(std::isfinite(background_overlap) && background_overlap > 0.0 &&
                  background_overlap < 1.0)
      << "error analysis: background overlap " << background_overlap << " must be in (0, 1)";
}

const char* ErrorTypeName(ErrorType type) {
  switch (type) {
    case ErrorType::kCls:
      return "cls";
    case ErrorType::kLoc:
      return "loc";
    case ErrorType::kBoth:
      return "both";
    case ErrorType::kDupe:
      return "dupe";
    case ErrorType::kBkg:
      return "bkg";
    case ErrorType::kMissed:
      return "missed";
  }
  return "?";
}

std::optional<ErrorType> ParseErrorType(std::string_view text) {
  for (int t = 0; t < kNumErrorTypes; ++t) {
    if (EqualsIgnoreCase(text, ErrorTypeName(static_cast<ErrorType>(t)))) {
      return static_cast<ErrorType>(t);
    }
  }
  return std::nullopt;
}

std::array<int64_t, kNumErrorTypes> ErrorClassification::Count(int class_index) const {
  std::array<int64_t, kNumErrorTypes> n{};
  for (const ClassifiedError& e : errors) {
    if (e.class_index == class_index) ++n[static_cast<int>(e.type)];
  }
  return n;
}

int ErrorClassification::ClassIndex(const std::string& name) const {
  for (size_t k = 0; k < classes.size(); ++k) {
    if (EqualsIgnoreCase(classes[k].name, name)) return static_cast<int>(k);
  }
  return -1;
}

ErrorClassification ClassifyErrors(const std::vector<EvalFrame>& frames, const EvalOptions& options,
                                   OverlapKind kind, Difficulty difficulty,
                                   const ErrorAnalysisOptions& ea) {
  CheckRequirements(options, kind, ea);
  ErrorClassification c;
  c.classes = options.classes;
  c.kind = kind;
  c.difficulty = difficulty;
  c.matcher = options.matcher;
  c.background_overlap = ea.background_overlap;
  c.num_frames = frames.size();
  const int num_classes = static_cast<int>(c.classes.size());
  const int kind_index = static_cast<int>(kind);
  const double t_b = ea.background_overlap;

  // The association with every detection present: Evaluate's records at score -inf.
  EvalOptions o = options;
  o.metrics = {kind};
  o.difficulties = {difficulty};
  o.score_threshold = -std::numeric_limits<double>::infinity();
  o.keep_records = true;
  o.require_detections = false;
  o.filter = FilterOptions{};
  o.breakdowns.clear();
  o.breakdown_naive = false;
  o.compute_aos = false;
  EvalResult result = Evaluate(frames, o);
  STEREODET_CHECK_EQ(result.results.size(), c.classes.size());
  std::vector<ClassAssociation> assoc;
  for (int k = 0; k < num_classes; ++k) {
    assoc.push_back(FromRecords(frames, c.classes[k], result.results[k].records));
    result.results[k].records.clear();
    result.results[k].records.shrink_to_fit();
    c.cells.push_back(std::move(result.results[k]));
  }

  // The analysed class of a type, or -1.
  auto class_of = [&](const std::string& type) {
    for (int k = 0; k < num_classes; ++k) {
      if (EqualsIgnoreCase(type, c.classes[k].name)) return k;
    }
    return -1;
  };

  for (size_t f = 0; f < frames.size(); ++f) {
    const EvalFrame& frame = frames[f];
    const size_t frame_begin = c.errors.size();
    std::vector<int> label_class(frame.labels.size());
    for (size_t i = 0; i < frame.labels.size(); ++i) {
      label_class[i] = class_of(frame.labels[i].type);
    }
    for (size_t j = 0; j < frame.detections.size(); ++j) {
      const Object& det = frame.detections[j];
      const int k = class_of(det.type);
      if (k < 0 || assoc[k].det_outcome[f][j] != Outcome::kFp) continue;
      const ClassSpec& spec = c.classes[k];
      const double t_f = spec.min_overlap[kind_index];
      // The largest overlaps (first label in file order on ties): of the class's own labels, of
      // its used ones, of other classes' labels, of all labels.
      double own = 0, used = 0, other = 0, all = 0;
      int own_l = -1, used_l = -1, other_l = -1, all_l = -1;
      for (size_t i = 0; i < frame.labels.size(); ++i) {
        const Object& label = frame.labels[i];
        if (IsDontCareLabel(label)) continue;
        const bool is_own = IsClassOrNeighbour(label.type, spec);
        // The threshold the overlap is decided at: the class's own, or for a Cls test that of
        // the label's class once relabelled to it.
        const double tau =
            is_own || label_class[i] < 0 ? t_f : c.classes[label_class[i]].min_overlap[kind_index];
        const double ov = DecidingOverlap(c.matcher, kind, det, label, tau, options.let);
        const int l = static_cast<int>(i);
        if (ov > all || all_l < 0) all = ov, all_l = l;
        if (is_own) {
          if (ov > own || own_l < 0) own = ov, own_l = l;
          if (assoc[k].label_state[f][i] == kUsed && (ov > used || used_l < 0)) {
            used = ov, used_l = l;
          }
        } else if (ov > other || other_l < 0) {
          other = ov, other_l = l;
        }
      }
      ClassifiedError e;
      e.frame = static_cast<int32_t>(f);
      e.detection = static_cast<int32_t>(j);
      e.class_index = k;
      e.score = det.score.value_or(kNaN);
      const double other_tau = other_l >= 0 && label_class[other_l] >= 0
                                   ? c.classes[label_class[other_l]].min_overlap[kind_index]
                                   : t_f;
      // TIDE's order of tests (quantify.py, TIDERun._eval_image): Loc, Cls, Dupe, Bkg, Other.
      if (own_l >= 0 && own >= t_b && !Matchable(c.matcher, own, t_f)) {
        e.type = ErrorType::kLoc, e.label = own_l, e.overlap = own;
      } else if (other_l >= 0 && Matchable(c.matcher, other, other_tau)) {
        e.type = ErrorType::kCls, e.label = other_l, e.overlap = other;
        e.target_class = label_class[other_l];
      } else if (used_l >= 0 && Matchable(c.matcher, used, t_f)) {
        e.type = ErrorType::kDupe, e.label = used_l, e.overlap = used;
      } else if (all_l < 0 || all <= t_b) {
        e.type = ErrorType::kBkg, e.overlap = all;
      } else {
        e.type = ErrorType::kBoth, e.label = all_l, e.overlap = all;
      }
      c.errors.push_back(e);
    }

    // The winners of unused labels (TIDE's BestGTMatch): Loc and Cls errors compete for a label
    // together, the highest score first, then file order.
    std::vector<int64_t> winner(frame.labels.size(), -1);
    for (size_t x = frame_begin; x < c.errors.size(); ++x) {
      const ClassifiedError& e = c.errors[x];
      int owner = -1;  // the class the label is unused in
      if (e.type == ErrorType::kLoc) {
        owner = e.class_index;
      } else if (e.type == ErrorType::kCls) {
        owner = e.target_class;
      } else {
        continue;
      }
      if (owner < 0 || assoc[owner].label_state[f][e.label] != kUnused) continue;
      int64_t& w = winner[e.label];
      if (w < 0 || e.score > c.errors[w].score ||
          (e.score == c.errors[w].score && e.detection < c.errors[w].detection)) {
        w = static_cast<int64_t>(x);
      }
    }
    for (const int64_t w : winner) {
      if (w >= 0) c.errors[w].fixable = true;
    }
    // FNs, and the missed ones among them: unused labels no Loc or Cls error explains.
    for (size_t i = 0; i < frame.labels.size(); ++i) {
      const int k = label_class[i];
      if (k < 0 || assoc[k].label_state[f][i] != kUnused) continue;
      UnmatchedLabel u;
      u.frame = static_cast<int32_t>(f);
      u.label = static_cast<int32_t>(i);
      u.class_index = k;
      u.missed = winner[i] < 0;
      c.false_negatives.push_back(u);
      if (u.missed) {
        ClassifiedError e;
        e.frame = u.frame;
        e.label = u.label;
        e.class_index = k;
        e.type = ErrorType::kMissed;
        c.errors.push_back(e);
      }
    }
  }
  return c;
}

std::vector<EvalFrame> FixErrors(const std::vector<EvalFrame>& frames, const ErrorClassification& c,
                                 int class_index, const std::vector<ErrorType>& types) {
  CheckFixArguments(frames, c, class_index);
  std::array<bool, kNumErrorTypes> on{};
  for (const ErrorType t : types) on[static_cast<int>(t)] = true;
  std::vector<EvalFrame> out = frames;
  std::vector<std::vector<uint8_t>> remove_label(frames.size()), remove_det(frames.size());
  auto remove = [](std::vector<uint8_t>& marks, size_t n, int32_t index) {
    if (marks.empty()) marks.assign(n, 0);
    marks[index] = 1;
  };
  for (const ClassifiedError& e : c.errors) {
    if (!on[static_cast<int>(e.type)]) continue;
    const size_t f = e.frame;
    if (e.type == ErrorType::kMissed) {
      if (e.class_index == class_index) remove(remove_label[f], out[f].labels.size(), e.label);
      continue;
    }
    const bool own = e.class_index == class_index;
    // Another class's Cls winner on one of this class's labels becomes this class's detection.
    const bool incoming = !own && e.type == ErrorType::kCls && e.target_class == class_index;
    if (!own && !incoming) continue;
    Object& det = out[f].detections[e.detection];
    if (e.type == ErrorType::kLoc && e.fixable) {
      const Object& label = frames[f].labels[e.label];
      det.box = label.box;
      det.box3d = label.box3d;
    } else if (e.type == ErrorType::kCls && e.fixable) {
      det.type = frames[f].labels[e.label].type;
    } else if (own) {
      remove(remove_det[f], out[f].detections.size(), e.detection);
    }
  }
  return Compact(std::move(out), remove_label, remove_det);
}

std::vector<EvalFrame> FixSpecialError(const std::vector<EvalFrame>& frames,
                                       const ErrorClassification& c, int class_index,
                                       SpecialError special) {
  CheckFixArguments(frames, c, class_index);
  std::vector<std::vector<uint8_t>> remove_label(frames.size()), remove_det(frames.size());
  auto remove = [](std::vector<uint8_t>& marks, size_t n, int32_t index) {
    if (marks.empty()) marks.assign(n, 0);
    marks[index] = 1;
  };
  if (special == SpecialError::kFalsePositives) {
    for (const ClassifiedError& e : c.errors) {
      if (e.class_index != class_index || e.detection < 0) continue;
      remove(remove_det[e.frame], frames[e.frame].detections.size(), e.detection);
    }
  } else {
    for (const UnmatchedLabel& u : c.false_negatives) {
      if (u.class_index != class_index) continue;
      remove(remove_label[u.frame], frames[u.frame].labels.size(), u.label);
    }
  }
  return Compact(frames, remove_label, remove_det);
}

ErrorAnalysis AnalyzeErrors(const std::vector<EvalFrame>& frames, const EvalOptions& options,
                            const ClassSpec& spec, OverlapKind kind, Difficulty difficulty,
                            const ErrorAnalysisOptions& ea) {
  EvalOptions o = options;
  int k = -1;
  for (size_t i = 0; i < o.classes.size(); ++i) {
    if (EqualsIgnoreCase(o.classes[i].name, spec.name)) {
      o.classes[i] = spec;
      k = static_cast<int>(i);
      break;
    }
  }
  if (k < 0) {
    o.classes.push_back(spec);
    k = static_cast<int>(o.classes.size()) - 1;
  }
  o.metrics = {kind};
  o.difficulties = {difficulty};
  const ErrorClassification c = ClassifyErrors(frames, o, kind, difficulty, ea);
  return AnalyzeClass(frames, o, c, k);
}

std::vector<ErrorAnalysis> AnalyzeAllErrors(const std::vector<EvalFrame>& frames,
                                            const EvalOptions& options,
                                            const ErrorAnalysisOptions& ea) {
  const size_t n_k = options.classes.size(), n_m = options.metrics.size(),
               n_d = options.difficulties.size();
  std::vector<ErrorAnalysis> out(n_k * n_m * n_d);
  for (size_t m = 0; m < n_m; ++m) {
    for (size_t d = 0; d < n_d; ++d) {
      const ErrorClassification c =
          ClassifyErrors(frames, options, options.metrics[m], options.difficulties[d], ea);
      for (size_t k = 0; k < n_k; ++k) {
        out[(k * n_m + m) * n_d + d] = AnalyzeClass(frames, options, c, static_cast<int>(k));
      }
    }
  }
  return out;
}

}  // namespace stereodet
