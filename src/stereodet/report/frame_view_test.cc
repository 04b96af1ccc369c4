#include "stereodet/report/frame_view.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/pipelines/evaluation.h"
#include "stereodet/report/raster.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/test_paths.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

const fs::path kViewData = ::stereodet::TestSourceDir() / "tests/data/view_small";

// tests/data/view_small evaluated with records (KITTI matcher, Car / Pedestrian / Cyclist, every
// metric) into `out`.
EvaluationResult EvaluateViewSmall(const fs::path& out) {
  EvaluationOptions options;
  options.input.gt = kViewData;
  options.input.det = kViewData / "det";
  options.out = out;
  options.records = true;
  return RunEvaluation(options);
}

int Count(const std::string& text, const std::string& pattern) {
  const std::regex re(pattern);
  return static_cast<int>(
      std::distance(std::sregex_iterator(text.begin(), text.end(), re), std::sregex_iterator()));
}

const ClassResult& CarModerate2d(const EvaluationResult& result) {
  const ClassResult* r =
      result.runs.front().result.Find("Car", OverlapKind::k2D, Difficulty::kModerate);
  EXPECT_NE(r, nullptr);
  return *r;
}

TEST(FrameViewTest, RecordsReadBackEqualTheEvaluatorsRecords) {
  TestTempDir dir;
  const EvaluationResult result = EvaluateViewSmall(dir.path() / "eval");
  const std::vector<ViewRecord> read = ReadMatchRecordsCsv(dir.path() / "eval/matches.csv");
  const ClassResult& car = CarModerate2d(result);
  const ViewCell cell{"Car", OverlapKind::k2D, Difficulty::kModerate};
  std::vector<ViewRecord> in_cell;
  for (const ViewRecord& r : read) {
    if (InCell(r, cell)) in_cell.push_back(r);
  }
  ASSERT_EQ(in_cell.size(), car.records.size());
  for (size_t i = 0; i < in_cell.size(); ++i) {
    const MatchRecord& m = car.records[i];
    EXPECT_EQ(in_cell[i].frame_id, result.input.frames[m.frame].id) << i;
    EXPECT_EQ(in_cell[i].outcome, m.outcome) << i;
    EXPECT_EQ(in_cell[i].detection, m.detection) << i;
    EXPECT_EQ(in_cell[i].label, m.label) << i;
    EXPECT_NEAR(in_cell[i].iou, m.iou, 1e-9) << i;
  }
  // The fixture as its README says: frame 000000 TP 1, FP 2, FN 1; frame 000001 TP 1, FP 2.
  const std::vector<FrameCounts> counts = CountByFrame(read, cell);
  ASSERT_EQ(counts.size(), 2u);
  EXPECT_EQ(counts[0].frame_id, "000000");
  EXPECT_EQ(counts[0].tp, 1);
  EXPECT_EQ(counts[0].fp, 2);
  EXPECT_EQ(counts[0].fn, 1);
  EXPECT_EQ(counts[1].frame_id, "000001");
  EXPECT_EQ(counts[1].tp, 1);
  EXPECT_EQ(counts[1].fp, 2);
  EXPECT_EQ(counts[1].fn, 0);
  const std::vector<FrameCounts> most_fn = WorstFrames(read, cell, Outcome::kFn, 3);
  ASSERT_EQ(most_fn.size(), 1u);
  EXPECT_EQ(most_fn[0].frame_id, "000000");
  const std::vector<FrameCounts> most_fp = WorstFrames(read, cell, Outcome::kFp, 1);
  ASSERT_EQ(most_fp.size(), 1u);
  EXPECT_EQ(most_fp[0].frame_id, "000000");  // a tie of 2 FPs: the first frame
}

// Draws the view of `frame_id` from the fixture's files and the evaluation's records.
FrameView ViewOf(const EvaluationResult& result, const std::vector<ViewRecord>& records,
                 const std::string& frame_id, FrameViewData* data_out = nullptr) {
  FrameViewData data;
  data.frame_id = frame_id;
  for (const EvalFrame& f : result.input.frames) {
    if (f.id == frame_id) {
      data.labels = f.labels;
      data.detections = f.detections;
    }
  }
  for (const ViewRecord& r : records) {
    if (r.frame_id == frame_id && InCell(r, data.cell)) data.records.push_back(r);
  }
  data.image = kViewData / "image_2" / (frame_id + ".png");
  data.calib = ReadCalibration(kViewData / "calib" / (frame_id + ".txt"));
  data.points = ReadVelodyne(kViewData / "velodyne" / (frame_id + ".bin"));
  if (data_out != nullptr) *data_out = data;
  return DrawFrameView(data);
}

TEST(FrameViewTest, DrawsOneBoxPerRecordSideInItsOutcomesColour) {
  TestTempDir dir;
  const EvaluationResult result = EvaluateViewSmall(dir.path() / "eval");
  const std::vector<ViewRecord> records = ReadMatchRecordsCsv(dir.path() / "eval/matches.csv");
  FrameViewData data;
  const FrameView view = ViewOf(result, records, "000000", &data);
  EXPECT_TRUE(view.has_image);
  EXPECT_EQ(view.num_tp, 1);
  EXPECT_EQ(view.num_fp, 2);
  EXPECT_EQ(view.num_fn, 1);
  // A TP row draws its detection and its label; the others one side each.
  int expected_boxes = 0;
  for (const ViewRecord& r : data.records) expected_boxes += (r.detection >= 0) + (r.label >= 0);
  EXPECT_EQ(expected_boxes, 5);
  EXPECT_EQ(view.num_image_boxes, expected_boxes);
  EXPECT_EQ(Count(view.image_svg, "<rect class=\"box "), expected_boxes);
  EXPECT_EQ(Count(view.image_svg, "<rect class=\"box tp det\""), 1);
  EXPECT_EQ(Count(view.image_svg, "<rect class=\"box tp label\""), 1);
  EXPECT_EQ(Count(view.image_svg, "<rect class=\"box fp det\""), 2);
  EXPECT_EQ(Count(view.image_svg, "<rect class=\"box fn label\""), 1);
  // Every object of the fixture has 3D fields: as many footprints in the bird's-eye view.
  EXPECT_EQ(view.num_bev_boxes, expected_boxes);
  EXPECT_EQ(Count(view.bev_svg, "<polygon class=\"box "), expected_boxes);
  EXPECT_GT(view.num_points, 100);
  EXPECT_THAT(view.image_svg, HasSubstr("data:image/png;base64,"));
  // The score and IoU of the TP: score 0.91, and the IoU the record holds.
  for (const ViewRecord& r : data.records) {
    if (r.outcome == Outcome::kTp) {
      EXPECT_THAT(view.image_svg, HasSubstr(fmt::format(">0.91 IoU {:.2f}<", r.iou)));
    }
    if (r.outcome == Outcome::kFn) {
      EXPECT_THAT(view.image_svg, HasSubstr(fmt::format(">FN IoU {:.2f}<", r.iou)));
    }
  }

  if (!PngFromSvgAvailable()) GTEST_SKIP() << "no librsvg: the pixels are not checked";
  const RasterImage image = RasterizeSvg(view.image_svg);
  EXPECT_EQ(image.width, 1242);
  EXPECT_EQ(image.height, 375 + 26);
  // The embedded image: sky (200) above the horizon, road (120) below, far from any box.
  EXPECT_EQ(image.At(1200, 20), 0xC8C8C8u);
  EXPECT_EQ(image.At(1200, 360), 0x787878u);
  // The middle of each box's left edge has its outcome's colour: the 3 px stroke covers the
  // whole pixel column floor(left).
  auto left_edge = [&](const Object& o) {
    return image.At(static_cast<int>(std::floor(o.box.left)),
                    static_cast<int>(std::floor((o.box.top + o.box.bottom) / 2)));
  };
  for (const ViewRecord& r : data.records) {
    if (r.outcome == Outcome::kTp) {
      EXPECT_EQ(left_edge(data.detections[r.detection]), 0x009E73u);
    } else if (r.outcome == Outcome::kFp) {
      EXPECT_EQ(left_edge(data.detections[r.detection]), 0xD55E00u) << r.detection;
    }
  }
  // Inside the TP detection's box, a few px right of its left edge, the road shows through.
  const Object& tp = data.detections[0];
  EXPECT_EQ(image.At(static_cast<int>(tp.box.left) + 6,
                     static_cast<int>((tp.box.top + tp.box.bottom) / 2)),
            0x787878u);
}

// A crowded frame by hand: five FP detections on one box (scores 0.9 .. 0.5) and two FN labels on
// another just below it, no image (a grey canvas).
FrameViewData CrowdedFrame() {
  FrameViewData data;
  data.frame_id = "000000";
  Object box;
  box.type = "Car";
  box.box = {100, 100, 200, 150};
  for (int i = 0; i < 5; ++i) {
    data.detections.push_back(box);
    ViewRecord r;
    r.frame_id = data.frame_id;
    r.outcome = Outcome::kFp;
    r.detection = i;
    r.score = 0.9 - 0.1 * i;
    r.iou = 0.1;
    data.records.push_back(r);
  }
  box.box = {105, 160, 210, 200};
  for (int i = 0; i < 2; ++i) {
    data.labels.push_back(box);
    ViewRecord r;
    r.frame_id = data.frame_id;
    r.outcome = Outcome::kFn;
    r.label = i;
    r.score = NAN;
    data.records.push_back(r);
  }
  return data;
}

// The (x, baseline) of every box text of an image view (the legend's texts are below the image).
std::vector<std::pair<double, double>> BoxTexts(const std::string& svg, double image_height) {
  std::vector<std::pair<double, double>> out;
  const std::regex text("<text x=\"([0-9.]+)\" y=\"([0-9.]+)\" fill=\"#[0-9A-Fa-f]+\" stroke");
  for (std::sregex_iterator it(svg.begin(), svg.end(), text), end; it != end; ++it) {
    const double y = std::stod((*it)[2]);
    if (y <= image_height) out.emplace_back(std::stod((*it)[1]), y);
  }
  return out;
}

TEST(FrameViewTest, MinScoreAndTopKChooseTheDetectionsDrawnLabelsStay) {
  const FrameViewData data = CrowdedFrame();
  FrameViewOptions options;
  EXPECT_EQ(DrawFrameView(data, options).num_image_boxes, 7);
  options.min_score = 0.65;  // 0.9, 0.8, 0.7
  FrameView view = DrawFrameView(data, options);
  EXPECT_EQ(view.num_image_boxes, 3 + 2);
  EXPECT_THAT(view.image_svg, HasSubstr(">0.70 IoU 0.10<"));
  EXPECT_THAT(view.image_svg, ::testing::Not(HasSubstr(">0.60 IoU")));
  EXPECT_EQ(view.num_fp, 5);  // the frame's counts, drawn or not
  options.top_k = 2;          // of those, 0.9 and 0.8
  view = DrawFrameView(data, options);
  EXPECT_EQ(Count(view.image_svg, "<rect class=\"box fp det\""), 2);
  EXPECT_THAT(view.image_svg, HasSubstr(">0.80 IoU 0.10<"));
  EXPECT_THAT(view.image_svg, ::testing::Not(HasSubstr(">0.70 IoU")));
  EXPECT_EQ(Count(view.image_svg, "<rect class=\"box fn label\""), 2);
  options.min_score = -std::numeric_limits<double>::infinity();
  options.top_k = 1;
  EXPECT_EQ(Count(DrawFrameView(data, options).image_svg, "<rect class=\"box fp det\""), 1);
  options.top_k = -1;
  EXPECT_THROW(DrawFrameView(data, options), std::invalid_argument);
}

TEST(FrameViewTest, BoxTextsDoNotOverlap) {
  const FrameViewData data = CrowdedFrame();
  const FrameView view = DrawFrameView(data);
  const auto texts = BoxTexts(view.image_svg, 375);
  ASSERT_EQ(texts.size(), 7u);  // five detections' and two FNs'
  for (size_t i = 0; i < texts.size(); ++i) {
    for (size_t j = i + 1; j < texts.size(); ++j) {
      // Every text starts at x 100 or 105 and is wider than 5 px: they must differ in height.
      EXPECT_GE(std::abs(texts[i].second - texts[j].second), 14.0) << i << " " << j;
    }
  }
  for (const auto& [x, y] : texts) {
    EXPECT_GE(y, 12.0);
    EXPECT_LE(y, 375.0);
  }
}

// view_small evaluated into DIR/eval (with records), and views of its worst frame per outcome.
FrameViewsOptions WorstViewOfViewSmall(const fs::path& dir) {
  EvaluateViewSmall(dir / "eval");
  FrameViewsOptions options;
  options.results = dir / "eval";
  options.worst = 1;
  return options;
}

TEST(FrameViewTest, WritesTheWorstFramesViewsAsSvgAndPng) {
  TestTempDir dir;
  FrameViewsOptions options = WorstViewOfViewSmall(dir.path());
  const FrameViewsResult views = WriteFrameViews(options);
  // Car only is evaluated (no Pedestrian or Cyclist detection): one most-FN, one most-FP frame.
  ASSERT_EQ(views.views.size(), 2u);
  EXPECT_EQ(views.views[0].reason, "most FN");
  EXPECT_EQ(views.views[0].frame_id, "000000");
  EXPECT_EQ(views.views[0].fn, 1);
  EXPECT_EQ(views.views[1].reason, "most FP");
  EXPECT_EQ(views.views[1].fp, 2);
  for (const WrittenFrameView& v : views.views) {
    EXPECT_TRUE(fs::exists(dir.path() / "eval/views" / v.image_svg)) << v.image_svg;
    EXPECT_TRUE(fs::exists(dir.path() / "eval/views" / v.bev_svg)) << v.bev_svg;
    EXPECT_EQ(v.image_svg, v.frame_id + "_car_2d_moderate_image.svg");
    if (PngFromSvgAvailable()) {
      EXPECT_TRUE(fs::exists(dir.path() / "eval/views" / v.image_png));
    }
  }
  options.frames = {"000042"};
  EXPECT_THROW(WriteFrameViews(options), std::runtime_error);
}

// view adds files and deletes none, but only into a folder of views.
TEST(FrameViewTest, WritesOnlyIntoAFolderOfViews) {
  TestTempDir dir;
  FrameViewsOptions options = WorstViewOfViewSmall(dir.path());
  options.out = dir.path() / "home";
  fs::create_directories(options.out);
  WriteFileAtomically(options.out / "thesis.tex", "precious");
  try {
    WriteFrameViews(options);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("holds thesis.tex, which is not a frame view"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(options.out), fs::directory_iterator()), 1);
  options.out = dir.path() / "views";
  EXPECT_NO_THROW(WriteFrameViews(options));
  EXPECT_NO_THROW(WriteFrameViews(options));  // its own views again
}

// --points takes a folder of scans or the `stereo --encode points` output folder (its velodyne/);
// one with no scan would draw "0 points" in every view.
TEST(FrameViewTest, PointsTakeAScanFolderOrAStereoOutputAndRefuseAFolderWithoutScans) {
  TestTempDir dir;
  FrameViewsOptions options = WorstViewOfViewSmall(dir.path());
  options.png = false;
  options.points = dir.path() / "empty";
  fs::create_directories(options.points);
  WriteFileAtomically(options.points / "README.txt", "no scans");
  EXPECT_THAT([&] { WriteFrameViews(options); },
              ::testing::ThrowsMessage<std::runtime_error>(::testing::HasSubstr(
                  "view --points " + options.points.string() + ": no point cloud (.bin)")));
  EXPECT_FALSE(fs::exists(dir.path() / "eval/views"));  // refused before drawing
  options.points = dir.path() / "stereo_out";
  fs::create_directories(options.points / "velodyne");
  for (const char* id : {"000000", "000001"}) {
    fs::copy_file(kViewData / "velodyne" / (std::string(id) + ".bin"),
                  options.points / "velodyne" / (std::string(id) + ".bin"));
  }
  const FrameViewsResult from_root = WriteFrameViews(options);
  options.points /= "velodyne";
  options.out = dir.path() / "views2";
  const FrameViewsResult from_scans = WriteFrameViews(options);
  ASSERT_EQ(from_root.views.size(), from_scans.views.size());
  for (size_t i = 0; i < from_root.views.size(); ++i) {
    EXPECT_EQ(ReadFile(dir.path() / "eval/views" / from_root.views[i].bev_svg),
              ReadFile(options.out / from_scans.views[i].bev_svg));
  }
}

TEST(FrameViewTest, ARecordOutsideTheFramesFilesIsRefused) {
  FrameViewData data;
  data.frame_id = "000000";
  data.labels.resize(1);
  ViewRecord r;
  r.outcome = Outcome::kFp;
  r.detection = 0;  // no detection in the frame
  data.records = {r};
  EXPECT_THROW(DrawFrameView(data), std::invalid_argument);
  FrameViewOptions bad;
  bad.bev_cell_m = 0;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

TEST(FrameViewTest, AFolderWithoutRecordsNamesTheFlag) {
  TestTempDir dir;
  EvaluationOptions options;
  options.input.gt = kViewData;
  options.input.det = kViewData / "det";
  options.out = dir.path() / "eval";
  RunEvaluation(options);
  FrameViewsOptions view;
  view.results = options.out;
  try {
    WriteFrameViews(view);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("--records"));
  }
}

}  // namespace
}  // namespace stereodet
