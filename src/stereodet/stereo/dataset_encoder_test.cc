#include "stereodet/stereo/dataset_encoder.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/stereo/frame_pictures.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/stereo/planar_scene.h"
#include "stereodet/stereo/visualize.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// A small scene dataset and options that keep the matcher quick on it.
constexpr int kWidth = 256, kHeight = 96;

std::vector<std::string> WriteScenes(const fs::path& root, int frames = 2) {
  PlanarSceneDatasetOptions options;
  options.frames = frames;
  options.width_px = kWidth;
  options.height_px = kHeight;
  return WritePlanarSceneDataset(root, options);
}

EncodeDatasetOptions SmallOptions() {
  EncodeDatasetOptions options;
  options.stereo.disparity.num_disparities = 64;
  options.progress.stream = nullptr;
  return options;
}

// Every regular file under `dir`, relative, in name order.
std::vector<fs::path> ListFiles(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file()) files.push_back(fs::relative(entry.path(), dir));
  }
  std::sort(files.begin(), files.end());
  return files;
}

// The encoder upsamples match-size codes by nearest-exact interpolation; sampling them back at the
// match-size pixel centres is exact for every size and scale (a property over random codes,
// KITTI's odd sizes included), so a `stereo` folder gives a detector the codes it would compute.
TEST(HeightCodesAtMatchSizeTest, InvertsTheEncodersNearestExactUpsampling) {
  cv::RNG rng(7);
  DisparityOptions options;
  for (const cv::Size full : {cv::Size(1242, 375), cv::Size(1224, 370), cv::Size(160, 48),
                              cv::Size(333, 97), cv::Size(641, 211)}) {
    for (const double scale : {0.25, 0.3, 0.5, 0.515, 0.75, 0.9, 1.0}) {
      options.match_scale = scale;
      const cv::Size match = options.MatchSize(full);
      cv::Mat codes(match, CV_16UC1);
      rng.fill(codes, cv::RNG::UNIFORM, 0, 512);
      cv::Mat up;
      cv::resize(codes, up, full, 0, 0, cv::INTER_NEAREST_EXACT);
      EXPECT_EQ(cv::norm(HeightCodesAtMatchSize(up, match), codes, cv::NORM_INF), 0.0)
          << full << " at " << scale;
    }
  }
  EXPECT_THROW(HeightCodesAtMatchSize(cv::Mat(10, 10, CV_16UC1), cv::Size(11, 10)),
               std::invalid_argument);
}

TEST(DatasetOutputsTest, ParsesAnyOrderAndNamesInOneOrder) {
  const DatasetOutputs outputs = ParseDatasetOutputs(" disparity, rgbh ,points");
  EXPECT_TRUE(outputs.rgbh);
  EXPECT_FALSE(outputs.rgbd);
  EXPECT_TRUE(outputs.points);
  EXPECT_TRUE(outputs.disparity);
  EXPECT_EQ(DatasetOutputsName(outputs), "rgbh,points,disparity");
  EXPECT_EQ(DatasetOutputsName(ParseDatasetOutputs("rgbd,rgbd")), "rgbd");
  EXPECT_EQ(DatasetOutputsName(DatasetOutputs()), "rgbh");  // the default
  EXPECT_EQ(DatasetOutputsName(DatasetOutputs{.rgbh = false}), "");
}

TEST(DatasetOutputsTest, RejectsUnknownNamesAndEmptyLists) {
  try {
    ParseDatasetOutputs("rgbh,lidar");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("unknown output 'lidar'"));
  }
  EXPECT_THROW(ParseDatasetOutputs(""), std::invalid_argument);
  EXPECT_THROW(ParseDatasetOutputs(" , "), std::invalid_argument);
}

TEST(EncodeDatasetOptionsTest, Check) {
  EXPECT_NO_THROW(EncodeDatasetOptions().Check());
  EncodeDatasetOptions none;
  none.outputs.rgbh = false;
  EXPECT_THROW(none.Check(), std::invalid_argument);
  EncodeDatasetOptions threads;
  threads.num_threads = -1;
  EXPECT_THROW(threads.Check(), std::invalid_argument);
  EncodeDatasetOptions stereo;
  stereo.stereo.disparity.num_disparities = 20;  // not a multiple of 16
  EXPECT_THROW(stereo.Check(), std::invalid_argument);
}

TEST(GroundFitLineTest, FormatsEveryField) {
  GroundPlaneFit fit;
  fit.fitted = true;
  fit.plane.normal_in_rect = {0.0, -1.0, 0.0};
  fit.plane.offset_m = 1.65;
  fit.inliers = 10;
  fit.samples = 20;
  fit.tilt_deg = 0.5;
  fit.reason = "fitted";
  EXPECT_EQ(GroundFitLine(fit),
            "fitted 1 normal 0.000000 -1.000000 0.000000 offset_m 1.6500 inliers 10 samples 20 "
            "tilt_deg 0.500 reason fitted\n");
}

TEST(GroundFitLineTest, ParsesWhatItWrites) {
  GroundPlaneFit fit;
  fit.fitted = true;
  fit.plane.normal_in_rect = Eigen::Vector3d(0, -0.998, 0.0523);
  fit.plane.offset_m = 1.6;
  fit.inliers = 900;
  fit.samples = 1000;
  fit.tilt_deg = 3.0;
  fit.reason = "fitted";
  std::string line = GroundFitLine(fit);
  line.pop_back();
  const GroundPlaneFit back = ParseGroundFitLine(line, "g.txt", GroundPlaneOptions{});
  EXPECT_TRUE(back.fitted);
  EXPECT_TRUE(back.suspect);  // 3 degrees > 1.5
  EXPECT_EQ(back.inliers, 900);
  EXPECT_DOUBLE_EQ(back.InlierFraction(), 0.9);
  EXPECT_DOUBLE_EQ(back.camera_height_m, 1.6);
  EXPECT_EQ(back.reason, "fitted");
  fit.fitted = false;
  fit.reason = "too few ground inliers (12 < 200)";
  line = GroundFitLine(fit);
  EXPECT_EQ(ParseGroundFitLine(line, "g.txt", {}).reason, fit.reason);
  EXPECT_FALSE(ParseGroundFitLine(line, "g.txt", {}).suspect);
  EXPECT_THROW(ParseGroundFitLine("fitted x", "g.txt", {}), ParseError);
}

TEST(DatasetManifestTest, RecordsOutputsAndSettingsButNotHowTheRunGoes) {
  EncodeDatasetOptions options;
  options.outputs = ParseDatasetOutputs("points,rgbh");
  options.stereo.disparity.num_disparities = 64;
  const std::string manifest = DatasetManifest(options);
  EXPECT_THAT(manifest, HasSubstr("\"encode\": \"rgbh,points\""));
  EXPECT_THAT(manifest, HasSubstr("\"num_disparities\": 64"));
  EXPECT_EQ(manifest.back(), '\n');
  EncodeDatasetOptions run = options;
  run.force = true;
  run.evaluate = true;
  run.num_threads = 3;
  run.progress.stream = nullptr;
  EXPECT_EQ(DatasetManifest(run), manifest);
  run.stereo.blur.sigma_px = 1.0;
  EXPECT_NE(DatasetManifest(run), manifest);
}

TEST(PlanarSceneDatasetTest, WritesTheKittiLayoutWithACentredPrincipalPoint) {
  TestTempDir dir;
  const std::vector<std::string> ids = WriteScenes(dir.path(), 3);
  EXPECT_EQ(ids, (std::vector<std::string>{"000000", "000001", "000002"}));
  EXPECT_EQ(ReadFile(dir / "ImageSets/all.txt"), "000000\n000001\n000002\n");
  for (const std::string& id : ids) {
    for (const char* folder : {"image_2", "image_3", "disp_noc_0"}) {
      EXPECT_TRUE(fs::exists(dir / "training" / folder / (id + ".png"))) << folder << " " << id;
    }
  }
  const cv::Mat left = ReadColourImage(dir / "training/image_2/000001.png");
  EXPECT_EQ(left.cols, kWidth);
  EXPECT_EQ(left.rows, kHeight);
  // KITTI's principal point moved by half the pixels cut off on each axis.
  const Calibration kitti = KittiLikeCalibration();
  const Calibration calib = ReadCalibration(dir / "training/calib/000001.txt");
  EXPECT_NEAR(calib.PrincipalPointPx().x(), kitti.PrincipalPointPx().x() - (1242 - kWidth) / 2.0,
              1e-6);
  EXPECT_NEAR(calib.PrincipalPointPx().y(), kitti.PrincipalPointPx().y() - (375 - kHeight) / 2.0,
              1e-6);
  EXPECT_NEAR(calib.FocalPx(), kitti.FocalPx(), 1e-6);

  PlanarSceneDatasetOptions bad;
  bad.frames = 0;
  EXPECT_THROW(WritePlanarSceneDataset(dir / "bad", bad), std::invalid_argument);
}

TEST(EncodeDatasetTest, EncodesEveryFrameThenResumesWhereFilesAreMissing) {
  TestTempDir dir;
  const std::vector<std::string> ids = WriteScenes(dir / "data");
  const KittiDataset dataset(dir / "data");
  EncodeDatasetOptions options = SmallOptions();
  options.outputs = ParseDatasetOutputs("rgbh,points,disparity");
  const fs::path out = dir / "out";

  const EncodeDatasetResult first = EncodeDataset(dataset, ids, out, options);
  EXPECT_EQ(first.encoded, 2);
  EXPECT_EQ(first.skipped, 0);
  int fallbacks = 0;
  for (const auto& [reason, count] : first.ground_fallbacks) fallbacks += count;
  EXPECT_EQ(first.ground_fitted + fallbacks, 2);
  EXPECT_THAT(first.stage_times, HasSubstr("disparity"));
  EXPECT_EQ(first.disparity_error.estimated_pixels, 0);  // not asked to evaluate
  EXPECT_EQ(ListFiles(out),
            (std::vector<fs::path>{"disparity/000000.png", "disparity/000001.png",
                                   "ground/000000.txt", "ground/000001.txt", "ground_summary.json",
                                   "rgbh/000000.png", "rgbh/000001.png", "run.json", "stereo.json",
                                   "velodyne/000000.bin", "velodyne/000001.bin"}));
  EXPECT_EQ(ReadFile(out / "stereo.json"), DatasetManifest(options));
  const std::string ground = ReadFile(out / "ground/000000.txt");
  EXPECT_EQ(ground.substr(0, 1), "#");
  EXPECT_THAT(ground, HasSubstr("\nfitted "));

  // Every frame's ground fit in the summary, as ground/ID.txt has it.
  const std::string summary_text = ReadFile(out / kGroundSummaryFile);
  const nlohmann::json summary = nlohmann::json::parse(summary_text);
  EXPECT_EQ(summary["summary"]["frames"], 2);
  EXPECT_EQ(summary["summary"]["fitted"], first.ground_fitted);
  for (const std::string& id : ids) {
    const nlohmann::json& frame = summary["per_frame"][id];
    const std::string line = ReadFile(out / "ground" / (id + ".txt"));
    EXPECT_THAT(line, HasSubstr(fmt::format("inliers {} samples {}", frame["inliers"].get<int>(),
                                            frame["samples"].get<int>())));
    EXPECT_NEAR(frame["inlier_fraction"].get<double>(),
                frame["samples"].get<int>() > 0
                    ? frame["inliers"].get<double>() / frame["samples"].get<int>()
                    : 0.0,
                1e-6);
  }

  // Everything there: nothing recomputed.
  const EncodeDatasetResult again = EncodeDataset(dataset, ids, out, options);
  EXPECT_EQ(again.encoded, 0);
  EXPECT_EQ(again.skipped, 2);
  // The summary of a resumed run covers the frames already done, read from ground/ID.txt.
  EXPECT_EQ(ReadFile(out / kGroundSummaryFile), summary_text);

  // One frame lost a file: only that frame is recomputed.
  fs::remove(out / "velodyne/000001.bin");
  const EncodeDatasetResult resumed = EncodeDataset(dataset, ids, out, options);
  EXPECT_EQ(resumed.encoded, 1);
  EXPECT_EQ(resumed.skipped, 1);
  EXPECT_TRUE(fs::exists(out / "velodyne/000001.bin"));

  // force recomputes every frame.
  options.force = true;
  EXPECT_EQ(EncodeDataset(dataset, ids, out, options).encoded, 2);
}

TEST(EncodeDatasetTest, RefusesAFolderMadeWithOtherSettingsUnlessForced) {
  TestTempDir dir;
  const std::vector<std::string> ids = WriteScenes(dir / "data");
  const KittiDataset dataset(dir / "data");
  const fs::path out = dir / "out";
  EncodeDatasetOptions options = SmallOptions();
  EncodeDataset(dataset, ids, out, options);
  const std::string manifest = ReadFile(out / "stereo.json");

  EncodeDatasetOptions other = options;
  other.stereo.disparity.method = DisparityMethod::kSemiGlobal;
  try {
    EncodeDataset(dataset, ids, out, other);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("stereo.json"));
    EXPECT_THAT(e.what(), HasSubstr("records different settings"));
    // The message names the setting, with both values.
    EXPECT_THAT(e.what(), HasSubstr("disparity.method: \"bm\" (this run: \"sgbm\")"));
  }
  EXPECT_EQ(ReadFile(out / "stereo.json"), manifest);  // left as it was

  // Another output is added to the folder's: only its files are written, the others kept.
  const std::string rgbh = ReadFile(out / "rgbh/000000.png");
  const auto rgbh_time = fs::last_write_time(out / "rgbh/000000.png");
  EncodeDatasetOptions more = options;
  more.outputs = ParseDatasetOutputs("points");
  const EncodeDatasetResult added = EncodeDataset(dataset, ids, out, more);
  EXPECT_EQ(added.encoded, 2);
  EXPECT_TRUE(fs::exists(out / "velodyne/000001.bin"));
  EXPECT_EQ(fs::last_write_time(out / "rgbh/000000.png"), rgbh_time);
  EXPECT_EQ(ReadFile(out / "rgbh/000000.png"), rgbh);
  EncodeDatasetOptions both = options;
  both.outputs = ParseDatasetOutputs("rgbh,points");
  EXPECT_EQ(ReadFile(out / "stereo.json"), DatasetManifest(both));
  EXPECT_EQ(EncodeDataset(dataset, ids, out, both).skipped, 2);  // all there now

  // force recomputes every frame and removes the outputs not asked for.
  other.force = true;
  const EncodeDatasetResult forced = EncodeDataset(dataset, ids, out, other);
  EXPECT_EQ(forced.encoded, 2);
  EXPECT_EQ(ReadFile(out / "stereo.json"), DatasetManifest(other));
  EXPECT_FALSE(fs::exists(out / "velodyne"));
}

TEST(EncodeDatasetTest, ResumeRedoesFramesMadeWithOtherSettingsAfterAnInterruptedForce) {
  TestTempDir dir;
  const std::vector<std::string> ids = WriteScenes(dir / "data", 3);
  const KittiDataset dataset(dir / "data");
  const fs::path out = dir / "out";
  EncodeDatasetOptions old_settings = SmallOptions();
  EXPECT_EQ(EncodeDataset(dataset, ids, out, old_settings).encoded, 3);

  // --force with new settings, interrupted after the first frame: stereo.json already holds the
  // new settings, frames 000001 and 000002 the old ones.
  EncodeDatasetOptions new_settings = SmallOptions();
  new_settings.stereo.disparity.num_disparities = 32;
  new_settings.force = true;
  EXPECT_EQ(EncodeDataset(dataset, {ids[0]}, out, new_settings).encoded, 1);
  EXPECT_EQ(ReadFile(out / "stereo.json"), DatasetManifest(new_settings));

  // The rerun without --force redoes exactly the two frames of the old settings.
  new_settings.force = false;
  const EncodeDatasetResult resumed = EncodeDataset(dataset, ids, out, new_settings);
  EXPECT_EQ(resumed.encoded, 2);
  EXPECT_EQ(resumed.skipped, 1);
  // Every frame now holds what an uninterrupted run with the new settings writes.
  EncodeDataset(dataset, ids, dir / "fresh", new_settings);
  for (const std::string& id : ids) {
    EXPECT_EQ(ReadFile(out / "rgbh" / (id + ".png")), ReadFile(dir / "fresh/rgbh" / (id + ".png")))
        << id;
    EXPECT_EQ(ReadFile(out / "ground" / (id + ".txt")),
              ReadFile(dir / "fresh/ground" / (id + ".txt")))
        << id;
  }
  // run.json lists every frame with one settings hash.
  const std::string run = ReadFile(out / "run.json");
  EXPECT_THAT(run, HasSubstr("\"tool\": \"stereo\""));
  EXPECT_THAT(run, HasSubstr("\"000002\": \""));
}

TEST(EncodeDatasetTest, RefusesOutputsFromOtherDataAndOutputsInsideTheInput) {
  TestTempDir dir;
  const std::vector<std::string> ids = WriteScenes(dir / "data", 1);
  WriteScenes(dir / "other", 1);
  const KittiDataset dataset(dir / "data");
  EncodeDataset(dataset, ids, dir / "out", SmallOptions());
  try {
    EncodeDataset(KittiDataset(dir / "other"), ids, dir / "out", SmallOptions());
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("holds outputs computed from --data"));
    EXPECT_THAT(e.what(), HasSubstr("other/training"));
  }
  // Two runs into one folder cannot interleave: the second is refused while the first runs.
  {
    const OutputLock running(dir / "out");
    try {
      EncodeDataset(dataset, ids, dir / "out", SmallOptions());
      FAIL() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_THAT(e.what(), HasSubstr("another run is writing into"));
    }
  }
  EXPECT_EQ(EncodeDataset(dataset, ids, dir / "out", SmallOptions()).skipped, 1);
  // --out inside the data (or the data itself) would overwrite it: refused before any write.
  const std::string left = ReadFile(dir / "data/training/image_2/000000.png");
  EXPECT_THROW(EncodeDataset(dataset, ids, dir / "data/training", SmallOptions()),
               std::invalid_argument);
  EXPECT_THROW(EncodeDataset(dataset, ids, dir / "data", SmallOptions()), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir / "data/training/rgbh"));
  EXPECT_EQ(ReadFile(dir / "data/training/image_2/000000.png"), left);
}

TEST(EncodeDatasetTest, BlurredRgbdAlsoWritesTheNetworkImage) {
  TestTempDir dir;
  const std::vector<std::string> ids = WriteScenes(dir / "data", 1);
  const KittiDataset dataset(dir / "data");
  EncodeDatasetOptions options = SmallOptions();
  options.outputs = ParseDatasetOutputs("rgbd");
  EncodeDataset(dataset, ids, dir / "sharp", options);
  EXPECT_EQ(ListFiles(dir / "sharp"),
            (std::vector<fs::path>{"depth/000000.png", "ground/000000.txt", "ground_summary.json",
                                   "height/000000.png", "run.json", "stereo.json"}));
  options.stereo.blur.sigma_px = 1.5;
  EncodeDataset(dataset, ids, dir / "blurred", options);
  EXPECT_EQ(ListFiles(dir / "blurred"),
            (std::vector<fs::path>{"depth/000000.png", "ground/000000.txt", "ground_summary.json",
                                   "height/000000.png", "image_2/000000.png", "run.json",
                                   "stereo.json"}));
}

TEST(EncodeDatasetTest, OutputsDoNotDependOnTheThreadCount) {
  TestTempDir dir;
  const std::vector<std::string> ids = WriteScenes(dir / "data", 3);
  const KittiDataset dataset(dir / "data");
  EncodeDatasetOptions options = SmallOptions();
  options.outputs = ParseDatasetOutputs("rgbh,rgbd,points,disparity");
  options.num_threads = 1;
  EncodeDataset(dataset, ids, dir / "one", options);
  options.num_threads = 3;
  EncodeDataset(dataset, ids, dir / "three", options);
  const std::vector<fs::path> files = ListFiles(dir / "one");
  ASSERT_EQ(files, ListFiles(dir / "three"));
  for (const fs::path& file : files) {
    EXPECT_EQ(ReadFile(dir / "one" / file), ReadFile(dir / "three" / file)) << file;
  }
}

// The pooled disparity error against the per-frame reference: counts summed, rates weighted by
// each frame's estimated pixels.
TEST(EncodeDatasetTest, EvaluatePoolsTheFramesDisparityError) {
  TestTempDir dir;
  const std::vector<std::string> ids = WriteScenes(dir / "data", 3);
  const KittiDataset dataset(dir / "data");
  EncodeDatasetOptions options = SmallOptions();
  options.evaluate = true;
  const EncodeDatasetResult result = EncodeDataset(dataset, ids, dir / "out", options);
  EXPECT_EQ(result.encoded, 3);

  long truth = 0, estimated = 0, outliers = 0;
  double bad = 0, d1 = 0, abs_error = 0;
  for (const std::string& id : ids) {
    const FramePaths in = dataset.Paths(id);
    StereoEncoder encoder(options.stereo);
    const StereoEncoding encoding =
        encoder.Encode(ReadColourImage(in.image_left), ReadColourImage(in.image_right),
                       StereoGeometry::FromCalibration(ReadCalibration(in.calib)));
    const DisparityErrorStats stats =
        EvaluateDisparity(encoding.disparity_px, ReadKittiDisparity(in.disparity));
    truth += stats.ground_truth_pixels;
    estimated += stats.estimated_pixels;
    bad += stats.bad_rate * stats.estimated_pixels;
    d1 += stats.d1_rate * stats.estimated_pixels;
    outliers += stats.d1_outlier_pixels;
    abs_error += stats.mean_abs_error_px * stats.estimated_pixels;
  }
  ASSERT_GT(estimated, 0);
  const DisparityErrorStats& pooled = result.disparity_error;
  EXPECT_EQ(pooled.ground_truth_pixels, truth);
  EXPECT_EQ(pooled.estimated_pixels, estimated);
  EXPECT_NEAR(pooled.density, static_cast<double>(estimated) / truth, 1e-12);
  EXPECT_NEAR(pooled.bad_rate, bad / estimated, 1e-12);
  EXPECT_NEAR(pooled.d1_rate, d1 / estimated, 1e-12);
  EXPECT_NEAR(pooled.mean_abs_error_px, abs_error / estimated, 1e-12);
  // The scenes' disparity is exact, so BM is close to it almost everywhere.
  EXPECT_LT(pooled.d1_rate, 0.05);
  // KITTI's D1-all: the outliers plus every ground-truth pixel BM left without a disparity.
  EXPECT_NEAR(pooled.d1_all_rate, static_cast<double>(outliers + truth - estimated) / truth, 1e-12);
  EXPECT_GT(pooled.d1_all_rate, pooled.d1_rate);
  // The same figures in OUT/disparity_evaluation.json, pooled and per frame.
  const nlohmann::json saved =
      nlohmann::json::parse(ReadFile(dir / "out" / kDisparityEvaluationFile));
  EXPECT_EQ(saved["frames"], 3);
  EXPECT_DOUBLE_EQ(saved["all"]["d1_all"].get<double>(), pooled.d1_all_rate);
  EXPECT_DOUBLE_EQ(saved["all"]["d1_estimated"].get<double>(), pooled.d1_rate);
  EXPECT_DOUBLE_EQ(saved["all"]["density"].get<double>(), pooled.density);
  EXPECT_EQ(saved["all"]["ground_truth_pixels"].get<long>(), truth);
  long per_frame_truth = 0;
  for (const std::string& id : ids) {
    per_frame_truth += saved["per_frame"][id]["ground_truth_pixels"].get<long>();
  }
  EXPECT_EQ(per_frame_truth, truth);

  // Evaluating again recomputes every frame (nothing is skipped) for the comparison, but keeps the
  // files of the frames already done.
  const auto rgbh_time = fs::last_write_time(dir / "out/rgbh/000001.png");
  const EncodeDatasetResult again = EncodeDataset(dataset, ids, dir / "out", options);
  EXPECT_EQ(again.encoded, 3);
  EXPECT_EQ(again.kept, 3);
  EXPECT_EQ(again.disparity_error.estimated_pixels, estimated);
  EXPECT_EQ(fs::last_write_time(dir / "out/rgbh/000001.png"), rgbh_time);
  // Without ground truth it is an error naming the file.
  fs::remove(dir / "data/training/disp_noc_0/000002.png");
  try {
    EncodeDataset(dataset, ids, dir / "out", options);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("000002.png"));
  }
}

TEST(EncodeDatasetTest, RefusesMissingInputsAndNoFramesBeforeWriting) {
  TestTempDir dir;
  std::vector<std::string> ids = WriteScenes(dir / "data");
  const KittiDataset dataset(dir / "data");
  fs::remove(dir / "data/training/image_3/000001.png");
  try {
    EncodeDataset(dataset, ids, dir / "out", SmallOptions());
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("1 required files are missing under"));
    EXPECT_THAT(e.what(), HasSubstr("000001: image_3/000001.png"));
  }
  EXPECT_THROW(EncodeDataset(dataset, {}, dir / "out", SmallOptions()), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(EncodeDatasetTest, APairOfUnequalSizesNamesBothFiles) {
  // The audit: the matcher's "left and right images differ in size" named no file or frame.
  TestTempDir dir;
  std::vector<std::string> ids = WriteScenes(dir / "data");
  const KittiDataset dataset(dir / "data");
  const fs::path right = dir / "data/training/image_3/000001.png";
  WriteImageAtomically(right, cv::Mat(kHeight, kWidth - 16, CV_8UC3, cv::Scalar(0, 0, 0)));
  try {
    EncodeDataset(dataset, ids, dir / "out", SmallOptions());
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("a stereo pair must have equal sizes: "));
    EXPECT_THAT(e.what(),
                HasSubstr("image_2/000001.png is 256x96 px, " + right.string() + " is 240x96 px"));
  }
}

TEST(EncodeDatasetTest, AnImageSmallerThanTheBlockNamesTheFile) {
  // The audit: "block size 15 does not fit the 8x8 image" named no file or frame.
  TestTempDir dir;
  std::vector<std::string> ids = WriteScenes(dir / "data");
  const KittiDataset dataset(dir / "data");
  const fs::path left = dir / "data/training/image_2/000001.png";
  const cv::Mat tiny(8, 8, CV_8UC3, cv::Scalar(0, 0, 0));
  WriteImageAtomically(left, tiny);
  WriteImageAtomically(dir / "data/training/image_3/000001.png", tiny);
  try {
    EncodeDataset(dataset, ids, dir / "out", SmallOptions());
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr(left.string() + ": the 8x8 px image is smaller than the "));
    EXPECT_THAT(e.what(), HasSubstr("block"));
  }
  // The same folder with a search range as wide as the image.
  const cv::Mat narrow(kHeight, 32, CV_8UC3, cv::Scalar(0, 0, 0));
  WriteImageAtomically(left, narrow);
  WriteImageAtomically(dir / "data/training/image_3/000001.png", narrow);
  EncodeDatasetOptions options = SmallOptions();
  options.stereo.disparity.num_disparities = 32;
  try {
    EncodeDataset(dataset, ids, dir / "out2", options);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr(left.string() + ": the image is 32 px wide"));
  }
}

TEST(FramePicturesTest, WritesFourPicturesOfTheImageSize) {
  TestTempDir dir;
  WriteScenes(dir / "data", 1);
  const KittiDataset dataset(dir / "data");
  StereoOptions options;
  options.disparity.num_disparities = 64;
  const FramePicturesResult result = WriteFramePictures(dataset, "000000", dir / "out", options);
  ASSERT_EQ(result.files.size(), 4u);
  EXPECT_EQ(result.files[0], dir / "out/000000_disparity.png");
  EXPECT_EQ(result.files[3], dir / "out/000000_bev.png");
  for (size_t i = 0; i < 3; ++i) {
    const cv::Mat picture = ReadColourImage(result.files[i]);
    EXPECT_EQ(picture.cols, kWidth) << result.files[i];
    EXPECT_EQ(picture.rows, kHeight) << result.files[i];
  }
  EXPECT_TRUE(fs::exists(result.files[3]));
  EXPECT_EQ(result.total_pixels, int64_t{kWidth} * kHeight);
  EXPECT_GT(result.stereo_pixels, 0);
  EXPECT_LE(result.stereo_pixels, result.total_pixels);
  EXPECT_GT(result.points, 0);
  EXPECT_THROW(WriteFramePictures(dataset, "000009", dir / "out", options), std::runtime_error);
  // An id that is a path would read and write outside --data and --out.
  EXPECT_THAT([&] { WriteFramePictures(dataset, "../../000000", dir / "out", options); },
              ::testing::ThrowsMessage<std::invalid_argument>(
                  ::testing::HasSubstr("--id '../../000000' is not a frame id (digits only)")));
}

// The keyed pictures: the picture unchanged on top, then the colour bar, the turbo map from t = 0
// at the bar's left end to t = 1 at its right end, on a white band.
TEST(FramePicturesTest, KeyedPicturesAddAColourBarBelowThePicture) {
  TestTempDir dir;
  WriteScenes(dir / "data", 1);
  const KittiDataset dataset(dir / "data");
  StereoOptions options;
  options.disparity.num_disparities = 64;
  const FramePicturesResult result = WriteFramePictures(dataset, "000000", dir / "out", options);
  ASSERT_EQ(result.keyed_files.size(), 4u);
  EXPECT_EQ(result.keyed_files[0], dir / "out/000000_disparity_key.png");
  for (size_t i = 0; i < 4; ++i) {
    const cv::Mat picture = ReadColourImage(result.files[i]);
    const cv::Mat keyed = ReadColourImage(result.keyed_files[i]);
    ASSERT_EQ(keyed.cols, picture.cols) << result.keyed_files[i];
    ASSERT_EQ(keyed.rows, picture.rows + ColourBarBandHeight()) << result.keyed_files[i];
    EXPECT_EQ(cv::norm(keyed(cv::Rect(0, 0, picture.cols, picture.rows)), picture, cv::NORM_INF),
              0);
    const int y = ColourBarTopPx(picture.rows) + ColourBarHeightPx() / 2;
    const int left = ColourBarMarginPx(), right = picture.cols - ColourBarMarginPx() - 1;
    EXPECT_EQ(keyed.at<cv::Vec3b>(y, left), TurboColour(0)) << i;
    EXPECT_EQ(keyed.at<cv::Vec3b>(y, right), TurboColour(1)) << i;
    EXPECT_EQ(keyed.at<cv::Vec3b>(y, 2), cv::Vec3b(255, 255, 255)) << i;  // the white margin
  }
  EXPECT_NE(TurboColour(0), TurboColour(1));
  ColourBar bad;
  bad.ticks = {{1.5, "x"}};
  EXPECT_THROW(WithColourBar(cv::Mat(10, 100, CV_8UC3), bad), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
