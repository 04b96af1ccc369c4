// The 3D detector end to end on a tiny KITTI-format dataset written by the test (seconds): it
// overfits a few frames and detects its own boxes, resumes bit-identically, writes KITTI files.
#include "stereodet/models/det3d/det3d_train.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>

#include "stereodet/geometry/calibration.h"
#include "stereodet/geometry/iou.h"
#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/models/det3d/det3d_detect.h"
#include "stereodet/models/det3d/gt_database.h"
#include "stereodet/models/models_test_util.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/test_paths.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// Frames with one or two cars (labels in the camera frame), a LiDAR scan of points inside each
// car and a flat ground 1.73 m under the sensor; also a copy of the scans as "stereo" points.
fs::path WriteTinyDataset(const std::string& name, int frames) {
  const fs::path root = ModelsTestDir(name);
  for (const char* folder : {"image_2", "label_2", "calib", "velodyne"}) {
    fs::create_directories(root / "training" / folder);
  }
  fs::create_directories(root / "stereo/velodyne");
  const Calibration calib = KittiLikeCalibration();
  const cv::Mat image(375, 1242, CV_8UC3, cv::Scalar(0, 0, 0));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<std::string> ids;
  for (int i = 0; i < frames; ++i) {
    const std::string id = FrameId(i);
    ids.push_back(id);
    cv::imwrite((root / "training/image_2" / (id + ".png")).string(), image);
    WriteCalibration(root / "training/calib" / (id + ".txt"), calib);
    std::vector<Object> labels;
    for (int k = 0; k < 1 + i % 2; ++k) {
      Object o;
      o.type = "Car";
      o.box3d.h = 1.5;
      o.box3d.w = 1.6;
      o.box3d.l = 3.9;
      o.box3d.location = {-3.0 + 6.0 * k + u(rng), 1.65, 8.0 + 3 * i + 4 * u(rng)};
      o.box3d.rotation_y = (i + k) % 2 == 0 ? 0.2 : 1.7;
      o.alpha = AlphaFromRotationY(o.box3d.rotation_y, o.box3d.location);
      o.box = {100, 100, 200, 200};
      labels.push_back(o);
    }
    WriteObjects(root / "training/label_2" / (id + ".txt"), labels);
    std::vector<VeloPoint> points;
    for (double x = 2; x < 25; x += 0.5) {
      for (double y = -10; y < 10; y += 0.5) {
        points.push_back({float(x + 0.2 * u(rng)), float(y + 0.2 * u(rng)), -1.73f, 0.1f});
      }
    }
    for (const Object& o : labels) {
      const LidarBox b = LidarBoxFromObject(o, calib);
      for (int n = 0; n < 300; ++n) {
        const double along = (u(rng) - 0.5) * b.l, across = (u(rng) - 0.5) * b.w;
        points.push_back({float(b.x + std::cos(b.yaw) * along - std::sin(b.yaw) * across),
                          float(b.y + std::sin(b.yaw) * along + std::cos(b.yaw) * across),
                          float(b.z + (u(rng) - 0.5) * b.h), 0.8f});
      }
    }
    WriteVelodyne(root / "training/velodyne" / (id + ".bin"), points);
    // The "stereo" copy: the same points, reflectance 1 - r, so a test can tell them apart.
    std::vector<VeloPoint> stereo = points;
    for (VeloPoint& p : stereo) p.reflectance = 1.0f - p.reflectance;
    WriteVelodyne(root / "stereo/velodyne" / (id + ".bin"), stereo);
  }
  WriteSplit(root / "ImageSets/train.txt", ids);
  WriteSplit(root / "ImageSets/val.txt", ids);
  return root;
}

TrainDet3dOptions TinyTraining(const fs::path& root, const fs::path& out) {
  TrainDet3dOptions o = TinyTrainingOptions<TrainDet3dOptions>(root, out);
  o.model = TinyDet3dConfig();
  o.batch_size = 2;
  o.warmup_steps = 4;
  o.learning_rate = 5e-3;
  o.augment.enabled = false;
  return o;
}

TEST(Det3dTrainTest, OverfitsAFewFramesAndDetectsItsOwnBoxes) {
  const fs::path root = WriteTinyDataset("det3d_data", 4);
  const fs::path out = ModelsTestDir("det3d_model");
  TrainDet3dOptions options = TinyTraining(root, out);
  options.epochs = 40;
  const TrainDet3dSummary s = TrainDet3d(options);
  EXPECT_EQ(s.frames, 4);
  EXPECT_EQ(s.objects, 6);
  EXPECT_EQ(s.gt_database_objects, 0);  // no augmentation: no GT sampling either
  EXPECT_EQ(s.epochs_done, 40);
  EXPECT_GT(s.auxiliary_parameters, 0);
  EXPECT_LT(s.auxiliary_parameters, s.parameters);
  // The loss fell (first epoch's against the last's, from the CSV log).
  std::ifstream log(out / "train_log.csv");
  std::string header, first, line, last;
  std::getline(log, header);
  std::getline(log, first);
  while (std::getline(log, line)) last = line;
  auto loss = [](const std::string& l) {
    return std::stod(l.substr(l.find(',', l.find(',', l.find(',') + 1) + 1) + 1));
  };
  EXPECT_LT(loss(last), 0.5 * loss(first)) << first << "\n" << last;

  const DetectDet3dOptions d =
      TinyDetectOptions<DetectDet3dOptions>(out, root, root / "detections");
  const DetectSummary ds = DetectDet3d(d);
  EXPECT_EQ(ds.frames, 4);
  EXPECT_TRUE(fs::exists(d.out_dir / "run.json"));
  for (int i = 0; i < 4; ++i) {
    const std::string id = FrameId(i);
    const std::vector<Object> labels = TinyLabels(root, id);
    const std::vector<Object> dets = TinyDetections(d.out_dir, id);
    ASSERT_GE(dets.size(), labels.size()) << id;
    EXPECT_LE(dets.size(), 100u);
    for (const Object& label : labels) {
      const double best = BestConfidentOverlap(
          dets, 0.3, [&](const Object& det) { return BevIou(det.box3d, label.box3d); });
      EXPECT_GT(best, 0.5) << "frame " << id << ": no confident detection of its car";
    }
  }
}

TEST(Det3dTrainTest, ResumeIsBitIdenticalAndFoldersAreGuarded) {
  const fs::path root = WriteTinyDataset("det3d_resume_data", 2);
  const fs::path out = ModelsTestDir("det3d_resume");
  TrainDet3dOptions options = TinyTraining(root, out);
  options.augment.enabled = true;  // seeded per (seed, epoch, frame): resumes exactly
  options.epochs = 2;
  options.max_epochs_this_run = 1;
  EXPECT_EQ(TrainDet3d(options).epochs_done, 1);
  // Into a folder with a model, without --resume or --force: refused.
  options.max_epochs_this_run = 0;
  EXPECT_THROW(TrainDet3d(options), std::invalid_argument);
  options.resume = true;
  EXPECT_EQ(TrainDet3d(options).epochs_run, 1);

  const fs::path straight = ModelsTestDir("det3d_straight");
  TrainDet3dOptions direct = TinyTraining(root, straight);
  direct.augment.enabled = true;
  direct.epochs = 2;
  TrainDet3d(direct);
  // The same weights (LibTorch's archive bytes differ run to run, so compare what they compute:
  // the best 100 boxes and their scores, bit for bit) and the same losses in the log.
  const Det3dModel a = Det3dModel::Load(out), b = Det3dModel::Load(straight);
  const KittiDataset dataset(root);
  const Det3dFrame frame = LoadDet3dFrame(dataset, "", PointSource::kLidar, FrameId(1), {"Car"},
                                          a.config().grid, {}, false);
  const std::vector<Det3dSample> samples = {MakeDet3dSample(frame, a.config(), a.anchors(), false)};
  Det3dDecodeOptions all;
  all.score_threshold = 0.0f;
  const auto da = a.Detect(samples, all), db = b.Detect(samples, all);
  ASSERT_EQ(da[0].size(), 100u);
  ASSERT_EQ(db[0].size(), 100u);
  for (size_t i = 0; i < 100; ++i) {
    EXPECT_EQ(da[0][i].box, db[0][i].box) << i;
    EXPECT_EQ(da[0][i].score, db[0][i].score) << i;
  }
  // GT sampling took part: each frame of this data set gets objects of the other pasted.
  std::vector<Det3dFrame> labelled;
  for (int i = 0; i < 2; ++i) {
    labelled.push_back(LoadDet3dFrame(dataset, "", PointSource::kLidar, FrameId(i), {"Car"},
                                      a.config().grid, {}, true));
  }
  const GtDatabase database = BuildGtDatabase(labelled, 1, PointSource::kLidar, {});
  for (const Det3dFrame& f : labelled) {
    EXPECT_GT(SampleGtObjects(f, database, {}, 1).pasted_per_class[0], 0) << f.id;
  }
  auto losses = [](const std::string& log) {  // the lines without the two timing columns
    std::string kept;
    std::istringstream in(log);
    for (std::string line; std::getline(in, line);) {
      kept += line.substr(0, line.rfind(',', line.rfind(',') - 1)) + "\n";
    }
    return kept;
  };
  EXPECT_EQ(losses(ReadFile(out / "train_log.csv")), losses(ReadFile(straight / "train_log.csv")));

  // Weights of another training are refused.
  fs::copy_file(straight / "model.pt", out / "model.pt", fs::copy_options::overwrite_existing);
  std::string text = ReadFile(out / "model.json");
  text.replace(text.find("\"fnv1a64\": \"") + 12, 4, "0000");
  WriteFileAtomically(out / "model.json", text);
  EXPECT_THROW(Det3dModel::Load(out), std::runtime_error);

  // A stereo model reads its points from --points.
  const fs::path stereo_out = ModelsTestDir("det3d_stereo");
  TrainDet3dOptions stereo = TinyTraining(root, stereo_out);
  stereo.model.input = PointSource::kStereo;
  stereo.epochs = 1;
  EXPECT_THROW(TrainDet3d(stereo), std::invalid_argument);  // no --points
  stereo.points_dir = root / "stereo";
  stereo.augment.enabled = true;
  const TrainDet3dSummary ss = TrainDet3d(stereo);
  EXPECT_EQ(ss.objects, 3);
  EXPECT_EQ(ss.gt_database_objects, 3);
  stereo.force = true;
  stereo.gt_sampling.enabled = false;
  EXPECT_EQ(TrainDet3d(stereo).gt_database_objects, 0);
}

TEST(Det3dTrainTest, GtDatabaseHoldsTheModelsOwnPointsOnly) {
  const fs::path root = WriteTinyDataset("det3d_gtdb_data", 4);
  const KittiDataset dataset(root);
  const Det3dConfig config = TinyDet3dConfig();
  std::vector<Det3dFrame> lidar, stereo;
  for (int i = 0; i < 4; ++i) {
    lidar.push_back(LoadDet3dFrame(dataset, "", PointSource::kLidar, FrameId(i), {"Car"},
                                   config.grid, {}, true));
    stereo.push_back(LoadDet3dFrame(dataset, root / "stereo", PointSource::kStereo, FrameId(i),
                                    {"Car"}, config.grid, {}, true));
  }
  const GtDatabase lidar_db = BuildGtDatabase(lidar, 1, PointSource::kLidar, {});
  const GtDatabase stereo_db = BuildGtDatabase(stereo, 1, PointSource::kStereo, {});
  EXPECT_EQ(lidar_db.ObjectCount(), 6);
  EXPECT_EQ(stereo_db.ObjectCount(), 6);
  EXPECT_GE(lidar_db.PointCount(), 6 * 300);
  for (const GtObject& o : lidar_db.objects_by_class[0]) {
    for (const VeloPoint& p : o.points) EXPECT_TRUE(p.reflectance == 0.8f || p.reflectance == 0.1f);
  }
  for (const GtObject& o : stereo_db.objects_by_class[0]) {
    for (const VeloPoint& p : o.points) {
      EXPECT_TRUE(p.reflectance == 1.0f - 0.8f || p.reflectance == 1.0f - 0.1f);
    }
  }
  // Pasting a stereo object into a stereo frame adds stereo points only.
  const GtSamplingResult r = SampleGtObjects(stereo[0], stereo_db, {}, 3);
  EXPECT_GT(r.pasted_per_class[0], 0);
  for (const VeloPoint& p : r.frame.points) {
    EXPECT_TRUE(p.reflectance == 1.0f - 0.8f || p.reflectance == 1.0f - 0.1f);
  }
}

TEST(Det3dTrainTest, LoadDropsPointsOutsideTheGridAndPillarsDoNotChange) {
  const fs::path root = WriteTinyDataset("det3d_crop_data", 2);
  const KittiDataset dataset(root);
  BevGridOptions grid;  // 12.8 x 12.8 m: cuts the tiny scans (x 2..25 m, y -10..10 m)
  grid.max_x_m = 12.8;
  grid.min_y_m = -6.4;
  grid.max_y_m = 6.4;
  PointFilterOptions keep_all;
  keep_all.crop_to_grid = false;
  for (PointSource source : {PointSource::kLidar, PointSource::kStereo}) {
    for (int i = 0; i < 2; ++i) {
      const Det3dFrame all = LoadDet3dFrame(dataset, root / "stereo", source, FrameId(i), {"Car"},
                                            grid, keep_all, true);
      const Det3dFrame cropped =
          LoadDet3dFrame(dataset, root / "stereo", source, FrameId(i), {"Car"}, grid, {}, true);
      size_t inside = 0;
      for (const VeloPoint& p : all.points) inside += grid.Contains(p.x, p.y, p.z);
      EXPECT_EQ(cropped.points.size(), inside);
      EXPECT_LT(inside, all.points.size());  // the grid cuts the scan
      EXPECT_GT(inside, 100u);
      for (const VeloPoint& p : cropped.points) EXPECT_TRUE(grid.Contains(p.x, p.y, p.z));
      // The memory is given back too, not only the points dropped (libstdc++ honours
      // shrink_to_fit).
      EXPECT_EQ(cropped.points.capacity(), cropped.points.size());
      EXPECT_EQ(cropped.boxes, all.boxes);
      const Pillars a = Pillarize(all.points, grid), b = Pillarize(cropped.points, grid);
      EXPECT_EQ(a.cell, b.cell);
      EXPECT_EQ(a.features, b.features);
      EXPECT_EQ(a.num_pillars, b.num_pillars);
    }
  }
}

// The checkpoint is tied to its training run and its model, as the SSD's is: --resume refuses one
// copied from another folder, naming the difference, and leaves the folder as it was.
TEST(Det3dTrainTest, ResumeRefusesACheckpointOfAnotherRunOrModel) {
  const fs::path root = WriteTinyDataset("det3d_tie_data", 2);
  auto half_train = [&](const std::string& name, int base_channels) {
    TrainDet3dOptions options = TinyTraining(root, ModelsTestDir(name));
    options.model.base_channels = base_channels;
    options.epochs = 2;
    options.max_epochs_this_run = 1;
    TrainDet3d(options);
    options.max_epochs_this_run = 0;
    options.resume = true;
    return options;
  };
  const TrainDet3dOptions mine = half_train("det3d_tie_mine", 16);
  const TrainDet3dOptions other_run = half_train("det3d_tie_other_run", 16);
  const TrainDet3dOptions other_model = half_train("det3d_tie_other_model", 8);
  EXPECT_NE(ReadFile(mine.out_dir / "model.json").find("\"training_run\": \""), std::string::npos);
  const fs::path checkpoint = mine.out_dir / "checkpoint.pt";
  const std::string own = ReadFile(checkpoint), config = ReadFile(mine.out_dir / "model.json");

  fs::copy_file(other_run.out_dir / "checkpoint.pt", checkpoint,
                fs::copy_options::overwrite_existing);
  EXPECT_THAT(
      [&] { TrainDet3d(mine); },
      ThrowsMessage<std::runtime_error>(HasSubstr("checkpoint.pt is from another training run (")));
  EXPECT_EQ(ReadFile(mine.out_dir / "model.json"), config);

  fs::copy_file(other_model.out_dir / "checkpoint.pt", checkpoint,
                fs::copy_options::overwrite_existing);
  EXPECT_THAT([&] { TrainDet3d(mine); },
              ThrowsMessage<std::runtime_error>(HasSubstr(
                  "checkpoint.pt was written for another model: base_channels: 8 here, 16 in the "
                  "model")));
  EXPECT_EQ(ReadFile(mine.out_dir / "model.json"), config);

  // Its own checkpoint resumes.
  WriteFileAtomically(checkpoint, own);
  EXPECT_EQ(TrainDet3d(mine).epochs_done, 2);
}

}  // namespace
}  // namespace stereodet
