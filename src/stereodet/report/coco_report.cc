#include "stereodet/report/coco_report.h"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <string_view>

#include "stereodet/report/report_json_internal.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/strings.h"

namespace stereodet {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using report_internal::Fixed;
using report_internal::kNaN;
using report_internal::Num;
using report_internal::Numbers;

// summarize()'s 12 numbers, in results.json's names and order.
constexpr const char* kStats[] = {"AP",  "AP50", "AP75",  "APs", "APm", "APl",
                                  "AR1", "AR10", "AR100", "ARs", "ARm", "ARl"};
constexpr const char* kScoreStats[] = {"BL", "BD", "BA", "ECE"};

// j[key] where j is an object holding it, else null (or an empty array): references into the
// results, not the copies json::value() returns.
const json& Field(const json& j, const char* key) {
  static const json kNull;
  return j.is_object() && j.contains(key) ? j[key] : kNull;
}
const json& Array(const json& j, const char* key) {
  static const json kEmpty = json::array();
  const json& f = Field(j, key);
  return f.is_array() ? f : kEmpty;
}

// A float64 array in numpy's .npy format (version 1 or 2, little-endian '<f8', C order) of the
// given shape: its values.
std::vector<double> ReadNpyFloat64(const fs::path& path, const std::vector<size_t>& shape) {
  const std::string bytes = ReadFile(path, kMaxReadFileBytes, "numpy array");
  STEREODET_CHECK_IO(bytes.size() >= 10 && bytes.compare(0, 6, "\x93NUMPY") == 0)
      << path.string() << ": not a .npy file";
  const int major = static_cast<unsigned char>(bytes[6]);
  const size_t length_bytes = major == 1 ? 2 : 4;
  size_t header_length = 0;
  for (size_t i = 0; i < length_bytes; ++i) {
    header_length |= static_cast<size_t>(static_cast<unsigned char>(bytes[8 + i])) << (8 * i);
  }
  const size_t data_start = 8 + length_bytes + header_length;
  STEREODET_CHECK_IO(data_start <= bytes.size()) << path.string() << ": header cut short";
  const std::string_view header(bytes.data() + 8 + length_bytes, header_length);
  STEREODET_CHECK_IO(header.find("'descr': '<f8'") != std::string_view::npos &&
                     header.find("'fortran_order': False") != std::string_view::npos)
      << path.string() << ": expected a little-endian float64 array in C order, header "
      << std::string(header);
  std::string want = "(";
  for (size_t i = 0; i < shape.size(); ++i) {
    want += (i ? ", " : "") + std::to_string(shape[i]);
  }
  want += shape.size() == 1 ? ",)" : ")";
  STEREODET_CHECK_IO(header.find("'shape': " + want) != std::string_view::npos)
      << path.string() << ": expected shape " << want << " (results.json's), header "
      << std::string(header);
  size_t count = 1;
  for (const size_t n : shape) count *= n;
  STEREODET_CHECK_IO(bytes.size() - data_start == count * sizeof(double))
      << path.string() << ": " << bytes.size() - data_start << " bytes of data for " << count
      << " float64 values";
  std::vector<double> values(count);
  std::memcpy(values.data(), bytes.data() + data_start, count * sizeof(double));
  return values;
}

// numpy's mean of the entries > -1 (summarize()), -1 where there are none. The report's curves
// need only the value, not numpy's summation order.
double MeanOfDefined(const std::vector<double>& values) {
  double sum = 0;
  int n = 0;
  for (const double v : values) {
    if (v > -1) {
      sum += v;
      ++n;
    }
  }
  return n == 0 ? -1.0 : sum / n;
}

// Each source's colour, as in the KITTI-mode figures.
std::string Colour(size_t source) { return PaletteColour(source); }

// A figure's frame: axes from 0 to 1 where `unit_x` / `unit_y` (precision, recall, AP, scores).
Plot MakePlot(const std::string& id, const std::string& title, const std::string& x_label,
              const std::string& y_label, bool unit_x, bool unit_y) {
  Plot p;
  p.id = id;
  p.title = title;
  p.x_label = x_label;
  p.y_label = y_label;
  if (unit_x) {
    p.x_min = 0;
    p.x_max = 1;
  }
  if (unit_y) {
    p.y_min = 0;
    p.y_max = 1;
  }
  return p;
}

// The stat's value and, where the folder has a bootstrap, its interval.
struct StatValue {
  double value = kNaN, lower = kNaN, upper = kNaN;
};
StatValue Stat(const json& r, const char* group, const char* name) {
  StatValue v;
  v.value = Num(Field(r, group), name);
  if (v.value < 0) v.value = kNaN;  // -1: no ground truth
  if (r.contains("bootstrap") && r["bootstrap"].is_object()) {
    const json& b = Field(r["bootstrap"], group);
    if (b.is_object() && b.contains(name)) {
      v.lower = Num(b[name], "lower");
      v.upper = Num(b[name], "upper");
    }
  }
  return v;
}

Plot PrFigure(const std::vector<CocoReportSource>& sources, const char* curve, const char* title,
              const std::string& id) {
  Plot p = MakePlot(id, title, "recall", "precision", true, true);
  std::vector<std::string> caption;
  for (size_t i = 0; i < sources.size(); ++i) {
    const json& r = *sources[i].results;
    const json& pr = Field(r, "report_pr");
    PlotSeries s;
    s.x = Numbers(pr, "recall");
    s.y = Numbers(pr, curve);
    if (s.x.size() != s.y.size()) continue;
    for (double& y : s.y) {
      if (y < 0) y = kNaN;  // no category with ground truth
    }
    const double ap = Num(Field(r, "stats"), curve);
    s.name = fmt::format("{}{} {}", sources.size() > 1 ? sources[i].label + " " : "", curve,
                         Fixed(ap < 0 ? kNaN : ap, 3));
    s.colour = Colour(i);
    caption.push_back(s.name);
    p.series.push_back(std::move(s));
  }
  const std::vector<double> max_dets =
      Numbers(Field(*sources.front().results, "options"), "max_dets");
  p.caption = fmt::format(
      "Precision at COCO's 101 recall thresholds, mean over the categories with ground truth "
      "(area all, maxDets {}); {}.",
      Fixed(max_dets.empty() ? kNaN : max_dets.back(), 0), fmt::join(caption, "; "));
  return p;
}

Plot StatsFigure(const std::vector<CocoReportSource>& sources) {
  Plot p = MakePlot("coco_stats", "The 12 numbers of COCOeval.summarize()", "summary number",
                    "AP or AR", false, true);
  for (const char* name : kStats) p.categories.push_back(name);
  bool intervals = false;
  for (size_t i = 0; i < sources.size(); ++i) {
    PlotSeries s;
    s.style = SeriesStyle::kBars;
    s.name = sources[i].label;
    s.colour = Colour(i);
    for (size_t k = 0; k < std::size(kStats); ++k) {
      const StatValue v = Stat(*sources[i].results, "stats", kStats[k]);
      s.x.push_back(static_cast<double>(k));
      s.y.push_back(v.value);
      s.y_low.push_back(v.lower);
      s.y_high.push_back(v.upper);
      intervals = intervals || !std::isnan(v.lower);
    }
    p.series.push_back(std::move(s));
  }
  p.width_px = std::max(p.width_px, 40.0 * static_cast<double>(std::size(kStats)) *
                                        std::max<size_t>(1, sources.size() / 2));
  p.caption = intervals ? "Bars: the estimates; whiskers: the bootstrap intervals over images "
                          "(results.json's \"bootstrap\")."
                        : "No bootstrap in these folders (eval --bootstrap N adds intervals).";
  return p;
}

Plot CategoriesFigure(const std::vector<CocoReportSource>& sources) {
  Plot p = MakePlot("coco_categories", "AP per category", "category", "AP@[.50:.95]", false, true);
  const json& first = Array(*sources.front().results, "categories");
  std::vector<int64_t> ids;
  // Names under the bars of a few categories; ids under many (COCO's 80 names would overlap),
  // the names being in the per-category table.
  const bool by_name = first.size() <= 20;
  for (const json& c : first) {
    ids.push_back(c.value("id", int64_t{0}));
    const std::string name = c.value("name", std::string());
    p.categories.push_back(by_name && !name.empty() ? name : std::to_string(ids.back()));
  }
  if (!by_name) p.x_label = "category id (names: the per-category table)";
  for (size_t i = 0; i < sources.size(); ++i) {
    std::map<int64_t, double> ap;
    for (const json& c : Array(*sources[i].results, "categories")) {
      const double v = Num(Field(c, "stats"), "AP");
      ap[c.value("id", int64_t{0})] = v < 0 ? kNaN : v;
    }
    PlotSeries s;
    s.style = SeriesStyle::kBars;
    s.name = sources[i].label;
    s.colour = Colour(i);
    for (size_t k = 0; k < ids.size(); ++k) {
      const auto it = ap.find(ids[k]);
      s.x.push_back(static_cast<double>(k));
      s.y.push_back(it == ap.end() ? kNaN : it->second);
    }
    p.series.push_back(std::move(s));
  }
  p.width_px = std::max(p.width_px, (by_name ? 60.0 : 22.0) * static_cast<double>(ids.size()) *
                                        static_cast<double>(std::max<size_t>(1, sources.size())));
  p.caption = fmt::format(
      "AP@[.50:.95] of each of the {} categories (COCOeval with params.catIds = [id]); a category "
      "without ground truth has no bar.",
      ids.size());
  return p;
}

Plot ReliabilityFigure(const std::vector<CocoReportSource>& sources) {
  Plot p = MakePlot("coco_reliability", "Reliability at IoU 0.5 (all categories, area all)",
                    "mean score of the bin", "fraction of TPs", true, true);
  PlotSeries diagonal;
  diagonal.x = {0, 1};
  diagonal.y = {0, 1};
  diagonal.colour = "#999999";
  diagonal.dashed = true;
  p.series.push_back(diagonal);
  std::vector<std::string> caption;
  for (size_t i = 0; i < sources.size(); ++i) {
    const json& r = *sources[i].results;
    if (!r.contains("report_reliability")) continue;
    const json& rel = r["report_reliability"];
    PlotSeries s;
    s.style = SeriesStyle::kLineMarkers;
    s.colour = Colour(i);
    const std::vector<double> score = Numbers(rel, "mean_score");
    const std::vector<double> tp = Numbers(rel, "tp_fraction");
    for (size_t b = 0; b < score.size() && b < tp.size(); ++b) {
      if (std::isnan(score[b]) || std::isnan(tp[b])) continue;
      s.x.push_back(score[b]);
      s.y.push_back(tp[b]);
    }
    const double ece = Num(Field(r, "score_stats"), "ECE50");
    s.name = fmt::format("{}ECE50 {}", sources.size() > 1 ? sources[i].label + " " : "",
                         Fixed(ece < 0 ? kNaN : ece, 3));
    caption.push_back(s.name);
    p.series.push_back(std::move(s));
  }
  p.caption = fmt::format(
      "Per score bin, the fraction of the detections at the operating point that are TPs "
      "against their mean score, pooled over the categories (reliability.csv; the dashed line is "
      "perfect calibration); {}.",
      fmt::join(caption, "; "));
  return p;
}

std::string IntervalCell(const StatValue& v) {
  if (std::isnan(v.value)) return "<td>-</td>";
  if (std::isnan(v.lower)) return fmt::format("<td>{:.3f}</td>", v.value);
  return fmt::format("<td>{:.3f} <small>[{:.3f}, {:.3f}]</small></td>", v.value, v.lower, v.upper);
}

}  // namespace

void LoadCocoReportData(const fs::path& folder, json* results) {
  json& r = *results;
  const json& options = Field(r, "options");
  const std::vector<double> ious = Numbers(options, "iou_thresholds");
  const std::vector<double> recalls = Numbers(options, "recall_thresholds");
  const json& arrays = Field(r, "arrays");
  STEREODET_CHECK_IO(arrays.is_object() && arrays.contains("precision") &&
                     Array(arrays["precision"], "shape").size() == 5)
      << (folder / "results.json").string()
      << " has no \"arrays\".\"precision\" of 5 dimensions: not COCO-mode results.json";
  std::vector<size_t> shape;
  for (const json& n : arrays["precision"]["shape"]) shape.push_back(n.get<size_t>());
  const size_t T = shape[0], R = shape[1], K = shape[2], A = shape[3], M = shape[4];
  STEREODET_CHECK_IO(T == ious.size() && R == recalls.size())
      << (folder / "results.json").string()
      << ": the precision array's shape does not match its options' thresholds";
  const std::vector<double> precision = ReadNpyFloat64(
      folder / arrays["precision"].value("file", std::string("precision.npy")), shape);
  size_t area_all = 0;
  const json& areas = Array(options, "area_ranges");
  for (size_t a = 0; a < areas.size(); ++a) {
    if (areas[a].value("label", std::string()) == "all") area_all = a;
  }
  auto at = [&](size_t t, size_t rr, size_t k) {
    return precision[(((t * R + rr) * K + k) * A + area_all) * M + (M - 1)];
  };
  auto iou_index = [&](double iou) {
    for (size_t t = 0; t < T; ++t) {
      if (std::abs(ious[t] - iou) < 1e-9) return static_cast<int>(t);
    }
    return -1;
  };
  json pr;
  pr["recall"] = recalls;
  std::vector<double> values;
  for (const auto& [name, iou] : {std::pair<const char*, double>{"AP50", 0.5}, {"AP75", 0.75}}) {
    const int t = iou_index(iou);
    std::vector<double> curve(R, -1.0);
    for (size_t rr = 0; rr < R && t >= 0; ++rr) {
      values.clear();
      for (size_t k = 0; k < K; ++k) values.push_back(at(t, rr, k));
      curve[rr] = MeanOfDefined(values);
    }
    pr[name] = curve;
  }
  std::vector<double> mean(R, -1.0);
  for (size_t rr = 0; rr < R; ++rr) {
    values.clear();
    for (size_t t = 0; t < T; ++t) {
      for (size_t k = 0; k < K; ++k) values.push_back(at(t, rr, k));
    }
    mean[rr] = MeanOfDefined(values);
  }
  pr["AP"] = mean;
  r["report_pr"] = pr;

  const fs::path reliability = folder / "reliability.csv";
  if (!fs::is_regular_file(reliability)) return;
  const std::string text = ReadFile(reliability, kMaxReadFileBytes, "reliability.csv");
  const std::vector<std::string_view> lines = Split(text, '\n');
  STEREODET_CHECK_IO(!lines.empty() &&
                     lines[0] == "iou,category_id,area,lower,upper,count,mean_score,tp_fraction")
      << reliability.string() << ": expected the header of eval --coco-brier's reliability.csv";
  // Pooled per bin (keyed by its bounds, in file order): counts summed, means weighted by them.
  std::vector<std::pair<double, double>> bins;
  std::map<std::pair<double, double>, std::array<double, 3>> pooled;  // count, score sum, tp sum
  for (size_t i = 1; i < lines.size(); ++i) {
    if (lines[i].empty()) continue;
    const std::vector<std::string_view> f = Split(lines[i], ',');
    STEREODET_CHECK_IO(f.size() == 8)
        << reliability.string() << " line " << i + 1 << ": " << f.size() << " fields, expected 8";
    auto number = [&](size_t field) {
      const std::optional<double> v = ParseDouble(f[field]);
      STEREODET_CHECK_IO(v.has_value()) << reliability.string() << " line " << i + 1 << ", field "
                                        << field + 1 << ": not a number: " << std::string(f[field]);
      return *v;
    };
    if (std::abs(number(0) - 0.5) > 1e-9 || f[2] != "all") continue;
    const std::pair<double, double> bin{number(3), number(4)};
    const double count = number(5);
    auto [it, inserted] = pooled.insert({bin, {0, 0, 0}});
    if (inserted) bins.push_back(bin);
    if (count > 0) {
      it->second[0] += count;
      it->second[1] += count * number(6);
      it->second[2] += count * number(7);
    }
  }
  json rel;
  for (const auto& bin : bins) {
    const std::array<double, 3>& p = pooled[bin];
    rel["lower"].push_back(bin.first);
    rel["upper"].push_back(bin.second);
    rel["count"].push_back(p[0]);
    rel["mean_score"].push_back(p[0] > 0 ? json(p[1] / p[0]) : json(nullptr));
    rel["tp_fraction"].push_back(p[0] > 0 ? json(p[2] / p[0]) : json(nullptr));
  }
  r["report_reliability"] = rel;
}

std::vector<CocoReportFigure> CocoReportFigures(const std::vector<CocoReportSource>& sources) {
  STEREODET_CHECK(!sources.empty()) << "a report needs at least one results folder";
  std::vector<CocoReportFigure> figures;
  const char* const pr = "Precision-recall";
  figures.push_back({pr, PrFigure(sources, "AP50", "Precision-recall at IoU 0.50", "coco_pr_50")});
  figures.push_back({pr, PrFigure(sources, "AP75", "Precision-recall at IoU 0.75", "coco_pr_75")});
  figures.push_back(
      {pr, PrFigure(sources, "AP", "Precision-recall, mean over IoU 0.50:0.95", "coco_pr_mean")});
  figures.push_back({"Summary", StatsFigure(sources)});
  figures.push_back({"Categories", CategoriesFigure(sources)});
  for (const CocoReportSource& s : sources) {
    if (s.results->contains("report_reliability")) {
      figures.push_back({"Calibration", ReliabilityFigure(sources)});
      break;
    }
  }
  return figures;
}

std::string CocoSummaryHtml(const std::vector<CocoReportSource>& sources) {
  bool brier = false, bootstrap = false;
  for (const CocoReportSource& s : sources) {
    brier = brier || s.results->contains("score_stats");
    bootstrap = bootstrap || s.results->contains("bootstrap");
  }
  std::string html =
      "<h2 id=\"summary\">Summary</h2>\n<table id=\"summary-table\">\n<tr><th>results</th>";
  for (const char* name : kStats) html += fmt::format("<th>{}</th>", name);
  if (brier) {
    for (const char* name : kScoreStats) html += fmt::format("<th>{}</th>", name);
  }
  html += "</tr>\n";
  for (const CocoReportSource& s : sources) {
    html += fmt::format("<tr><td class=\"t\">{}</td>", XmlEscape(s.label));
    for (const char* name : kStats) html += IntervalCell(Stat(*s.results, "stats", name));
    if (brier) {
      for (const char* name : kScoreStats) {
        html += IntervalCell(Stat(*s.results, "score_stats", name));
      }
    }
    html += "</tr>\n";
  }
  html += fmt::format(
      "</table>\n<p style=\"font-size:12px\">pycocotools' summarize() numbers (area all, maxDets "
      "100 unless named){}{}.</p>\n",
      brier ? "; BL, BD, BA: Brier over labels, detections and all, ECE: calibration error, at "
              "[.50:.95] (docs/metrics.md, COCO mode)"
            : "",
      bootstrap ? "; [lower, upper]: the bootstrap interval over images" : "");
  // Per category: AP, AP50, AP75 of each source, the first source's categories.
  html +=
      "<h2 id=\"categories-table\">Per category</h2>\n<table>\n<tr><th>category</th><th>id</th>";
  for (const CocoReportSource& s : sources) {
    for (const char* name : {"AP", "AP50", "AP75"}) {
      html +=
          fmt::format("<th>{}{}</th>", sources.size() > 1 ? XmlEscape(s.label) + " " : "", name);
    }
  }
  html += "</tr>\n";
  std::vector<std::map<int64_t, const json*>> by_id(sources.size());
  for (size_t i = 0; i < sources.size(); ++i) {
    for (const json& c : Array(*sources[i].results, "categories")) {
      by_id[i][c.value("id", int64_t{0})] = &c;
    }
  }
  for (const json& c : Array(*sources.front().results, "categories")) {
    const int64_t id = c.value("id", int64_t{0});
    html += fmt::format("<tr><td class=\"t\">{}</td><td>{}</td>",
                        XmlEscape(c.value("name", std::string())), id);
    for (size_t i = 0; i < sources.size(); ++i) {
      const auto it = by_id[i].find(id);
      for (const char* name : {"AP", "AP50", "AP75"}) {
        const double v = it == by_id[i].end() ? kNaN : Num(Field(*it->second, "stats"), name);
        html += fmt::format("<td>{}</td>", Fixed(v < 0 ? kNaN : v, 3));
      }
    }
    html += "</tr>\n";
  }
  html += "</table>\n";
  return html;
}

std::string CocoHeaderHtml(const std::string& label, const fs::path& folder, const json& r) {
  const json& tool = Field(r, "tool");
  const json& input = Field(r, "input");
  const json& options = Field(r, "options");
  auto text = [](const json& j, const char* key) {
    return j.is_object() && j.contains(key) && j[key].is_string() ? j[key].get<std::string>()
                                                                  : std::string("-");
  };
  return fmt::format(
      "<dt>{}</dt><dd>folder <code>{}</code>; {} {} (COCO mode); matcher {}; {} images, {} "
      "categories, {} ground truths, {} detections; input hash <code>{}</code><br>command line: "
      "<code>{}</code></dd>\n",
      XmlEscape(label), XmlEscape(folder.string()), XmlEscape(text(tool, "name")),
      XmlEscape(text(tool, "version")), XmlEscape(text(options, "matcher")),
      Fixed(Num(input, "num_images"), 0), Fixed(Num(input, "num_categories"), 0),
      Fixed(Num(input, "num_gt"), 0), Fixed(Num(input, "num_detections"), 0),
      XmlEscape(text(r, "input_hash")), XmlEscape(text(r, "command_line")));
}

}  // namespace stereodet
