#include "stereodet/report/frame_view.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "stereodet/eval/eval_input.h"
#include "stereodet/kitti/calib_io.h"
#include "stereodet/report/raster.h"
#include "stereodet/report/svg_plot.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/strings.h"

namespace stereodet {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string Base64(const std::string& bytes) {
  static constexpr char kTable[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v =
        (uint8_t(bytes[i]) << 16) | (uint8_t(bytes[i + 1]) << 8) | uint8_t(bytes[i + 2]);
    for (int k = 18; k >= 0; k -= 6) out += kTable[(v >> k) & 63];
  }
  if (i < bytes.size()) {
    uint32_t v = uint8_t(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= uint8_t(bytes[i + 1]) << 8;
    out += kTable[(v >> 18) & 63];
    out += kTable[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kTable[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// Width and height of a PNG file from its IHDR chunk, or nullopt when `bytes` is not a PNG.
std::optional<std::pair<int, int>> PngSize(const std::string& bytes) {
  static constexpr char kSignature[] = "\x89PNG\r\n\x1a\n";
  if (bytes.size() < 24 || bytes.compare(0, 8, kSignature, 8) != 0 ||
      bytes.compare(12, 4, "IHDR") != 0) {
    return std::nullopt;
  }
  auto be32 = [&](size_t at) {
    return (uint32_t(uint8_t(bytes[at])) << 24) | (uint32_t(uint8_t(bytes[at + 1])) << 16) |
           (uint32_t(uint8_t(bytes[at + 2])) << 8) | uint32_t(uint8_t(bytes[at + 3]));
  };
  const uint32_t w = be32(16), h = be32(20);
  if (w == 0 || h == 0 || w > 100000 || h > 100000) return std::nullopt;
  return std::make_pair(static_cast<int>(w), static_cast<int>(h));
}

const char* OutcomeClass(Outcome o) {
  switch (o) {
    case Outcome::kTp:
      return "tp";
    case Outcome::kFp:
      return "fp";
    case Outcome::kFn:
      return "fn";
    default:
      return "ignored";
  }
}

const char* OutcomeColour(Outcome o) {
  switch (o) {
    case Outcome::kTp:
      return kViewTpColour;
    case Outcome::kFp:
      return kViewFpColour;
    case Outcome::kFn:
      return kViewFnColour;
    default:
      return kViewIgnoredColour;
  }
}

// What one record draws: a detection and/or a label, each with its text.
struct Drawn {
  const Object* object;
  bool detection;
  Outcome outcome;
  int index;
  std::string text;
};

std::vector<Drawn> DrawnObjects(const FrameViewData& data, const FrameViewOptions& options) {
  // The records whose detection is drawn: at least min_score, then the top_k highest scores.
  std::vector<size_t> candidates;
  for (size_t i = 0; i < data.records.size(); ++i) {
    const ViewRecord& r = data.records[i];
    if (r.detection >= 0 && !(r.score < options.min_score)) candidates.push_back(i);
  }
  if (options.top_k > 0 && candidates.size() > static_cast<size_t>(options.top_k)) {
    std::stable_sort(candidates.begin(), candidates.end(), [&](size_t a, size_t b) {
      return data.records[a].score > data.records[b].score;
    });
    candidates.resize(static_cast<size_t>(options.top_k));
  }
  const std::set<size_t> with_detection(candidates.begin(), candidates.end());
  std::vector<Drawn> drawn;
  for (size_t i = 0; i < data.records.size(); ++i) {
    const ViewRecord& r = data.records[i];
    STEREODET_CHECK(r.detection < static_cast<int>(data.detections.size()) &&
                    r.label < static_cast<int>(data.labels.size()) &&
                    (r.detection >= 0 || r.label >= 0))
        << "frame " << data.frame_id << ": record of detection " << r.detection << " and label "
        << r.label << " outside its " << data.detections.size() << " detections and "
        << data.labels.size() << " labels";
    if (r.label >= 0) {
      std::string text;
      if (r.outcome == Outcome::kFn) text = fmt::format("FN IoU {:.2f}", r.iou);
      drawn.push_back({&data.labels[r.label], false, r.outcome, r.label, text});
    }
    if (r.detection >= 0 && with_detection.count(i) != 0) {
      std::string text = fmt::format("{:.2f} IoU {:.2f}", r.score, r.iou);
      if (r.outcome == Outcome::kIgnored) text.clear();
      if (r.outcome == Outcome::kDontCare) text = "DontCare";
      drawn.push_back({&data.detections[r.detection], true, r.outcome, r.detection, text});
    }
  }
  return drawn;
}

std::string Num(double v) { return fmt::format("{:.2f}", v); }

// Baselines for the texts of one image view such that no two overlap: a text that would overlap one
// placed before moves a line at a time in its direction (-1 up, +1 down), and the other way once
// it would leave the canvas; after 12 tries it stays where it first wanted to be. A text's extent
// is estimated from its length (13 px DejaVu Sans: about 7.5 px a character, 13 px tall).
class TextPlacer {
 public:
  explicit TextPlacer(double canvas_height) : canvas_height_(canvas_height) {}

  double Place(double x, double baseline, size_t chars, int direction) {
    const double width = 7.5 * static_cast<double>(chars);
    double y = baseline;
    for (int tries = 0; tries < 12; ++tries) {
      if (Free(x, y, width)) {
        placed_.push_back({x, y, width});
        return y;
      }
      y += direction * kLine;
      if (y < kLine || y > canvas_height_ - 3) {
        direction = -direction;
        y = baseline + direction * kLine;
      }
    }
    placed_.push_back({x, baseline, width});
    return baseline;
  }

 private:
  static constexpr double kLine = 15;  // px between baselines
  struct Placed {
    double x, baseline, width;
  };
  bool Free(double x, double baseline, double width) const {
    for (const Placed& p : placed_) {
      if (x < p.x + p.width && p.x < x + width && std::abs(baseline - p.baseline) < kLine - 1) {
        return false;
      }
    }
    return true;
  }
  double canvas_height_;
  std::vector<Placed> placed_;
};

std::string Text(double x, double y, const std::string& colour, const std::string& text,
                 const char* anchor = "start") {
  // A white halo under the text keeps it legible on any image.
  return fmt::format(
      "<text x=\"{}\" y=\"{}\" fill=\"{}\" stroke=\"#fff\" stroke-width=\"3\" "
      "paint-order=\"stroke\" text-anchor=\"{}\">{}</text>\n",
      Num(x), Num(y), colour, anchor, XmlEscape(text));
}

std::string Legend(const FrameView& v, const FrameViewData& data, double y) {
  std::string s;
  double x = 8;
  auto item = [&](const char* colour, const std::string& text) {
    s += fmt::format(
        "<rect x=\"{}\" y=\"{}\" width=\"14\" height=\"10\" fill=\"none\" stroke=\"{}\" "
        "stroke-width=\"3\"/>\n",
        Num(x), Num(y - 10), colour);
    s += fmt::format("<text x=\"{}\" y=\"{}\" fill=\"#111\">{}</text>\n", Num(x + 20), Num(y),
                     XmlEscape(text));
    x += 30 + 7.5 * text.size();
  };
  item(kViewTpColour, fmt::format("TP {}", v.num_tp));
  item(kViewFpColour, fmt::format("FP {}", v.num_fp));
  item(kViewFnColour, fmt::format("FN {}", v.num_fn));
  item(kViewIgnoredColour, fmt::format("ignored {}", v.num_ignored));
  s += fmt::format(
      "<text x=\"{}\" y=\"{}\" fill=\"#111\">frame {}, {} {} {}; labels dashed, detections "
      "solid</text>\n",
      Num(x), Num(y), XmlEscape(data.frame_id), XmlEscape(data.cell.class_name),
      OverlapKindName(data.cell.metric), DifficultyName(data.cell.difficulty));
  return s;
}

}  // namespace

std::string ViewCellName(const ViewCell& cell) {
  std::string name = fmt::format("{}_{}_{}", cell.class_name, OverlapKindName(cell.metric),
                                 DifficultyName(cell.difficulty));
  std::transform(name.begin(), name.end(), name.begin(),
                 [](unsigned char c) { return std::isalnum(c) ? std::tolower(c) : '_'; });
  return name;
}

bool InCell(const ViewRecord& r, const ViewCell& cell) {
  return r.class_name == cell.class_name && r.metric == cell.metric &&
         r.difficulty == cell.difficulty;
}

std::vector<ViewRecord> ReadMatchRecordsCsv(const fs::path& path) {
  const std::string text = ReadFile(path);
  std::vector<ViewRecord> records;
  std::istringstream in(text);
  std::string line;
  int line_number = 0;
  std::map<std::string, size_t> column;
  const std::string file = path.string();
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::vector<std::string_view> cells = Split(line, ',');
    if (line_number == 1) {
      for (size_t i = 0; i < cells.size(); ++i) column[std::string(cells[i])] = i;
      for (const char* name : {"frame", "class", "metric", "difficulty", "min_overlap", "outcome",
                               "detection", "label", "score", "iou"}) {
        if (!column.count(name)) {
          throw ParseError(file, 1, name, "no such column: not a records file of eval --records");
        }
      }
      continue;
    }
    if (line.empty()) continue;
    auto cell = [&](const char* name) -> std::string {
      const size_t i = column.at(name);
      if (i >= cells.size()) throw ParseError(file, line_number, name, "missing");
      return std::string(cells[i]);
    };
    auto number = [&](const char* name, bool allow_empty) {
      const std::string v = cell(name);
      if (v.empty() && allow_empty) return kNaN;
      try {
        size_t used = 0;
        const double d = std::stod(v, &used);
        if (used != v.size()) throw std::invalid_argument(v);
        return d;
      } catch (const std::exception&) {
        if (v == "nan" || v == "-nan") return kNaN;
        throw ParseError(file, line_number, name, "'" + v + "' is not a number");
      }
    };
    ViewRecord r;
    r.frame_id = cell("frame");
    r.class_name = cell("class");
    const std::optional<OverlapKind> metric = ParseOverlapKind(cell("metric"));
    if (!metric) throw ParseError(file, line_number, "metric", "unknown '" + cell("metric") + "'");
    r.metric = *metric;
    const std::optional<Difficulty> difficulty = ParseDifficulty(cell("difficulty"));
    if (!difficulty) {
      throw ParseError(file, line_number, "difficulty", "unknown '" + cell("difficulty") + "'");
    }
    r.difficulty = *difficulty;
    const std::optional<Outcome> outcome = ParseOutcome(cell("outcome"));
    if (!outcome)
      throw ParseError(file, line_number, "outcome", "unknown '" + cell("outcome") + "'");
    r.outcome = *outcome;
    r.min_overlap = number("min_overlap", false);
    r.detection = static_cast<int>(number("detection", false));
    r.label = static_cast<int>(number("label", false));
    r.score = number("score", true);
    r.iou = number("iou", false);
    records.push_back(std::move(r));
  }
  STEREODET_CHECK_IO(line_number >= 1) << file << ": empty, not a records file of eval --records";
  return records;
}

void FrameViewOptions::Check() const {
  STEREODET_CHECK(bev_side_m > 0 && bev_forward_m > 0 && bev_px_per_m > 0 && bev_cell_m > 0)
      << "view: the bird's-eye view's sizes must be positive (side " << bev_side_m << " m, forward "
      << bev_forward_m << " m, " << bev_px_per_m << " px/m, cell " << bev_cell_m << " m)";
  STEREODET_CHECK(bev_side_m * bev_px_per_m <= 8000 && bev_forward_m * bev_px_per_m <= 8000)
      << "view: the bird's-eye view would be larger than 16000 x 8000 px";
  STEREODET_CHECK(canvas_width_px > 0 && canvas_height_px > 0)
      << "view: canvas size " << canvas_width_px << " x " << canvas_height_px << " px";
  STEREODET_CHECK_GE(top_k, 0) << " (--top-k)";
  STEREODET_CHECK(!std::isnan(min_score)) << "view: --min-score is NaN";
}

FrameView DrawFrameView(const FrameViewData& data, const FrameViewOptions& options) {
  options.Check();
  FrameView view;
  const std::vector<Drawn> drawn = DrawnObjects(data, options);
  for (const ViewRecord& r : data.records) {
    switch (r.outcome) {
      case Outcome::kTp:
        ++view.num_tp;
        break;
      case Outcome::kFp:
        ++view.num_fp;
        break;
      case Outcome::kFn:
        ++view.num_fn;
        break;
      default:
        ++view.num_ignored;
    }
  }

  // The image view.
  int width = options.canvas_width_px, height = options.canvas_height_px;
  std::string image_element;
  if (!data.image.empty() && fs::exists(data.image)) {
    const std::string bytes = ReadFile(data.image);
    if (const auto size = PngSize(bytes)) {
      std::tie(width, height) = *size;
      image_element = fmt::format(
          "<image x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" "
          "xlink:href=\"data:image/png;base64,{}\"/>\n",
          width, height, Base64(bytes));
      view.has_image = true;
    }
  }
  const int band = 26;  // the legend line below the image
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" "
      "class=\"stereodet-view\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\" "
      "font-family=\"DejaVu Sans, sans-serif\" font-size=\"13\">\n"
      "<rect width=\"{0}\" height=\"{1}\" fill=\"#fff\"/>\n",
      width, height + band);
  if (image_element.empty()) {
    svg += fmt::format("<rect width=\"{}\" height=\"{}\" fill=\"#d9d9d9\"/>\n", width, height);
  } else {
    svg += image_element;
  }
  // Labels first, so that detections are drawn over them; ignored ones first of all.
  std::vector<const Drawn*> order;
  for (const Drawn& d : drawn) order.push_back(&d);
  std::stable_sort(order.begin(), order.end(), [](const Drawn* a, const Drawn* b) {
    auto rank = [](const Drawn* d) {
      return (d->outcome == Outcome::kTp || d->outcome == Outcome::kFp || d->outcome == Outcome::kFn
                  ? 2
                  : 0) +
             (d->detection ? 1 : 0);
    };
    return rank(a) < rank(b);
  });
  std::string texts;
  TextPlacer placer(height);
  for (const Drawn* d : order) {
    const Box2D& b = d->object->box;
    const char* colour = OutcomeColour(d->outcome);
    svg += fmt::format(
        "<rect class=\"box {} {}\" data-index=\"{}\" x=\"{}\" y=\"{}\" width=\"{}\" "
        "height=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"3\"{}/>\n",
        OutcomeClass(d->outcome), d->detection ? "det" : "label", d->index, Num(b.left), Num(b.top),
        Num(b.Width()), Num(b.Height()), colour, d->detection ? "" : " stroke-dasharray=\"8 5\"");
    ++view.num_image_boxes;
    if (!d->text.empty()) {
      // Detections' text above the box, labels' below it, moved on where another text is.
      const double baseline =
          d->detection ? std::max(12.0, b.top - 4) : std::min<double>(height - 3, b.bottom + 14);
      texts += Text(b.left, placer.Place(b.left, baseline, d->text.size(), d->detection ? -1 : 1),
                    colour, d->text);
    }
  }
  svg += texts;
  svg += Legend(view, data, height + band - 8);
  svg += "</svg>\n";
  view.image_svg = std::move(svg);

  // The bird's-eye view: x right, z up the page.
  const double ppm = options.bev_px_per_m;
  const double bw = 2 * options.bev_side_m * ppm, bh = options.bev_forward_m * ppm;
  auto px = [&](double x) { return (x + options.bev_side_m) * ppm; };
  auto py = [&](double z) { return (options.bev_forward_m - z) * ppm; };
  std::string bev = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"stereodet-view stereodet-bev\" "
      "width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\" font-family=\"DejaVu Sans, "
      "sans-serif\" font-size=\"12\">\n<rect width=\"{0}\" height=\"{1}\" fill=\"#fff\"/>\n",
      Num(bw), Num(bh + band));
  for (int z = 10; z < options.bev_forward_m; z += 10) {
    bev += fmt::format(
        "<line x1=\"0\" y1=\"{0}\" x2=\"{1}\" y2=\"{0}\" stroke=\"#ddd\"/>\n"
        "<text x=\"4\" y=\"{2}\" fill=\"#888\">{3} m</text>\n",
        Num(py(z)), Num(bw), Num(py(z) - 3), z);
  }
  bev += fmt::format("<line x1=\"{0}\" y1=\"0\" x2=\"{0}\" y2=\"{1}\" stroke=\"#ddd\"/>\n",
                     Num(px(0)), Num(bh));
  if (data.calib && !data.points.empty()) {
    // One square per occupied cell: a 100k-point scan becomes a few thousand squares.
    const Eigen::Affine3d rect_from_velo = data.calib->RectFromVelo();
    const double cell = options.bev_cell_m;
    const int nx = static_cast<int>(std::ceil(2 * options.bev_side_m / cell));
    const int nz = static_cast<int>(std::ceil(options.bev_forward_m / cell));
    std::set<int64_t> occupied;
    for (const VeloPoint& p : data.points) {
      const Eigen::Vector3d q = rect_from_velo * Eigen::Vector3d(p.x, p.y, p.z);
      const double ix = std::floor((q.x() + options.bev_side_m) / cell);
      const double iz = std::floor(q.z() / cell);
      if (ix < 0 || iz < 0 || ix >= nx || iz >= nz) continue;
      ++view.num_points;
      occupied.insert(static_cast<int64_t>(iz) * nx + static_cast<int64_t>(ix));
    }
    std::string path;
    const double side = cell * ppm;
    for (const int64_t k : occupied) {
      const double x = (k % nx) * cell - options.bev_side_m, z = (k / nx + 1) * cell;
      path +=
          fmt::format("M{} {}h{}v{}h-{}z", Num(px(x)), Num(py(z)), Num(side), Num(side), Num(side));
    }
    if (!path.empty()) bev += "<path class=\"points\" fill=\"#555\" d=\"" + path + "\"/>\n";
  }
  for (const Drawn* d : order) {
    if (!d->object->Has3D()) continue;
    const std::array<BevPoint, 4> c = BevCorners(d->object->box3d);
    std::string points;
    for (const BevPoint& p : c) points += fmt::format("{},{} ", Num(px(p.x())), Num(py(p.y())));
    points.pop_back();
    bev += fmt::format(
        "<polygon class=\"box {} {}\" data-index=\"{}\" points=\"{}\" fill=\"none\" stroke=\"{}\" "
        "stroke-width=\"2\"{}/>\n",
        OutcomeClass(d->outcome), d->detection ? "det" : "label", d->index, points,
        OutcomeColour(d->outcome), d->detection ? "" : " stroke-dasharray=\"6 4\"");
    ++view.num_bev_boxes;
  }
  // The camera.
  bev += fmt::format("<path d=\"M{0} {1}l-6 10h12z\" fill=\"#111\"/>\n", Num(px(0)), Num(bh - 10));
  bev += fmt::format(
      "<text x=\"8\" y=\"{}\" fill=\"#111\">frame {}: {} points, {} boxes; x {} .. {} m, z 0 .. {} "
      "m</text>\n</svg>\n",
      Num(bh + band - 8), XmlEscape(data.frame_id), view.num_points, view.num_bev_boxes,
      Num(-options.bev_side_m), Num(options.bev_side_m), Num(options.bev_forward_m));
  view.bev_svg = std::move(bev);
  return view;
}

std::vector<FrameCounts> CountByFrame(const std::vector<ViewRecord>& records,
                                      const ViewCell& cell) {
  std::map<std::string, FrameCounts> by_frame;
  for (const ViewRecord& r : records) {
    if (!InCell(r, cell)) continue;
    FrameCounts& c = by_frame[r.frame_id];
    c.frame_id = r.frame_id;
    c.tp += r.outcome == Outcome::kTp;
    c.fp += r.outcome == Outcome::kFp;
    c.fn += r.outcome == Outcome::kFn;
  }
  std::vector<FrameCounts> out;
  for (auto& [id, c] : by_frame) out.push_back(c);
  return out;
}

std::vector<FrameCounts> WorstFrames(const std::vector<ViewRecord>& records, const ViewCell& cell,
                                     Outcome by, int count) {
  STEREODET_CHECK(by == Outcome::kFn || by == Outcome::kFp)
      << "worst frames: by FN or FP, not " << OutcomeName(by);
  std::vector<FrameCounts> frames = CountByFrame(records, cell);
  auto key = [by](const FrameCounts& c) { return by == Outcome::kFn ? c.fn : c.fp; };
  frames.erase(std::remove_if(frames.begin(), frames.end(),
                              [&](const FrameCounts& c) { return key(c) == 0; }),
               frames.end());
  std::stable_sort(frames.begin(), frames.end(), [&](const FrameCounts& a, const FrameCounts& b) {
    return key(a) > key(b);  // stable: ties stay in frame id order
  });
  if (static_cast<int>(frames.size()) > count) frames.resize(std::max(0, count));
  return frames;
}

void FrameViewsOptions::Check() const {
  STEREODET_CHECK(!results.empty()) << "view: no results folder given";
  STEREODET_CHECK(worst >= 0) << "view: worst " << worst << " is negative";
  STEREODET_CHECK(png_scale > 0 && png_scale <= 8)
      << "view: png_scale " << png_scale << " is not in (0, 8]";
  STEREODET_CHECK(metric.empty() || ParseOverlapKind(metric))
      << "view: --metric: unknown '" << metric << "' (2d, bev, 3d)";
  view.Check();
}

fs::path MatchRecordsFile(const fs::path& folder, const json& results) {
  if (fs::exists(folder / "matches.csv")) return folder / "matches.csv";
  if (results.contains("overlaps") && results["overlaps"].is_array() &&
      !results["overlaps"].empty() && results["overlaps"][0].is_string()) {
    const fs::path p =
        folder / fmt::format("matches_{}.csv", results["overlaps"][0].get<std::string>());
    if (fs::exists(p)) return p;
  }
  return {};
}

namespace {

struct Dataset {
  EvalInput input;
  fs::path root;  // the folder holding label_2, image_2, calib, velodyne
  std::map<std::string, size_t> index;
};

Dataset ReadDataset(const json& results) {
  const json in = results.value("input", json::object());
  EvalInputOptions options;
  options.gt = in.value("gt", std::string());
  options.det = in.value("det", std::string());
  options.split = in.value("split", std::string());
  options.lenient = in.value("lenient", false);
  if (in.contains("score_if_missing") && in["score_if_missing"].is_number()) {
    options.score_if_missing = in["score_if_missing"].get<double>();
  }
  Dataset d;
  d.input = LoadEvalFrames(options);
  d.root = d.input.label_dir.parent_path();
  for (size_t i = 0; i < d.input.frames.size(); ++i) d.index[d.input.frames[i].id] = i;
  return d;
}

std::vector<ViewCell> Cells(const json& results, const FrameViewsOptions& options) {
  std::vector<std::string> classes = options.classes;
  std::string metric = options.metric;
  for (const json& e : results.value("results", json::array())) {
    if (!e.value("evaluated", false)) continue;
    const std::string c = e.value("class", std::string());
    if (options.classes.empty() && std::find(classes.begin(), classes.end(), c) == classes.end()) {
      classes.push_back(c);
    }
    if (metric.empty()) metric = e.value("metric", std::string());
  }
  std::vector<ViewCell> cells;
  const std::optional<OverlapKind> kind = ParseOverlapKind(metric);
  if (!kind) return cells;
  for (const std::string& c : classes) cells.push_back({c, *kind, options.difficulty});
  return cells;
}

// The folder of .bin point clouds that `points` (FrameViewsOptions::points) names: the folder
// itself, or its velodyne/ (the output folder of `stereodet stereo --encode points`). Throws
// std::runtime_error naming it when it holds no .bin file: every view would say "0 points".
fs::path PointsFolder(const fs::path& points) {
  auto has_scans = [](const fs::path& dir) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return false;
    for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
      if (e.path().extension() == ".bin") return true;
    }
    return false;
  };
  if (has_scans(points)) return points;
  STEREODET_CHECK_IO(has_scans(points / "velodyne"))
      << "view --points " << points.string()
      << ": no point cloud (.bin) there or in its velodyne/; give a folder of "
         ".bin scans, or the output folder of `stereodet stereo --encode points`";
  return points / "velodyne";
}

FrameViewsResult WriteViews(
    const Dataset& dataset, const std::vector<ViewRecord>& records,
    const std::vector<std::pair<ViewCell, std::vector<std::pair<std::string, std::string>>>>& jobs,
    const fs::path& out, const FrameViewsOptions& options) {
  FrameViewsResult result;
  const fs::path points_dir =
      options.points.empty() ? dataset.root / "velodyne" : PointsFolder(options.points);
  const bool png = options.png && PngFromSvgAvailable();
  if (options.png && !png) {
    result.notes.push_back("view: PNG files not written: this build has no librsvg");
  }
  fs::create_directories(out);
  int64_t total = 0;
  for (const auto& job : jobs) total += static_cast<int64_t>(job.second.size());
  ProgressReporter progress("view", total, options.progress);
  std::set<std::string> without_image;
  std::map<std::string, WrittenFrameView> drawn;  // by file stem: a frame with most FN and FP
  for (const auto& [cell, frames] : jobs) {
    std::map<std::string, std::vector<ViewRecord>> by_frame;
    for (const ViewRecord& r : records) {
      if (InCell(r, cell)) by_frame[r.frame_id].push_back(r);
    }
    const std::vector<FrameCounts> counts = CountByFrame(records, cell);
    for (const auto& [frame_id, reason] : frames) {
      const std::string stem = frame_id + "_" + ViewCellName(cell);
      if (const auto done = drawn.find(stem); done != drawn.end()) {
        WrittenFrameView again = done->second;
        again.reason = reason;
        result.views.push_back(std::move(again));
        progress.Add();
        continue;
      }
      const auto it = dataset.index.find(frame_id);
      STEREODET_CHECK_IO(it != dataset.index.end())
          << "view: frame " << frame_id << " is not one of the evaluation's frames";
      const EvalFrame& frame = dataset.input.frames[it->second];
      FrameViewData data;
      data.frame_id = frame_id;
      data.labels = frame.labels;
      data.detections = frame.detections;
      data.records = by_frame[frame_id];
      data.cell = cell;
      data.image = dataset.root / "image_2" / (frame_id + ".png");
      const fs::path calib = dataset.root / "calib" / (frame_id + ".txt");
      if (fs::exists(calib)) data.calib = ReadCalibration(calib);
      const fs::path points = points_dir / (frame_id + ".bin");
      if (data.calib && fs::exists(points)) data.points = ReadVelodyne(points);
      const FrameView view = DrawFrameView(data, options.view);
      if (!view.has_image) without_image.insert(frame_id);

      WrittenFrameView w;
      w.frame_id = frame_id;
      w.cell = cell;
      w.reason = reason;
      for (const FrameCounts& c : counts) {
        if (c.frame_id == frame_id) {
          w.tp = c.tp;
          w.fp = c.fp;
          w.fn = c.fn;
        }
      }
      w.image_svg = stem + "_image.svg";
      w.bev_svg = stem + "_bev.svg";
      const std::string header = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
      WriteFileAtomically(out / w.image_svg, header + view.image_svg);
      WriteFileAtomically(out / w.bev_svg, header + view.bev_svg);
      result.files.push_back(out / w.image_svg);
      result.files.push_back(out / w.bev_svg);
      if (png) {
        w.image_png = stem + "_image.png";
        w.bev_png = stem + "_bev.png";
        WritePngFromSvg(out / w.image_png, view.image_svg, options.png_scale);
        WritePngFromSvg(out / w.bev_png, view.bev_svg, options.png_scale);
        result.files.push_back(out / w.image_png);
        result.files.push_back(out / w.bev_png);
      }
      drawn[stem] = w;
      result.views.push_back(std::move(w));
      progress.Add();
    }
  }
  progress.Finish();
  if (!without_image.empty()) {
    result.notes.push_back(fmt::format(
        "view: {} frame(s) without a PNG left image in {} (drawn on a grey canvas), first {}",
        without_image.size(), (dataset.root / "image_2").string(), *without_image.begin()));
  }
  return result;
}

// `view` adds files to its folder and deletes none, but it writes only into a folder of views: an
// absent or empty one, or one whose every file is a frame view (ID_CELL_image|bev.svg|png) or a
// leftover temporary of one; a model folder, a data set or someone's files are refused before
// anything is drawn, naming the first file that is not a view.
void CheckViewsFolder(const fs::path& out) {
  std::error_code ec;
  if (!fs::exists(out, ec)) return;
  STEREODET_CHECK_IO(fs::is_directory(out, ec))
      << "view: --out " << out.string() << " is a file, not a folder";
  for (const fs::directory_entry& entry : fs::directory_iterator(out)) {
    const std::string name = entry.path().filename().string();
    const bool temporary =
        !name.empty() && name[0] == '.' && name.find(".tmp-") != std::string::npos;
    bool view = false;
    for (const char* suffix : {"_image.svg", "_bev.svg", "_image.png", "_bev.png"}) {
      view =
          view || (name.size() > std::strlen(suffix) &&
                   name.compare(name.size() - std::strlen(suffix), std::string::npos, suffix) == 0);
    }
    STEREODET_CHECK_IO(entry.is_regular_file(ec) && (view || temporary))
        << "view: --out " << out.string() << " holds " << name
        << ", which is not a frame view; view writes only into an empty folder or one of frame "
           "views: give a new or empty folder";
  }
}

// The worst frames of every cell, most FN then most FP.
std::vector<std::pair<ViewCell, std::vector<std::pair<std::string, std::string>>>> WorstJobs(
    const std::vector<ViewRecord>& records, const std::vector<ViewCell>& cells, int worst) {
  std::vector<std::pair<ViewCell, std::vector<std::pair<std::string, std::string>>>> jobs;
  for (const ViewCell& cell : cells) {
    std::vector<std::pair<std::string, std::string>> frames;
    for (const FrameCounts& c : WorstFrames(records, cell, Outcome::kFn, worst)) {
      frames.push_back({c.frame_id, "most FN"});
    }
    for (const FrameCounts& c : WorstFrames(records, cell, Outcome::kFp, worst)) {
      frames.push_back({c.frame_id, "most FP"});
    }
    jobs.push_back({cell, frames});
  }
  return jobs;
}

}  // namespace

FrameViewsResult WriteFrameViews(const FrameViewsOptions& options) {
  options.Check();
  const fs::path results_path = options.results / "results.json";
  STEREODET_CHECK_IO(fs::exists(results_path))
      << "view: " << options.results.string()
      << " is not a results folder of stereodet eval --out (no results.json)";
  json results;
  try {
    results = json::parse(ReadFile(results_path));
  } catch (const json::exception& e) {
    STEREODET_THROW_IO() << results_path.string() << ": not JSON: " << e.what();
  }
  const fs::path records_csv = MatchRecordsFile(options.results, results);
  STEREODET_CHECK_IO(!records_csv.empty())
      << "view: " << options.results.string()
      << " has no matches.csv: evaluate with `stereodet eval ... --out DIR --records`";
  const std::vector<ViewRecord> records = ReadMatchRecordsCsv(records_csv);
  const std::vector<ViewCell> cells = Cells(results, options);
  const Dataset dataset = ReadDataset(results);
  std::vector<std::pair<ViewCell, std::vector<std::pair<std::string, std::string>>>> jobs;
  if (options.frames.empty()) {
    jobs = WorstJobs(records, cells, options.worst);
  } else {
    for (const ViewCell& cell : cells) {
      std::vector<std::pair<std::string, std::string>> frames;
      for (const std::string& id : options.frames) frames.push_back({id, "asked"});
      jobs.push_back({cell, frames});
    }
  }
  const fs::path out = options.out.empty() ? options.results / "views" : options.out;
  CheckViewsFolder(out);
  return WriteViews(dataset, records, jobs, out, options);
}

FrameViewsResult WriteWorstFrameViews(const json& results, const fs::path& records_csv,
                                      const fs::path& out, const FrameViewsOptions& options) {
  const std::vector<ViewRecord> records = ReadMatchRecordsCsv(records_csv);
  Dataset dataset;
  try {
    dataset = ReadDataset(results);
  } catch (const std::exception& e) {
    FrameViewsResult none;
    none.notes.push_back(std::string("frame views not drawn: cannot read the evaluated frames "
                                     "again (") +
                         e.what() + ")");
    return none;
  }
  return WriteViews(dataset, records, WorstJobs(records, Cells(results, options), options.worst),
                    out, options);
}

}  // namespace stereodet
