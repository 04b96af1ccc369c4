#include "stereodet/report/html_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "stereodet/report/coco_report.h"
#include "stereodet/report/raster.h"
#include "stereodet/report/report_json_internal.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/output_folder.h"
#include "stereodet/util/strings.h"

namespace stereodet {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using report_internal::Fixed;
using report_internal::kNaN;
using report_internal::Num;
using report_internal::Numbers;
using report_internal::Str;

// The numbers the report reads from results.json must be numbers (or null: not computed). A
// string or an object there (an edited or damaged file) would show as an empty cell or a missing
// point, so it is refused naming the file, the entry and the field.
void CheckResultNumbers(const json& results, const std::filesystem::path& path) {
  auto check = [&](const json& parent, const char* key, const std::string& where) {
    if (!parent.is_object() || !parent.contains(key)) return;
    const json& v = parent[key];
    STEREODET_CHECK_IO(v.is_number() || v.is_null())
        << path.string() << ": " << where << key << " is " << v.dump().substr(0, 40)
        << ", not a number; is the file damaged or edited? Evaluate again";
  };
  check(results.value("input", json::object()), "num_frames", "input.");
  int index = 0;
  for (const json& e : results["results"]) {
    auto text = [&](const char* key) {
      return e.is_object() && e.contains(key) && e[key].is_string() ? e[key].get<std::string>()
                                                                    : std::string("?");
    };
    const std::string where = fmt::format("results[{}] ({} {} {}): ", index, text("class"),
                                          text("metric"), text("difficulty"));
    for (const char* key : {"min_overlap", "ap_r40", "ap_r11", "aos_r40", "aos_r11", "ap_voc",
                            "num_detections", "num_valid_labels", "curve_points"}) {
      check(e, key, where);
    }
    if (e.is_object() && e.contains("best_f1")) {
      for (const char* key : {"f1", "precision", "recall", "threshold"}) {
        check(e["best_f1"], key, where + "best_f1.");
      }
    }
    ++index;
  }
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// An AP-like figure of a cell (ap_r40, aos_r11, ...) for the reader: "-" where the cell has no
// valid label (the devkit reports 0 there, which reads as a detector that found nothing).
std::string ApText(const json& e, const char* key) {
  return e.value("num_valid_labels", 0) == 0 ? std::string("-") : Fixed(Num(e, key), 2);
}

// A cell of the results: class x metric x difficulty x overlap set.
struct CellKey {
  std::string class_name, metric, difficulty, overlaps;
  auto operator<=>(const CellKey&) const = default;
};

CellKey KeyOf(const json& e) {
  return {Str(e, "class"), Str(e, "metric"), Str(e, "difficulty"), Str(e, "overlaps")};
}

// The evaluated entries of a source by cell.
std::map<CellKey, const json*> Cells(const ReportSource& source) {
  std::map<CellKey, const json*> cells;
  for (const json& e : source.results["results"]) {
    if (e.value("evaluated", false)) cells.emplace(KeyOf(e), &e);
  }
  return cells;
}

bool SeveralOverlapSets(const ReportSource& source) {
  std::set<std::string> sets;
  for (const json& e : source.results["results"]) sets.insert(Str(e, "overlaps"));
  return sets.size() > 1;
}

std::string GroupStem(const CellKey& k, bool with_overlaps) {
  return Lower(k.class_name) + "_" + k.metric + (with_overlaps ? "_" + k.overlaps : "");
}
std::string CellStem(const CellKey& k, bool with_overlaps) {
  return Lower(k.class_name) + "_" + k.metric + "_" + Lower(k.difficulty) +
         (with_overlaps ? "_" + k.overlaps : "");
}

std::string CellTitle(const CellKey& k, const json& e) {
  return fmt::format("{} {} {}, overlap {}", k.class_name, k.metric, k.difficulty,
                     Fixed(Num(e, "min_overlap"), 2));
}

// Series colours: by role with one source, by source (and dashed by role) with several.
struct Styler {
  size_t num_sources;
  std::string Colour(size_t source, size_t role) const {
    // All 8 palette colours, so that up to 8 overlaid folders (the experiment's models,
    // docs/experiment.md) each get a colour of their own.
    return PaletteColour(num_sources > 1 ? source : role);
  }
  std::string Name(const ReportSource& s, const std::string& name) const {
    return num_sources > 1 ? s.label + ": " + name : name;
  }
};

std::vector<CocoReportSource> CocoSources(const std::vector<ReportSource>& sources) {
  std::vector<CocoReportSource> out;
  for (const ReportSource& s : sources) out.push_back({s.label, &s.results});
  return out;
}

// The sources' entries for `key` (nullptr where a source lacks the cell).
std::vector<const json*> EntriesFor(const std::vector<std::map<CellKey, const json*>>& cells,
                                    const CellKey& key) {
  std::vector<const json*> out;
  for (const auto& c : cells) {
    auto it = c.find(key);
    out.push_back(it == c.end() ? nullptr : it->second);
  }
  return out;
}

Plot PrFigure(const std::vector<ReportSource>& sources, const std::vector<const json*>& entries,
              const CellKey& key, const std::string& stem, const Styler& st) {
  Plot p;
  p.id = "pr_" + stem;
  p.title = CellTitle(key, *entries.front()) + ": precision vs recall";
  p.x_label = "recall";
  p.y_label = "precision";
  p.x_min = 0, p.x_max = 1, p.y_min = 0, p.y_max = 1;
  std::vector<std::string> caption;
  for (size_t i = 0; i < sources.size(); ++i) {
    if (entries[i] == nullptr) continue;
    const json& e = *entries[i];
    const std::string matcher = Str(sources[i].results["options"], "matcher");
    // LET cells: their LET-APL beside the AP (docs/metrics.md, LET-3D-AP).
    const std::string apl =
        e.contains("apl_r40") ? fmt::format(", APL_R40 {}", ApText(e, "apl_r40")) : std::string();
    PlotSeries exact;
    exact.name = st.Name(sources[i], fmt::format("{}, exact curve: AP_R40 {}, AP_R11 {}{}", matcher,
                                                 ApText(e, "ap_r40"), ApText(e, "ap_r11"), apl));
    exact.x = Numbers(e["curve"], "recall");
    exact.y = Numbers(e["curve"], "precision");
    exact.steps = true;  // precision holds until the next detection
    exact.colour = st.Colour(i, 0);
    exact.style = exact.x.size() <= 60 ? SeriesStyle::kLineMarkers : SeriesStyle::kLine;
    p.series.push_back(std::move(exact));
    if (e.contains("kitti")) {
      PlotSeries devkit;
      devkit.name =
          st.Name(sources[i], "devkit's 41 slots, read as recall i/40 (as its AP_R40 is)");
      devkit.y = Numbers(e["kitti"], "precision");
      for (size_t s = 0; s < devkit.y.size(); ++s)
        devkit.x.push_back(static_cast<double>(s) / 40.0);
      devkit.colour = st.Colour(i, 1);
      devkit.dashed = true;
      devkit.style = SeriesStyle::kLineMarkers;
      p.series.push_back(std::move(devkit));
    }
    if (e.value("num_valid_labels", 0) == 0) {
      // Nothing to recall: the plot stays empty and says why (the devkit's 0 is no score).
      caption.push_back(fmt::format(
          "{}no valid label in this cell, so no recall and no AP ({} detections)",
          sources.size() > 1 ? sources[i].label + ": " : "", e.value("num_detections", 0)));
      continue;
    }
    caption.push_back(fmt::format(
        "{}{} valid labels, {} detections; AP_R40 {} / AP_R11 {}{}; best F1 {} (precision {}, "
        "recall {} at score {})",
        sources.size() > 1 ? sources[i].label + ": " : "", e.value("num_valid_labels", 0),
        e.value("num_detections", 0), ApText(e, "ap_r40"), ApText(e, "ap_r11"), apl,
        Fixed(Num(e["best_f1"], "f1"), 3), Fixed(Num(e["best_f1"], "precision"), 3),
        Fixed(Num(e["best_f1"], "recall"), 3), Fixed(Num(e["best_f1"], "threshold"), 3)));
  }
  p.caption = fmt::format("{}.", fmt::join(caption, "; "));
  return p;
}

// Easy, Moderate and Hard in one precision-recall figure, as the devkit plots a class and metric:
// the exact curves as steps. With one results folder a colour per difficulty; with several a
// colour per folder and a line per difficulty (solid Easy, dashed Moderate, dotted Hard).
Plot PrDifficultiesFigure(const std::vector<ReportSource>& sources,
                          const std::vector<std::map<CellKey, const json*>>& cells,
                          const CellKey& group, const std::vector<std::string>& difficulties,
                          bool with_overlaps, const std::string& stem, const Styler& st) {
  static constexpr const char* kDash[] = {"", "5,3", "1.5,2.5"};
  Plot p;
  p.id = "pr_difficulties_" + stem;
  p.title = group.class_name + " " + group.metric +
            (with_overlaps ? " (" + group.overlaps + " overlaps)" : "") +
            ": precision vs recall by difficulty";
  p.x_label = "recall";
  p.y_label = "precision";
  p.x_min = 0, p.x_max = 1, p.y_min = 0, p.y_max = 1;
  std::vector<std::string> caption;
  for (size_t i = 0; i < sources.size(); ++i) {
    for (size_t d = 0; d < difficulties.size(); ++d) {
      CellKey key = group;
      key.difficulty = difficulties[d];
      const auto it = cells[i].find(key);
      if (it == cells[i].end()) continue;
      const json& e = *it->second;
      PlotSeries s;
      s.name =
          st.Name(sources[i], fmt::format("{}: AP_R40 {}", difficulties[d], ApText(e, "ap_r40")));
      s.x = Numbers(e["curve"], "recall");
      s.y = Numbers(e["curve"], "precision");
      s.steps = true;
      s.colour = PaletteColour(sources.size() > 1 ? i : d);
      if (sources.size() > 1) s.dash_array = kDash[d % std::size(kDash)];
      p.series.push_back(std::move(s));
      caption.push_back(fmt::format("{}{} {} valid labels",
                                    sources.size() > 1 ? sources[i].label + ", " : "",
                                    difficulties[d], e.value("num_valid_labels", 0)));
    }
  }
  p.caption = fmt::format("The exact curves (every score) of each difficulty, drawn as steps; {}.",
                          fmt::join(caption, "; "));
  return p;
}

Plot RocFigure(const std::vector<ReportSource>& sources, const std::vector<const json*>& entries,
               const CellKey& key, const std::string& stem, const Styler& st) {
  Plot p;
  p.id = "roc_" + stem;
  p.title = CellTitle(key, *entries.front()) + ": recall vs false positives";
  p.x_label = "false positives per frame";
  p.y_label = "recall";
  p.x_min = 0, p.y_min = 0, p.y_max = 1;
  std::vector<std::string> caption;
  for (size_t i = 0; i < sources.size(); ++i) {
    if (entries[i] == nullptr) continue;
    const json& e = *entries[i];
    PlotSeries s;
    s.x = Numbers(e["curve"], "fp_per_frame");
    s.y = Numbers(e["curve"], "recall");
    const double frames = Num(sources[i].results["input"], "num_frames");
    s.name = st.Name(sources[i],
                     fmt::format("recall at each score threshold ({} frames)", Fixed(frames, 0)));
    s.colour = st.Colour(i, 0);
    s.style = s.x.size() <= 60 ? SeriesStyle::kLineMarkers : SeriesStyle::kLine;
    const double max_recall = s.y.empty() ? kNaN : *std::max_element(s.y.begin(), s.y.end());
    const double max_fppf = s.x.empty() ? kNaN : *std::max_element(s.x.begin(), s.x.end());
    caption.push_back(fmt::format("{}recall reaches {} at {} false positives per frame",
                                  sources.size() > 1 ? sources[i].label + ": " : "",
                                  Fixed(max_recall, 3), Fixed(max_fppf, 3)));
    p.series.push_back(std::move(s));
  }
  p.caption = fmt::format("{}.", fmt::join(caption, "; "));
  return p;
}

Plot ReliabilityFigure(const std::vector<ReportSource>& sources,
                       const std::vector<const json*>& entries, const CellKey& key,
                       const std::string& stem, const Styler& st) {
  Plot p;
  p.id = "reliability_" + stem;
  p.title = CellTitle(key, *entries.front()) + ": reliability";
  p.x_label = "mean score in bin";
  p.y_label = "fraction of TPs in bin";
  p.x_min = 0, p.x_max = 1, p.y_min = 0, p.y_max = 1;
  PlotSeries diagonal;
  diagonal.name = "perfect calibration";
  diagonal.x = {0, 1};
  diagonal.y = {0, 1};
  diagonal.colour = "#999999";
  diagonal.dashed = true;
  p.series.push_back(diagonal);
  std::vector<std::string> caption;
  for (size_t i = 0; i < sources.size(); ++i) {
    if (entries[i] == nullptr) continue;
    const json& cal = (*entries[i])["calibration"];
    PlotSeries s;
    std::vector<std::string> counts;
    for (const json& b : cal["bins"]) {
      const bool filled = b.value("count", 0) > 0;
      s.x.push_back(filled ? Num(b, "mean_score") : kNaN);
      s.y.push_back(filled ? Num(b, "tp_fraction") : kNaN);
      counts.push_back(fmt::format("{}", b.value("count", 0)));
    }
    // LaECE (IoU as the target) and D-ECE (score x box position and size bins) beside the ECE,
    // where the results have them (older folders do not).
    std::string more;
    if (cal.contains("laece")) more += fmt::format(", LaECE {}", Fixed(Num(cal, "laece"), 4));
    if (cal.contains("dece")) more += fmt::format(", D-ECE {}", Fixed(Num(cal, "dece"), 4));
    s.name = st.Name(sources[i], fmt::format("ECE {}{} ({} detections)", Fixed(Num(cal, "ece"), 4),
                                             more, cal.value("num_detections", 0)));
    s.colour = st.Colour(i, 1);
    s.style = SeriesStyle::kLineMarkers;
    caption.push_back(fmt::format("{}ECE {}{}; detections per bin {}",
                                  sources.size() > 1 ? sources[i].label + ": " : "",
                                  Fixed(Num(cal, "ece"), 4), more, fmt::join(counts, ", ")));
    p.series.push_back(std::move(s));
  }
  p.caption =
      fmt::format("{} (empty bins are not drawn; LaECE and D-ECE: docs/metrics.md, Calibration).",
                  fmt::join(caption, "; "));
  return p;
}

bool HasLocalization(const json* e) {
  if (e == nullptr || !e->contains("localization")) return false;
  for (const json& b : (*e)["localization"]) {
    if (b.value("count", 0) > 0 && std::isfinite(Num(b, "centre_error_median_m"))) return true;
  }
  return false;
}

Plot LocalizationFigure(const std::vector<ReportSource>& sources,
                        const std::vector<const json*>& entries, const CellKey& key,
                        const std::string& stem, const Styler& st) {
  Plot p;
  p.id = "localization_" + stem;
  p.title = CellTitle(key, *entries.front()) + ": 3D error vs distance";
  p.x_label = "label depth z (m), bin centre";
  p.y_label = "error (m)";
  p.x_min = 0, p.y_min = 0;
  std::vector<std::string> caption;
  for (size_t i = 0; i < sources.size(); ++i) {
    if (!HasLocalization(entries[i])) continue;
    PlotSeries centre, depth;
    int64_t pairs = 0;
    std::vector<std::string> per_bin;  // "10-15 m: 4" for the bins with pairs
    for (const json& b : (*entries[i])["localization"]) {
      const double mid = (Num(b, "lower_m") + Num(b, "upper_m")) / 2;
      const bool filled = b.value("count", 0) > 0;
      pairs += b.value("count", 0);
      if (filled) {
        per_bin.push_back(fmt::format("{:g}-{:g} m: {}", Num(b, "lower_m"), Num(b, "upper_m"),
                                      b.value("count", 0)));
      }
      centre.x.push_back(mid);
      centre.y.push_back(filled ? Num(b, "centre_error_median_m") : kNaN);
      centre.y_low.push_back(filled ? Num(b, "centre_error_median_m") : kNaN);
      centre.y_high.push_back(filled ? Num(b, "centre_error_p90_m") : kNaN);
      depth.x.push_back(mid);
      depth.y.push_back(filled ? Num(b, "abs_depth_error_median_m") : kNaN);
      depth.y_low.push_back(filled ? Num(b, "abs_depth_error_median_m") : kNaN);
      depth.y_high.push_back(filled ? Num(b, "abs_depth_error_p90_m") : kNaN);
    }
    centre.name = st.Name(sources[i], "median 3D centre error |c_det - c_label| (whisker: p90)");
    depth.name = st.Name(sources[i], "median |depth error| |z_det - z_label| (whisker: p90)");
    centre.colour = st.Colour(i, 0);
    depth.colour = st.Colour(i, 1);
    depth.dashed = true;
    centre.style = depth.style = SeriesStyle::kLineMarkers;
    caption.push_back(fmt::format("{}{} TP pairs with 3D boxes ({})",
                                  sources.size() > 1 ? sources[i].label + ": " : "", pairs,
                                  fmt::join(per_bin, ", ")));
    p.series.push_back(std::move(centre));
    p.series.push_back(std::move(depth));
  }
  p.caption = fmt::format("{}; bins of {} m; empty bins are not drawn.", fmt::join(caption, "; "),
                          Fixed(Num(sources.front().results["options"], "distance_bin_m"), 1));
  return p;
}

// The breakdown axes of a cell's results.json entry ("breakdown": eval --breakdown), in order.
std::vector<std::string> BreakdownAxes(const json* e) {
  std::vector<std::string> axes;
  if (e == nullptr || !e->contains("breakdown")) return axes;
  for (const json& b : (*e)["breakdown"]) {
    const std::string axis = b.value("axis", "");
    if (std::find(axes.begin(), axes.end(), axis) == axes.end()) axes.push_back(axis);
  }
  return axes;
}

// AP_R40 per bin of one breakdown axis (eval --breakdown), one bar series per source: the bins are
// the first source's; a source without them has no bars there.
Plot BreakdownFigure(const std::vector<ReportSource>& sources,
                     const std::vector<const json*>& entries, const CellKey& key,
                     const std::string& axis, const std::string& stem, const Styler& st) {
  Plot p;
  p.id = "breakdown_" + axis + "_" + stem;
  p.title = CellTitle(key, *entries.front()) + ": AP_R40 by " + axis;
  p.x_label = axis + " bin";
  p.y_label = "AP_R40 (%)";
  p.y_min = 0, p.y_max = 100;
  for (const json& b : (*entries.front())["breakdown"]) {
    if (b.value("axis", "") == axis) p.categories.push_back(b.value("bin", ""));
  }
  std::vector<std::string> caption;
  for (size_t i = 0; i < sources.size(); ++i) {
    if (entries[i] == nullptr || !entries[i]->contains("breakdown")) continue;
    PlotSeries s;
    s.style = SeriesStyle::kBars;
    s.name = st.Name(sources[i], "AP_R40");
    s.colour = st.Colour(i, 0);
    std::vector<std::string> values;
    bool intervals = false;  // `eval --bootstrap`: each bin's AP_R40 interval as a whisker
    for (size_t c = 0; c < p.categories.size(); ++c) {
      double v = kNaN, lower = kNaN, upper = kNaN;
      int64_t labels = 0;
      for (const json& b : (*entries[i])["breakdown"]) {
        if (b.value("axis", "") == axis && b.value("bin", "") == p.categories[c]) {
          v = Num(b, "ap_r40");
          labels = b.value("num_valid_labels", 0);
          if (b.contains("bootstrap") && b["bootstrap"].contains("ap_r40")) {
            lower = Num(b["bootstrap"]["ap_r40"], "lower");
            upper = Num(b["bootstrap"]["ap_r40"], "upper");
            intervals = true;
          }
        }
      }
      s.x.push_back(static_cast<double>(c));
      s.y.push_back(v);
      s.y_low.push_back(lower);
      s.y_high.push_back(upper);
      values.push_back(fmt::format("{} {}{} ({} labels)", p.categories[c], Fixed(v, 2),
                                   std::isfinite(lower)
                                       ? fmt::format(" [{}, {}]", Fixed(lower, 2), Fixed(upper, 2))
                                       : std::string(),
                                   labels));
    }
    if (!intervals) s.y_low.clear(), s.y_high.clear();
    caption.push_back(fmt::format("{}{}", sources.size() > 1 ? sources[i].label + ": " : "",
                                  fmt::join(values, ", ")));
    p.series.push_back(std::move(s));
    // LET cells: each bin's LET-APL, a bar beside its AP (a colour of its own: the third role with
    // one source, after the naive bars' colours with several).
    PlotSeries apl;
    apl.style = SeriesStyle::kBars;
    apl.name = st.Name(sources[i], "APL_R40 (LET, affinity-weighted)");
    apl.colour = sources.size() > 1 ? PaletteColour(i + 2 * sources.size()) : st.Colour(i, 2);
    std::vector<std::string> apl_values;
    for (size_t c = 0; c < p.categories.size(); ++c) {
      double v = kNaN;
      for (const json& b : (*entries[i])["breakdown"]) {
        if (b.value("axis", "") == axis && b.value("bin", "") == p.categories[c] &&
            b.contains("apl_r40")) {
          v = Num(b, "apl_r40");
          apl_values.push_back(fmt::format("{} {}", p.categories[c], Fixed(v, 2)));
        }
      }
      apl.x.push_back(static_cast<double>(c));
      apl.y.push_back(v);
    }
    if (!apl_values.empty()) {
      caption.push_back(fmt::format("{}APL_R40 {}",
                                    sources.size() > 1 ? sources[i].label + " " : "",
                                    fmt::join(apl_values, ", ")));
      p.series.push_back(std::move(apl));
    }
    // eval --breakdown-naive: each bin evaluated on its own, a bar beside the stable one (a colour
    // of its own: the next role with one source, the palette's second half with several).
    PlotSeries naive;
    naive.style = SeriesStyle::kBars;
    naive.name = st.Name(sources[i], "AP_R40 naive (bin evaluated alone)");
    naive.colour = sources.size() > 1 ? PaletteColour(i + sources.size()) : st.Colour(i, 1);
    std::vector<std::string> naive_values;
    for (size_t c = 0; c < p.categories.size(); ++c) {
      double v = kNaN;
      for (const json& b : (*entries[i])["breakdown"]) {
        if (b.value("axis", "") == axis && b.value("bin", "") == p.categories[c] &&
            b.contains("naive")) {
          v = Num(b["naive"], "ap_r40");
          naive_values.push_back(fmt::format("{} {}", p.categories[c], Fixed(v, 2)));
        }
      }
      naive.x.push_back(static_cast<double>(c));
      naive.y.push_back(v);
    }
    if (!naive_values.empty()) {
      caption.push_back(fmt::format("{}naive {}", sources.size() > 1 ? sources[i].label + " " : "",
                                    fmt::join(naive_values, ", ")));
      p.series.push_back(std::move(naive));
    }
  }
  p.caption = fmt::format(
      "{}. From the cell's one matching: a pair counts in its label's bin, a detection without a "
      "value on the axis in every bin (docs/metrics.md, Breakdowns); a bin without labels has no "
      "bar; with eval --bootstrap, whiskers and brackets give each bin's interval; in the LET "
      "kinds a second bar per bin gives its LET-APL; with eval --breakdown-naive, another bar per "
      "bin gives the bin evaluated on its own.",
      fmt::join(caption, "; "));
  return p;
}

// `eval --errors`: the AP_R40 points each error type's fix gains, a bar per type and source.
Plot ErrorsFigure(const std::vector<ReportSource>& sources, const std::vector<const json*>& entries,
                  const CellKey& key, const std::string& stem, const Styler& st) {
  static const char* const kTypes[] = {"cls", "loc", "both", "dupe", "bkg", "missed"};
  Plot p;
  p.id = "errors_" + stem;
  p.title = CellTitle(key, *entries.front()) + ": where the AP goes (TIDE)";
  p.x_label = "error type fixed alone (FP, FN: every false positive / miss)";
  p.y_label = "AP_R40 gained (points)";
  for (const char* type : kTypes) p.categories.push_back(type);
  p.categories.push_back("FP");
  p.categories.push_back("FN");
  std::vector<std::string> caption;
  for (size_t i = 0; i < sources.size(); ++i) {
    if (entries[i] == nullptr || !entries[i]->contains("errors")) continue;
    const json& e = (*entries[i])["errors"];
    PlotSeries s;
    s.style = SeriesStyle::kBars;
    s.name = st.Name(sources[i], "dAP_R40");
    s.colour = st.Colour(i, 0);
    std::vector<std::string> values;
    for (size_t c = 0; c < p.categories.size(); ++c) {
      const bool special = c >= std::size(kTypes);
      const double v = special ? Num(e["special"], c == std::size(kTypes) ? "fp_r40" : "fn_r40")
                               : Num(e["delta_ap_r40"], kTypes[c]);
      s.x.push_back(static_cast<double>(c));
      s.y.push_back(v);
      values.push_back(special ? fmt::format("{} {}", p.categories[c], Fixed(v, 2))
                               : fmt::format("{} {} ({})", p.categories[c], Fixed(v, 2),
                                             e["count"].value(kTypes[c], 0)));
    }
    caption.push_back(fmt::format("{}AP_R40 {}; {}",
                                  sources.size() > 1 ? sources[i].label + ": " : "",
                                  Fixed(Num(e, "ap_r40"), 2), fmt::join(values, ", ")));
    p.series.push_back(std::move(s));
  }
  p.caption = fmt::format(
      "{}. dAP (count): AP_R40 with only that type fixed, re-evaluated, minus the AP as is "
      "(docs/metrics.md, Error analysis); every detection takes part, so a Dupe's fix can lower "
      "the AP.",
      fmt::join(caption, "; "));
  return p;
}

Plot BrierFigure(const std::vector<ReportSource>& sources,
                 const std::vector<std::map<CellKey, const json*>>& cells, const CellKey& group,
                 const std::vector<std::string>& difficulties, const std::string& stem,
                 const Styler& st) {
  Plot p;
  p.id = "brier_" + stem;
  p.title = fmt::format("{} {}: Brier scores", group.class_name, group.metric);
  p.x_label = "difficulty";
  p.y_label = "Brier score (lower is better)";
  p.categories = difficulties;
  p.y_min = 0;
  static constexpr const char* kKinds[][2] = {{"over_labels", "over labels"},
                                              {"over_detections", "over detections"},
                                              {"over_all", "over all"}};
  std::vector<std::string> caption;
  auto brier = [&](size_t i, size_t d, size_t k) {
    CellKey key = group;
    key.difficulty = difficulties[d];
    auto it = cells[i].find(key);
    return it == cells[i].end() ? kNaN : Num((*it->second)["brier"], kKinds[k][0]);
  };
  const bool several = sources.size() > 1;
  if (several) {
    // One colour per results folder, as in every other figure: the three kinds of each difficulty
    // are categories of their own, one bar series per folder.
    // Short names, so that nine fit under the bars: "E labels", "M dets", "H all".
    static constexpr const char* kShort[] = {"labels", "dets", "all"};
    p.categories.clear();
    for (const std::string& difficulty : difficulties) {
      for (const char* kind : kShort) p.categories.push_back(difficulty.substr(0, 1) + " " + kind);
    }
    p.x_label = "difficulty (E, M, H) and Brier score over labels, detections, all";
  }
  for (size_t i = 0; i < sources.size(); ++i) {
    for (size_t k = 0; k < 3; ++k) {
      std::vector<std::string> values;
      for (size_t d = 0; d < difficulties.size(); ++d) values.push_back(Fixed(brier(i, d, k), 4));
      caption.push_back(fmt::format("{}Brier {} {}", several ? sources[i].label + " " : "",
                                    kKinds[k][1], fmt::join(values, " / ")));
    }
    if (several) {
      PlotSeries s;
      s.style = SeriesStyle::kBars;
      s.name = sources[i].label;
      s.colour = st.Colour(i, 0);
      for (size_t d = 0; d < difficulties.size(); ++d) {
        for (size_t k = 0; k < 3; ++k) {
          s.x.push_back(static_cast<double>(s.x.size()));
          s.y.push_back(brier(i, d, k));
        }
      }
      p.series.push_back(std::move(s));
      continue;
    }
    for (size_t k = 0; k < 3; ++k) {
      PlotSeries s;
      s.style = SeriesStyle::kBars;
      s.name = std::string("Brier ") + kKinds[k][1];
      s.colour = st.Colour(i, k);
      for (size_t d = 0; d < difficulties.size(); ++d) {
        s.x.push_back(static_cast<double>(d));
        s.y.push_back(brier(i, d, k));
      }
      p.series.push_back(std::move(s));
    }
  }
  if (several) p.width_px = std::max(p.width_px, 80.0 * static_cast<double>(p.categories.size()));
  p.caption = fmt::format("{} ({}).", fmt::join(caption, "; "), fmt::join(difficulties, " / "));
  return p;
}

// The kind of a figure, from its id: "pr_difficulties", "pr", "roc", "reliability",
// "localization", "breakdown", "brier", "sweep", "compare".
std::string FigureKind(const std::string& id) {
  if (id.rfind("pr_difficulties_", 0) == 0) return "pr_difficulties";
  return id.substr(0, id.find('_'));
}

// The order of the kinds within a section: the difficulties' PR figure, then each kind's row.
int FigureKindRank(const std::string& id) {
  static const char* const kOrder[] = {"pr_difficulties", "pr",        "roc",    "reliability",
                                       "localization",    "breakdown", "errors", "brier"};
  const std::string kind = FigureKind(id);
  for (int i = 0; i < static_cast<int>(std::size(kOrder)); ++i) {
    if (kind == kOrder[i]) return i;
  }
  return static_cast<int>(std::size(kOrder));
}

// "Car 2d, loose overlaps" -> "car-2d-loose-overlaps": the section's anchor.
std::string Slug(const std::string& text) {
  std::string slug;
  for (char c : text) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      slug += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else if (!slug.empty() && slug.back() != '-') {
      slug += '-';
    }
  }
  return slug;
}

std::string ScriptJson(const json& j) {
  std::string text = j.dump();
  for (size_t p = 0; (p = text.find("</", p)) != std::string::npos; p += 3)
    text.replace(p, 2, "<\\/");
  return text;
}

const std::vector<std::string> kSweepColumns = {
    "class",           "metric",       "difficulty",       "filter",       "value",
    "naive_precision", "naive_recall", "stable_precision", "stable_recall"};
const std::vector<std::string> kCompareColumns = {
    "class",   "metric",        "difficulty", "lower_m",       "upper_m",
    "count_a", "abs_dz_mean_a", "count_b",    "abs_dz_mean_b", "difference_b_minus_a",
    "model_dz"};
const std::set<std::string> kTextColumns = {"class",  "metric",  "difficulty",
                                            "filter", "measure", "axis"};

// A CSV of FormatSweepCsv or FormatCompareCsv: a header, then rows of plain fields (no quoting).
std::vector<ReportSource::Row> ReadCsvRows(const fs::path& path,
                                           const std::vector<std::string>& required) {
  std::istringstream in(ReadFile(path));
  std::string line;
  STEREODET_CHECK_IO(static_cast<bool>(std::getline(in, line))) << path.string() << " is empty";
  std::vector<std::string> names;
  std::stringstream header(line);
  for (std::string name; std::getline(header, name, ',');) names.push_back(name);
  for (const std::string& r : required) {
    STEREODET_CHECK_IO(std::find(names.begin(), names.end(), r) != names.end())
        << path.string() << " has no column " << r << " (is it stereodet's?)";
  }
  std::vector<ReportSource::Row> rows;
  for (int line_number = 2; std::getline(in, line); ++line_number) {
    if (line.empty()) continue;
    ReportSource::Row row;
    // Split keeps empty fields, a last one included ("...,0.3," ends in an empty cell).
    size_t i = 0;
    for (const std::string_view field_view : Split(line, ',')) {
      const std::string field(field_view);
      STEREODET_CHECK_IO(i < names.size()) << path.string() << ":" << line_number
                                           << ": more fields than the header's " << names.size();
      if (kTextColumns.count(names[i]) != 0) {
        row.text[names[i]] = field;
      } else {
        char* end = nullptr;
        const double v = std::strtod(field.c_str(), &end);
        row.number[names[i]] = field.empty() || field == "-" || *end != '\0' ? kNaN : v;
      }
      ++i;
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

double RowNumber(const ReportSource::Row& row, const std::string& name) {
  auto it = row.number.find(name);
  return it == row.number.end() ? kNaN : it->second;
}

std::string RowText(const ReportSource::Row& row, const std::string& name) {
  auto it = row.text.find(name);
  return it == row.text.end() ? std::string() : it->second;
}

CellKey RowKey(const ReportSource::Row& row) {
  return {RowText(row, "class"), RowText(row, "metric"), RowText(row, "difficulty"), ""};
}

// The cells of CSV sources in the first source's order, with every source's rows of each.
std::vector<std::pair<CellKey, std::vector<std::vector<const ReportSource::Row*>>>> RowCells(
    const std::vector<ReportSource>& sources) {
  std::vector<std::pair<CellKey, std::vector<std::vector<const ReportSource::Row*>>>> cells;
  std::map<CellKey, size_t> index;
  for (const ReportSource::Row& row : sources.front().rows) {
    const CellKey key = RowKey(row);
    if (index.emplace(key, cells.size()).second) {
      cells.push_back({key, std::vector<std::vector<const ReportSource::Row*>>(sources.size())});
    }
  }
  for (size_t s = 0; s < sources.size(); ++s) {
    for (const ReportSource::Row& row : sources[s].rows) {
      auto it = index.find(RowKey(row));
      if (it != index.end()) cells[it->second].second[s].push_back(&row);
    }
  }
  return cells;
}

std::string RowCellStem(const CellKey& k) {
  return Lower(k.class_name) + "_" + k.metric + "_" + Lower(k.difficulty);
}

Plot SweepFigure(const std::vector<ReportSource>& sources,
                 const std::vector<std::vector<const ReportSource::Row*>>& rows, const CellKey& key,
                 const Styler& st) {
  Plot p;
  p.id = "sweep_" + RowCellStem(key);
  std::string filter;
  for (const auto& source_rows : rows) {
    if (!source_rows.empty()) filter = source_rows.front()->text.at("filter");
  }
  p.title = fmt::format("{} {} {}: filter sweep ({})", key.class_name, key.metric, key.difficulty,
                        filter);
  p.x_label = "filter value: " + filter;
  p.y_label = "precision, recall";
  p.y_min = 0, p.y_max = 1;
  static constexpr const char* kSeries[][2] = {{"naive_precision", "naive filter: precision"},
                                               {"stable_precision", "stable filter: precision"},
                                               {"naive_recall", "naive filter: recall"},
                                               {"stable_recall", "stable filter: recall"}};
  std::vector<std::string> caption;
  for (size_t i = 0; i < sources.size(); ++i) {
    if (rows[i].empty()) continue;
    for (size_t k = 0; k < 4; ++k) {
      PlotSeries s;
      s.name = st.Name(sources[i], kSeries[k][1]);
      for (const ReportSource::Row* row : rows[i]) {
        s.x.push_back(RowNumber(*row, "value"));
        double y = RowNumber(*row, kSeries[k][0]);
        // compare.csv written before difference_a_minus_b existed: the negative of B - A.
        if (k == 2 && !row->number.count(kSeries[k][0]))
          y = -RowNumber(*row, "difference_b_minus_a");
        s.y.push_back(y);
      }
      s.colour = st.Colour(i, k);
      s.dashed = k % 2 == 1;  // stable
      s.style = k < 2 ? SeriesStyle::kLine : SeriesStyle::kLineMarkers;
      p.series.push_back(std::move(s));
    }
    const ReportSource::Row& last = *rows[i].back();
    caption.push_back(fmt::format(
        "{}at {} = {}: precision {} naive / {} stable, recall {} naive / {} stable",
        sources.size() > 1 ? sources[i].label + ": " : "", filter,
        fmt::format("{:g}", RowNumber(last, "value")), Fixed(RowNumber(last, "naive_precision"), 3),
        Fixed(RowNumber(last, "stable_precision"), 3), Fixed(RowNumber(last, "naive_recall"), 3),
        Fixed(RowNumber(last, "stable_recall"), 3)));
  }
  p.caption = fmt::format("{}.", fmt::join(caption, "; "));
  return p;
}

Plot CompareFigure(const std::vector<ReportSource>& sources,
                   const std::vector<std::vector<const ReportSource::Row*>>& rows,
                   const CellKey& key, const Styler& st) {
  const ReportSource& first = sources.front();
  // "A (lidar)" where compare.json names the detection folders, else "A".
  const std::string a = first.name_a.empty() ? "A" : "A (" + first.name_a + ")";
  const std::string b = first.name_b.empty() ? "B" : "B (" + first.name_b + ")";
  Plot p;
  p.id = "compare_" + RowCellStem(key);
  p.title = fmt::format("{} {} {}: depth error of A and B vs distance", key.class_name, key.metric,
                        key.difficulty);
  p.x_label = "label depth z (m), bin centre";
  p.y_label = "depth error (m)";
  p.x_min = 0;
  static constexpr const char* kColumns[] = {"abs_dz_mean_a", "abs_dz_mean_b",
                                             "difference_a_minus_b", "model_dz"};
  const std::string names[] = {a + ": mean |depth error|", b + ": mean |depth error|", "A - B",
                               "stereo model dz = z^2 / (b f) dd"};
  std::vector<std::string> caption;
  double measured_max = 0, measured_min = 0;  // of A, B and A - B: the axis is scaled to these
  std::vector<std::string> model_beyond;
  for (size_t i = 0; i < sources.size(); ++i) {
    if (rows[i].empty()) continue;
    int64_t pairs_a = 0, pairs_b = 0;
    for (size_t k = 0; k < 4; ++k) {
      PlotSeries s;
      s.name = st.Name(sources[i], names[k]);
      for (const ReportSource::Row* row : rows[i]) {
        s.x.push_back((RowNumber(*row, "lower_m") + RowNumber(*row, "upper_m")) / 2);
        double y = RowNumber(*row, kColumns[k]);
        // compare.csv written before difference_a_minus_b existed: the negative of B - A.
        if (k == 2 && !row->number.count(kColumns[k])) y = -RowNumber(*row, "difference_b_minus_a");
        s.y.push_back(y);
        if (k < 3 && std::isfinite(y)) {
          measured_max = std::max(measured_max, y);
          measured_min = std::min(measured_min, y);
        }
      }
      s.colour = k == 3 ? "#777777" : st.Colour(i, k);
      s.dashed = k >= 2;
      s.style = k == 3 ? SeriesStyle::kLine : SeriesStyle::kLineMarkers;
      p.series.push_back(std::move(s));
    }
    std::vector<std::string> per_bin;  // "10-15 m: 1/1" for the bins with pairs
    for (const ReportSource::Row* row : rows[i]) {
      const auto count_a = static_cast<int64_t>(RowNumber(*row, "count_a"));
      const auto count_b = static_cast<int64_t>(RowNumber(*row, "count_b"));
      pairs_a += count_a;
      pairs_b += count_b;
      if (count_a + count_b > 0) {
        per_bin.push_back(fmt::format("{:g}-{:g} m: {}/{}", RowNumber(*row, "lower_m"),
                                      RowNumber(*row, "upper_m"), count_a, count_b));
      }
    }
    caption.push_back(fmt::format("{}{} matched pairs of A, {} of B (per bin, A/B: {})",
                                  sources.size() > 1 ? sources[i].label + ": " : "", pairs_a,
                                  pairs_b, fmt::join(per_bin, ", ")));
  }
  // The model grows as z^2 and would flatten the measured errors to the axis: the y axis is
  // scaled to those, and the model's line leaves the plot where it is larger (said below).
  if (measured_max > 0) {
    p.y_max = 1.25 * measured_max;
    p.y_min = 1.25 * measured_min;
    for (const PlotSeries& s : p.series) {
      if (s.colour != "#777777") continue;
      for (size_t j = 0; j < s.y.size(); ++j) {
        if (std::isfinite(s.y[j]) && s.y[j] > p.y_max) {
          model_beyond.push_back(fmt::format("{:g} m ({:.2f} m)", s.x[j], s.y[j]));
          break;
        }
      }
    }
  }
  p.caption = fmt::format(
      "{}; A - B (compare.csv's difference_a_minus_b) is positive where A errs more; empty bins "
      "are not drawn; the model at the bin centre{}.",
      fmt::join(caption, "; "),
      model_beyond.empty()
          ? std::string()
          : "; the axis is scaled to the measured errors, and the model leaves it from z = " +
                model_beyond.front() + " on");
  return p;
}

// A curve CSV of WriteEvalReport (curves/pr_*.csv) as the JSON object of columns the figures read:
// one array per column, the counts tp, fp, fn as integers, the other columns as numbers (null for
// an empty field: NaN). Exact: the CSV holds every number's shortest round-trip text.
json ReadCurveCsv(const fs::path& path) {
  const std::string text = ReadFile(path);
  std::vector<std::string_view> lines = Split(text, '\n');
  if (!lines.empty() && lines.back().empty()) lines.pop_back();
  STEREODET_CHECK_IO(!lines.empty()) << path.string() << ": empty, not a curve CSV";
  const std::vector<std::string_view> header = Split(lines.front(), ',');
  std::vector<json::array_t> columns(header.size());
  for (json::array_t& c : columns) c.reserve(lines.size() - 1);
  for (size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string_view> fields = Split(lines[i], ',');
    STEREODET_CHECK_IO(fields.size() == header.size())
        << path.string() << ":" << i + 1 << ": " << fields.size() << " fields, the header has "
        << header.size();
    for (size_t c = 0; c < fields.size(); ++c) {
      if (fields[c].empty()) {
        columns[c].emplace_back(nullptr);
      } else if (header[c] == "tp" || header[c] == "fp" || header[c] == "fn") {
        const std::optional<long long> v = ParseInt(fields[c]);
        STEREODET_CHECK_IO(v.has_value()) << path.string() << ":" << i + 1 << ": " << header[c]
                                          << " '" << fields[c] << "' is not a count";
        columns[c].emplace_back(static_cast<int64_t>(*v));
      } else {
        const std::optional<double> v = ParseDouble(fields[c]);
        STEREODET_CHECK_IO(v.has_value()) << path.string() << ":" << i + 1 << ": " << header[c]
                                          << " '" << fields[c] << "' is not a number";
        columns[c].emplace_back(*v);
      }
    }
  }
  json curve = json::object();
  for (size_t c = 0; c < header.size(); ++c) curve[std::string(header[c])] = std::move(columns[c]);
  return curve;
}

}  // namespace

std::string FolderLabel(const fs::path& folder) {
  const fs::path p = folder.lexically_normal();  // "a/b/." -> "a/b/"
  return (p.has_filename() ? p.filename() : p.parent_path().filename()).string();
}

ReportSource ReadReportSource(const fs::path& folder, const std::string& label) {
  const fs::path path = folder / "results.json";
  ReportSource source;
  source.folder = folder;
  source.label = label;
  if (!fs::is_regular_file(path)) {
    for (const auto& [name, kind] :
         {std::pair<const char*, ReportKind>{"sweep.csv", ReportKind::kSweep},
          {"compare.csv", ReportKind::kCompare}}) {
      if (!fs::is_regular_file(folder / name)) continue;
      source.kind = kind;
      source.rows =
          ReadCsvRows(folder / name, kind == ReportKind::kSweep ? kSweepColumns : kCompareColumns);
      if (kind == ReportKind::kCompare && fs::is_regular_file(folder / "compare.json")) {
        const fs::path inputs_path = folder / "compare.json";
        json inputs;
        try {
          inputs = json::parse(ReadFile(inputs_path));
        } catch (const json::exception& e) {
          STEREODET_THROW_IO() << inputs_path.string() << ": not JSON: " << e.what();
        }
        const auto name = [&](const char* key) {
          return inputs.is_object() && inputs.contains(key) && inputs[key].is_string()
                     ? FolderLabel(inputs[key].get<std::string>())
                     : std::string();
        };
        source.name_a = name("det_a");
        source.name_b = name("det_b");
      }
      if (kind == ReportKind::kCompare) {
        // The paired intervals of `eval compare --bootstrap` (and of its bins), for the page's
        // difference table.
        const std::vector<std::string> paired_columns = {
            "class", "metric",    "difficulty",      "measure",        "a",
            "b",     "a_minus_b", "a_minus_b_lower", "a_minus_b_upper"};
        for (const char* file : {"bootstrap.csv", "bootstrap_breakdown.csv"}) {
          if (!fs::is_regular_file(folder / file)) continue;
          for (ReportSource::Row& row : ReadCsvRows(folder / file, paired_columns)) {
            source.paired.push_back(std::move(row));
          }
        }
      }
      return source;
    }
    STEREODET_THROW_IO() << path.string() << " is not there: is " << folder.string()
                         << " a results folder of `stereodet eval --out`? (nor is there a "
                            "sweep.csv of eval sweep or a compare.csv of eval compare)";
  }
  try {
    source.results = json::parse(ReadFile(path));
  } catch (const json::exception& e) {
    STEREODET_THROW_IO() << path.string() << ": not JSON: " << e.what();
  }
  if (source.results.is_object() && source.results.value("mode", "") == "coco") {
    source.kind = ReportKind::kCoco;
    LoadCocoReportData(folder, &source.results);
    return source;
  }
  STEREODET_CHECK_IO(source.results.is_object() && source.results.contains("results") &&
                     source.results["results"].is_array())
      << path.string() << " is not a stereodet results.json (it has no \"results\" array)";
  CheckResultNumbers(source.results, path);
  // The exact curves are in the CSVs results.json names; the figures read them as "curve".
  for (json& e : source.results["results"]) {
    if (e.is_object() && e.contains("curve_csv") && e["curve_csv"].is_string() &&
        !e.contains("curve")) {
      e["curve"] = ReadCurveCsv(folder / e["curve_csv"].get<std::string>());
    }
  }
  source.records = MatchRecordsFile(folder, source.results);
  return source;
}

std::vector<ReportFigure> ReportFigures(const std::vector<ReportSource>& sources) {
  STEREODET_CHECK(!sources.empty()) << "a report needs at least one results folder";
  for (const ReportSource& s : sources) {
    STEREODET_CHECK(s.kind == sources.front().kind)
        << "report: " << s.folder.string() << " holds another kind of results than "
        << sources.front().folder.string() << " (eval, eval sweep and eval compare do not mix)";
  }
  const Styler st{sources.size()};
  std::vector<ReportFigure> figures;
  if (sources.front().kind == ReportKind::kCoco) {
    for (CocoReportFigure& f : CocoReportFigures(CocoSources(sources))) {
      figures.push_back({std::move(f.section), std::move(f.plot)});
    }
    return figures;
  }
  if (sources.front().kind != ReportKind::kEval) {
    for (const auto& [key, rows] : RowCells(sources)) {
      const std::string section = key.class_name + " " + key.metric;
      figures.push_back({section, sources.front().kind == ReportKind::kSweep
                                      ? SweepFigure(sources, rows, key, st)
                                      : CompareFigure(sources, rows, key, st)});
    }
    return figures;
  }
  std::vector<std::map<CellKey, const json*>> cells;
  for (const ReportSource& s : sources) cells.push_back(Cells(s));
  const bool with_overlaps = SeveralOverlapSets(sources.front());
  // Groups (class x metric x overlaps) in the first source's result order, with their difficulties.
  std::vector<std::pair<CellKey, std::vector<std::string>>> groups;
  size_t group_start = 0;  // the index of the group's first figure
  for (const json& e : sources.front().results["results"]) {
    if (!e.value("evaluated", false)) continue;
    CellKey key = KeyOf(e);
    CellKey group = key;
    group.difficulty.clear();
    if (groups.empty() || groups.back().first != group) {
      groups.push_back({group, {}});
      group_start = figures.size();
    }
    groups.back().second.push_back(key.difficulty);
    const std::string stem = CellStem(key, with_overlaps);
    const std::string section = key.class_name + " " + key.metric +
                                (with_overlaps ? ", " + key.overlaps + " overlaps" : "");
    const std::vector<const json*> entries = EntriesFor(cells, key);
    figures.push_back({section, PrFigure(sources, entries, key, stem, st)});
    figures.push_back({section, RocFigure(sources, entries, key, stem, st)});
    figures.push_back({section, ReliabilityFigure(sources, entries, key, stem, st)});
    if (std::any_of(entries.begin(), entries.end(), HasLocalization)) {
      figures.push_back({section, LocalizationFigure(sources, entries, key, stem, st)});
    }
    for (const std::string& axis : BreakdownAxes(entries.front())) {
      figures.push_back({section, BreakdownFigure(sources, entries, key, axis, stem, st)});
    }
    if (std::any_of(entries.begin(), entries.end(),
                    [](const json* e) { return e != nullptr && e->contains("errors"); })) {
      figures.push_back({section, ErrorsFigure(sources, entries, key, stem, st)});
    }
    // The group's Brier figure after its last difficulty.
    const json& results = sources.front().results["results"];
    const size_t index = static_cast<size_t>(&e - &results[0]);
    bool last = true;
    for (size_t j = index + 1; j < results.size(); ++j) {
      if (!results[j].value("evaluated", false)) continue;
      CellKey next = KeyOf(results[j]);
      next.difficulty.clear();
      last = next != group;
      break;
    }
    if (last) {
      // The group's figures open with its difficulties' curves in one figure and close with its
      // Brier scores.
      const std::string group_stem = GroupStem(group, with_overlaps);
      figures.insert(figures.begin() + static_cast<std::ptrdiff_t>(group_start),
                     {section, PrDifficultiesFigure(sources, cells, group, groups.back().second,
                                                    with_overlaps, group_stem, st)});
      figures.push_back(
          {section, BrierFigure(sources, cells, group, groups.back().second, group_stem, st)});
      // Grouped by kind (each kind's difficulties in a row), difficulties in their order.
      std::stable_sort(figures.begin() + static_cast<std::ptrdiff_t>(group_start), figures.end(),
                       [](const ReportFigure& a, const ReportFigure& b) {
                         return FigureKindRank(a.plot.id) < FigureKindRank(b.plot.id);
                       });
    }
  }
  return figures;
}

namespace {

// The paper's Table 1 (issue 17): with several results folders, one table per class (Car,
// Pedestrian, Cyclist, in that order, those the first folder evaluated), one row per folder, at
// Moderate, the first overlap set (KITTI's: Car 0.7, Pedestrian and Cyclist 0.5) and 2D where
// evaluated (else the first metric): AP_R40 and AP_R11 of the folder's matcher, the exact AP
// (every score; the optimal and VOC matchers compute it, the KITTI matcher does not: "-"), and
// the Brier score over labels.
std::string Table1Html(const std::vector<ReportSource>& sources) {
  if (sources.size() < 2) return "";
  const json& first = sources.front().results["results"];
  std::string metric, overlaps;
  for (const json& e : first) {
    if (!e.value("evaluated", false)) continue;
    if (overlaps.empty()) overlaps = Str(e, "overlaps");
    if (metric.empty() || Str(e, "metric") == "2d") metric = Str(e, "metric");
  }
  std::string html;
  for (const char* class_name : {"Car", "Pedestrian", "Cyclist"}) {
    auto find = [&](const ReportSource& s) -> const json* {
      for (const json& e : s.results["results"]) {
        if (e.value("evaluated", false) && Str(e, "class") == class_name &&
            Str(e, "metric") == metric && Str(e, "difficulty") == "Moderate" &&
            Str(e, "overlaps") == overlaps) {
          return &e;
        }
      }
      return nullptr;
    };
    const json* cell = find(sources.front());
    if (cell == nullptr) continue;
    html += fmt::format(
        "<h3>{0}, {1} Moderate, IoU {2}</h3>\n<table class=\"table1\" id=\"table1-{3}\">\n"
        "<tr><th>results</th><th>matcher</th><th>labels</th><th>AP_R40</th><th>AP_R11</th>"
        "<th>AP exact</th><th>Brier over labels</th></tr>\n",
        class_name, XmlEscape(metric), Fixed(Num(*cell, "min_overlap"), 2), Lower(class_name));
    for (const ReportSource& s : sources) {
      const json* e = find(s);
      const std::string matcher = Str(s.results["options"], "matcher");
      if (e == nullptr) {
        html += fmt::format(
            "<tr><td class=\"t\">{}</td><td class=\"t\">{}</td><td colspan=\"5\" "
            "class=\"t\">not evaluated</td></tr>\n",
            XmlEscape(s.label), XmlEscape(matcher));
        continue;
      }
      html += fmt::format(
          "<tr><td class=\"t\">{}</td><td class=\"t\">{}</td><td>{}{}</td><td>{}</td><td>{}</td>"
          "<td>{}</td><td>{}</td></tr>\n",
          XmlEscape(s.label), XmlEscape(matcher), e->value("num_valid_labels", 0),
          e->value("small_sample", false) ? "*" : "", ApText(*e, "ap_r40"), ApText(*e, "ap_r11"),
          ApText(*e, "ap_voc"), Fixed(Num((*e)["brier"], "over_labels"), 4));
    }
    html += "</table>\n";
  }
  if (html.empty()) return "";
  return "<h2 id=\"table1\">Table 1: one row per model</h2>\n<p style=\"font-size:12px\">As "
         "the paper's Table 1: AP in percent (AP_R40 and AP_R11 with each folder's matcher; AP "
         "exact over every score, which the optimal and VOC matchers compute and the KITTI matcher "
         "does not), the Brier score over labels (docs/metrics.md); * 40 or fewer valid "
         "labels.</p>\n" +
         html;
}

std::string WorstFramesHtml(const std::vector<ReportFrameViews>& views) {
  if (views.empty()) return "";
  std::string html =
      "<h2 id=\"worst-frames\">Worst frames</h2>\n<p style=\"font-size:12px\">Per class, the "
      "frames with most false negatives and most false positives at the operating point, from the "
      "per-detection records (matches.csv): their labels (dashed) and detections (solid) on the "
      "left image, TP green, FP red, FN blue, ignored grey, and the bird's-eye view.</p>\n";
  bool any = false;
  for (const ReportFrameViews& v : views) {
    if (!v.has_records) {
      html += fmt::format(
          "<p class=\"no-views\">{}: no frame views: the folder has no matches.csv (evaluate with "
          "<code>--records</code>).</p>\n",
          XmlEscape(v.label));
      continue;
    }
    for (const std::string& note : v.views.notes) {
      html += "<p style=\"font-size:12px\">note: " + XmlEscape(note) + "</p>\n";
    }
    any = any || !v.views.views.empty();
  }
  if (!any) return html;
  html +=
      "<table id=\"worst-frames\">\n<tr><th>results</th><th>cell</th><th>frames with</th>"
      "<th>frame</th><th>TP</th><th>FP</th><th>FN</th><th>image view</th><th>bird's-eye "
      "view</th></tr>\n";
  for (const ReportFrameViews& v : views) {
    for (const WrittenFrameView& w : v.views.views) {
      auto links = [&](const std::string& svg, const std::string& png, const char* kind) {
        std::string s = fmt::format(
            "<a class=\"stereodet-view-link\" data-frame=\"{}\" data-view=\"{}\" "
            "href=\"{}/{}\">SVG</a>",
            XmlEscape(w.frame_id), kind, v.folder, XmlEscape(svg));
        if (!png.empty()) {
          s += fmt::format(
              " <a class=\"stereodet-view-link\" data-frame=\"{}\" data-view=\"{}\" "
              "href=\"{}/{}\">PNG</a>",
              XmlEscape(w.frame_id), kind, v.folder, XmlEscape(png));
        }
        return s;
      };
      html += fmt::format(
          "<tr><td class=\"t\">{}</td><td class=\"t\">{}</td><td class=\"t\">{}</td>"
          "<td class=\"t\">{}</td><td>{}</td><td>{}</td><td>{}</td><td class=\"t\">{}</td>"
          "<td class=\"t\">{}</td></tr>\n",
          XmlEscape(v.label), ViewCellName(w.cell), w.reason, XmlEscape(w.frame_id), w.tp, w.fp,
          w.fn, links(w.image_svg, w.image_png, "image"), links(w.bev_svg, w.bev_png, "bev"));
    }
  }
  return html + "</table>\n";
}

}  // namespace

// The difference table of `eval compare --bootstrap` folders: per folder, cell (and bin, from
// bootstrap_breakdown.csv) the paired A - B of AP_R40 and Brier over labels with its interval,
// "*" where it excludes 0. Empty when no folder has bootstrap.csv.
std::string PairedTableHtml(const std::vector<ReportSource>& sources) {
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  std::string rows;
  for (const ReportSource& s : sources) {
    for (const ReportSource::Row& row : s.paired) {
      const auto text = [&](const char* name) { return RowText(row, name); };
      const std::string measure = text("measure");
      if (measure != "ap_r40" && measure != "brier_labels") continue;
      const int decimals = measure == "ap_r40" ? 2 : 4;
      std::string bin = "all";
      if (!text("axis").empty()) {
        const double lower = RowNumber(row, "lower"), upper = RowNumber(row, "upper");
        bin = text("axis") + " " +
              BreakdownBinName(std::isnan(lower) ? -kInfinity : lower,
                               std::isnan(upper) ? kInfinity : upper);
      }
      const double d = RowNumber(row, "a_minus_b"), lo = RowNumber(row, "a_minus_b_lower"),
                   hi = RowNumber(row, "a_minus_b_upper");
      const bool excludes_zero = lo > 0 || hi < 0;
      rows += fmt::format(
          "<tr><td class=\"t\">{}</td><td class=\"t\">{}</td><td class=\"t\">{}</td>"
          "<td class=\"t\">{}</td><td class=\"t\">{}</td><td class=\"t\">{}</td><td>{}</td>"
          "<td>{}</td><td>{} [{}, {}]{}</td></tr>\n",
          XmlEscape(s.label), XmlEscape(text("class")), XmlEscape(text("metric")),
          XmlEscape(text("difficulty")), XmlEscape(bin),
          measure == "ap_r40" ? "AP_R40" : "Brier over labels",
          Fixed(RowNumber(row, "a"), decimals), Fixed(RowNumber(row, "b"), decimals),
          Fixed(d, decimals), Fixed(lo, decimals), Fixed(hi, decimals), excludes_zero ? " *" : "");
    }
  }
  if (rows.empty()) return "";
  return "<h2 id=\"paired\">Paired A - B (eval compare --bootstrap)</h2>\n<p>Each difference "
         "with its paired bootstrap interval (both sets resampled with the same frames; "
         "docs/metrics.md, Bootstrap intervals); * where it excludes 0.</p>\n"
         "<table id=\"paired-table\">\n<tr><th>compare</th><th>class</th><th>metric</th>"
         "<th>difficulty</th><th>bin</th><th>measure</th><th>A</th><th>B</th><th>A - "
         "B</th></tr>\n" +
         rows + "</table>\n";
}

std::string ReportHtml(const std::vector<ReportSource>& sources,
                       const std::vector<ReportFigure>& figures, bool with_png,
                       const std::vector<ReportFrameViews>& views) {
  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<title>stereodet evaluation report</title>\n<style>\n"
      "body{font-family:'DejaVu Sans',Arial,sans-serif;margin:24px;color:#111;max-width:1600px}\n"
      "h1{font-size:22px}h2{font-size:18px;margin-top:32px;border-bottom:1px solid #ccc}\n"
      "table{border-collapse:collapse;font-size:12px}td,th{border:1px solid #ccc;padding:2px 6px;"
      "text-align:right}th{background:#f2f2f2}td.t{text-align:left}\n"
      // One row of figures per kind (PR, ROC, reliability, ...), each as wide as the page lets it
      // be: the difficulties of a kind side by side.
      ".figures{display:flex;flex-wrap:wrap;gap:12px;margin-bottom:12px}\n"
      "figure.stereodet-figure{margin:0;flex:1 1 420px;max-width:640px;min-width:0}"
      "figure.stereodet-figure svg{width:100%;height:auto}"
      "figcaption{font-size:12px;color:#333}\n"
      "code{font-size:12px}dl{font-size:13px}dt{font-weight:bold;margin-top:8px}\n"
      "</style>\n</head>\n<body>\n<h1>stereodet evaluation report</h1>\n<dl>\n";
  for (const ReportSource& s : sources) {
    if (s.kind == ReportKind::kCoco) {
      html += CocoHeaderHtml(s.label, s.folder, s.results);
      continue;
    }
    if (s.kind != ReportKind::kEval) {
      html += fmt::format(
          "<dt>{}</dt><dd>folder <code>{}</code>; {} ({} rows)</dd>\n", XmlEscape(s.label),
          XmlEscape(s.folder.string()),
          s.kind == ReportKind::kSweep ? "eval sweep: sweep.csv" : "eval compare: compare.csv",
          s.rows.size());
      continue;
    }
    const json& r = s.results;
    const json tool = r.value("tool", json::object());
    html += fmt::format(
        "<dt>{}</dt><dd>folder <code>{}</code>; {} {}; matcher {}; {} frames; input hash "
        "<code>{}</code><br>command line: <code>{}</code></dd>\n",
        XmlEscape(s.label), XmlEscape(s.folder.string()), XmlEscape(Str(tool, "name")),
        XmlEscape(Str(tool, "version")), XmlEscape(Str(r["options"], "matcher")),
        Fixed(Num(r["input"], "num_frames"), 0), XmlEscape(Str(r, "input_hash")),
        XmlEscape(Str(r, "command_line")));
    if (r.contains("notes")) {
      for (const json& n : r["notes"]) {
        if (n.is_string()) html += "<dd>note: " + XmlEscape(n.get<std::string>()) + "</dd>\n";
      }
    }
  }
  html += "</dl>\n<p>Figures: ";
  std::string last;
  for (const ReportFigure& figure : figures) {
    if (figure.section == last) continue;
    html += fmt::format("{}<a href=\"#{}\">{}</a>", last.empty() ? "" : " | ", Slug(figure.section),
                        XmlEscape(figure.section));
    last = figure.section;
  }
  html += "</p>\n";
  html += PairedTableHtml(sources);
  const bool eval = sources.front().kind == ReportKind::kEval;
  if (eval) html += "<h2 id=\"summary\">Summary</h2>\n<table id=\"summary-table\">\n<tr>";
  if (eval) {
    for (const char* h : {"results", "class", "metric", "difficulty", "overlaps", "min overlap",
                          "labels", "detections", "AP_R40", "AP_R11", "AOS / APL_R40", "best F1",
                          "Brier labels", "Brier detections", "Brier all", "ECE", "D-ECE"}) {
      html += fmt::format("<th>{}</th>", h);
    }
    html += "</tr>\n";
    // One cell's rows together, a row per results folder (the cells in the first folder's order,
    // then any only later folders have).
    std::vector<std::map<CellKey, const json*>> cells;
    std::vector<CellKey> order;
    std::set<CellKey> seen;
    for (const ReportSource& s : sources) {
      cells.push_back(Cells(s));
      for (const json& e : s.results["results"]) {
        if (e.value("evaluated", false) && seen.insert(KeyOf(e)).second) order.push_back(KeyOf(e));
      }
    }
    for (const CellKey& key : order) {
      for (size_t i = 0; i < sources.size(); ++i) {
        const auto it = cells[i].find(key);
        if (it == cells[i].end()) continue;
        const ReportSource& s = sources[i];
        const json& e = *it->second;
        const json& b = e["brier"];
        html += fmt::format(
            "<tr><td class=\"t\">{}</td><td class=\"t\">{}</td><td class=\"t\">{}</td>"
            "<td class=\"t\">{}</td><td class=\"t\">{}</td><td>{}</td><td>{}{}</td><td>{}</td>"
            "<td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>"
            "<td>{}</td><td>{}</td></tr>\n",
            XmlEscape(s.label), XmlEscape(Str(e, "class")), Str(e, "metric"), Str(e, "difficulty"),
            Str(e, "overlaps"), Fixed(Num(e, "min_overlap"), 2), e.value("num_valid_labels", 0),
            e.value("small_sample", false) ? "*" : "", e.value("num_detections", 0),
            ApText(e, "ap_r40"), ApText(e, "ap_r11"),
            ApText(e, e.contains("apl_r40") ? "apl_r40" : "aos_r40"),  // LET cells: LET-APL
            Fixed(Num(e["best_f1"], "f1"), 3), Fixed(Num(b, "over_labels"), 4),
            Fixed(Num(b, "over_detections"), 4), Fixed(Num(b, "over_all"), 4),
            Fixed(Num(e["calibration"], "ece"), 4), Fixed(Num(e["calibration"], "dece"), 4));
      }
    }
    html +=
        "</table>\n<p style=\"font-size:12px\">AP, AOS (2D) and LET-APL (let-bev, let-3d) in "
        "percent; * 40 or fewer valid labels "
        "(docs/metrics.md, small samples).</p>\n";
  }
  if (eval) html += Table1Html(sources);
  if (sources.front().kind == ReportKind::kCoco) html += CocoSummaryHtml(CocoSources(sources));
  html += WorstFramesHtml(views);

  // Figures, one section per class x metric (x overlap set), a row per kind of figure.
  json data = json::array();
  std::string section, kind;
  for (const ReportFigure& figure : figures) {
    const Plot& p = figure.plot;
    if (figure.section != section) {
      if (!section.empty()) html += "</div>\n";
      section = figure.section;
      kind = FigureKind(p.id);
      html += fmt::format("<h2 id=\"{}\">{}</h2>\n<div class=\"figures\" data-kind=\"{}\">\n",
                          Slug(section), XmlEscape(section), kind);
    } else if (FigureKind(p.id) != kind) {
      kind = FigureKind(p.id);
      html += fmt::format("</div>\n<div class=\"figures\" data-kind=\"{}\">\n", kind);
    }
    html += fmt::format("<figure class=\"stereodet-figure\" id=\"fig-{}\">\n", p.id);
    html += RenderSvg(p);
    html += fmt::format("<figcaption>{} <a href=\"figures/{}.svg\">SVG</a>", XmlEscape(p.caption),
                        p.id);
    if (with_png) html += fmt::format(" <a href=\"figures/{}.png\">PNG</a>", p.id);
    html += "</figcaption>\n</figure>\n";
    data.push_back(PlotToJson(p));
  }
  if (!section.empty()) html += "</div>\n";
  html += "<script type=\"application/json\" id=\"stereodet-figures\">" + ScriptJson(data) +
          "</script>\n";
  html +=
      "<script>\n"
      "(function () {\n"
      "  var data = JSON.parse(document.getElementById('stereodet-figures').textContent);\n"
      "  var drawn = document.querySelectorAll('figure.stereodet-figure svg').length;\n"
      "  console.log('stereodet-report: ' + drawn + ' figures drawn, ' + data.length + ' in "
      "data');\n"
      "  if (drawn !== data.length) console.error('stereodet-report: figures missing');\n"
      "  document.body.setAttribute('data-figures', String(drawn));\n"
      "})();\n"
      "</script>\n</body>\n</html>\n";
  return html;
}

ReportResult WriteReportFiles(const fs::path& dir, const std::vector<ReportSource>& sources,
                              bool png, double png_scale, int worst_frames) {
  const std::vector<ReportFigure> figures = ReportFigures(sources);
  ReportResult result;
  result.png = png && PngFromSvgAvailable();
  if (png && !result.png) {
    result.notes.push_back(
        "PNG files not written: this build has no librsvg (install librsvg2-dev "
        "and rebuild); the SVG files are complete");
  }
  fs::create_directories(dir / "figures");
  for (const ReportFigure& figure : figures) {
    const Plot& p = figure.plot;
    const std::string svg = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n" + RenderSvg(p);
    const fs::path svg_path = dir / "figures" / (p.id + ".svg");
    WriteFileAtomically(svg_path, svg);
    result.files.push_back(svg_path);
    if (result.png) {
      const fs::path png_path = dir / "figures" / (p.id + ".png");
      WritePngFromSvg(png_path, svg, png_scale);
      result.files.push_back(png_path);
    }
  }
  // The worst frames' views, at the image's own resolution.
  std::vector<ReportFrameViews> views;
  for (size_t i = 0; i < sources.size() && worst_frames > 0; ++i) {
    const ReportSource& s = sources[i];
    if (s.kind != ReportKind::kEval) continue;
    ReportFrameViews v;
    v.label = s.label;
    v.folder = sources.size() == 1 ? "views" : fmt::format("views/{}", i + 1);
    v.has_records = !s.records.empty();
    if (v.has_records) {
      FrameViewsOptions options;
      options.results = s.folder;
      options.worst = worst_frames;
      options.png = result.png;
      v.views = WriteWorstFrameViews(s.results, s.records, dir / v.folder, options);
      result.files.insert(result.files.end(), v.views.files.begin(), v.views.files.end());
      result.num_views += static_cast<int>(v.views.views.size());
      for (const std::string& note : v.views.notes) result.notes.push_back(s.label + ": " + note);
    }
    views.push_back(std::move(v));
  }
  result.index = dir / "index.html";
  WriteFileAtomically(result.index, ReportHtml(sources, figures, result.png, views));
  result.files.push_back(result.index);
  result.num_figures = static_cast<int>(figures.size());
  return result;
}

void ReportOptions::Check() const {
  STEREODET_CHECK(!results.empty()) << "report: no results folder given";
  STEREODET_CHECK(labels.empty() || labels.size() == results.size())
      << "report: " << labels.size() << " labels for " << results.size() << " results folders";
  STEREODET_CHECK(results.size() == 1 || !out.empty())
      << "report: with several results folders, say where the report goes (out)";
  STEREODET_CHECK(png_scale > 0 && png_scale <= 8)
      << "report: png_scale " << png_scale << " is not in (0, 8]";
  STEREODET_CHECK(worst_frames >= 0) << "report: worst_frames " << worst_frames << " is negative";
}

ReportResult WriteReport(const ReportOptions& options) {
  options.Check();
  std::vector<ReportSource> sources;
  for (size_t i = 0; i < options.results.size(); ++i) {
    std::string label = options.labels.empty() ? "" : options.labels[i];
    if (label.empty()) label = FolderLabel(options.results[i]);
    sources.push_back(ReadReportSource(options.results[i], label));
  }
  const fs::path out = options.out.empty() ? options.results.front() / "report" : options.out;
  StagedFolder staged(out, "report", {kMakerReport});
  ReportResult result = WriteReportFiles(staged.path(), sources, options.png, options.png_scale,
                                         options.worst_frames);
  staged.Commit();
  for (fs::path& f : result.files) f = out / f.lexically_relative(staged.path());
  result.index = out / "index.html";
  return result;
}

}  // namespace stereodet
