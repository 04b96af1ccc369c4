// Test support for the models tests (include from *_test.cc only).
#ifndef STEREODET_MODELS_MODELS_TEST_UTIL_H_
#define STEREODET_MODELS_MODELS_TEST_UTIL_H_

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "stereodet/geometry/calibration.h"
#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/models/config_test_util.h"
#include "stereodet/models/det3d/det3d_model.h"
#include "stereodet/models/rpn/rpn_model.h"
#include "stereodet/models/ssd/ssd_model.h"
#include "stereodet/util/test_paths.h"

namespace stereodet {

// An empty folder `name` under the build tree's models_test_tmp/ (removed first if it exists).
// The models tests run as one program (one CTest test), so fixed names do not race.
inline std::filesystem::path ModelsTestDir(const std::string& name) {
  const std::filesystem::path dir = TestBinaryDir() / "models_test_tmp" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// Frames for the image families' training tests, in the KITTI layout under models_test_tmp/NAME
// (image_2, image_3, label_2, calib; ImageSets/train.txt and val.txt list every frame): `frames`
// frames of `size` px, dark noise 0..`background_max`, one bright textured "car" (`car_min`..255)
// at `car(i)` in frame i, 8 px further left in the right image so that stereo finds it, labelled
// Car (1.5 x 1.6 x 3.9 m, 10 m ahead), KittiLikeCalibration. Drawn from a generator of its own
// (cv::RNG(5)): cv::randu would use OpenCV's process-wide one, and the frames would depend on the
// tests run before.
inline std::filesystem::path WriteTinyImageDataset(const std::string& name, int frames,
                                                   cv::Size size, int background_max, int car_min,
                                                   const std::function<cv::Rect(int)>& car) {
  const std::filesystem::path root = ModelsTestDir(name);
  cv::RNG rng(5);
  std::vector<std::string> ids;
  for (const char* folder : {"image_2", "image_3", "label_2", "calib"}) {
    std::filesystem::create_directories(root / "training" / folder);
  }
  for (int i = 0; i < frames; ++i) {
    const std::string id = FrameId(i);
    ids.push_back(id);
    cv::Mat left(size, CV_8UC3);
    rng.fill(left, cv::RNG::UNIFORM, 0, background_max);
    const cv::Rect box = car(i);
    cv::Mat patch(box.size(), CV_8UC3);
    rng.fill(patch, cv::RNG::UNIFORM, car_min, 255);
    const cv::Mat right = left.clone();
    patch.copyTo(left(box));
    patch.copyTo(right(box - cv::Point(8, 0)));
    cv::imwrite((root / "training/image_2" / (id + ".png")).string(), left);
    cv::imwrite((root / "training/image_3" / (id + ".png")).string(), right);
    WriteCalibration(root / "training/calib" / (id + ".txt"), KittiLikeCalibration());
    Object label;
    label.type = "Car";
    label.box = {double(box.x), double(box.y), double(box.br().x), double(box.br().y)};
    label.box3d.h = 1.5;
    label.box3d.w = 1.6;
    label.box3d.l = 3.9;
    label.box3d.location = {0, 1.6, 10};
    WriteObjects(root / "training/label_2" / (id + ".txt"), {label});
  }
  WriteSplit(root / "ImageSets/train.txt", ids);
  WriteSplit(root / "ImageSets/val.txt", ids);
  return root;
}

// A family's training options (TrainSsdOptions, TrainRpnOptions, TrainDet3dOptions) for the
// KITTI-layout `root` into the model folder `out`, on one thread (one thread: OpenMP barriers spin
// badly on a loaded 2-core machine), quiet; each family's tests add their tiny model.
template <typename TrainOptions>
TrainOptions TinyTrainingOptions(const std::filesystem::path& root,
                                 const std::filesystem::path& out) {
  TrainOptions o;
  o.data_root = root;
  o.out_dir = out;
  o.threads = 1;
  o.progress.stream = nullptr;
  return o;
}

// A family's detect options (DetectSsdOptions, DetectRpnOptions, DetectDet3dOptions) for the model
// in `model` over the KITTI-layout `root` (its val split), into `out`, on one thread, quiet.
template <typename DetectOptions>
DetectOptions TinyDetectOptions(const std::filesystem::path& model,
                                const std::filesystem::path& root,
                                const std::filesystem::path& out) {
  DetectOptions o;
  o.model_dir = model;
  o.data_root = root;
  o.out_dir = out;
  o.threads = 1;
  o.progress.stream = nullptr;
  return o;
}

// The labels of frame `id` of a tiny dataset, and the detections a detect command wrote for it.
inline std::vector<Object> TinyLabels(const std::filesystem::path& root, const std::string& id) {
  return ReadObjects(root / "training/label_2" / (id + ".txt")).objects;
}
inline std::vector<Object> TinyDetections(const std::filesystem::path& dir, const std::string& id) {
  return ReadObjects(dir / (id + ".txt"), {.kind = ObjectFileKind::kDetection}).objects;
}

// The largest `overlap(detection)` over the detections scoring at least `min_score` (0 when
// none does); every detection must have a score in [0, 1] (a test failure otherwise).
template <typename Overlap>
double BestConfidentOverlap(const std::vector<Object>& detections, double min_score,
                            Overlap overlap) {
  double best = 0;
  for (const Object& det : detections) {
    EXPECT_TRUE(det.score.has_value() && *det.score >= 0.0 && *det.score <= 1.0)
        << "a detection without a score in [0, 1]";
    if (det.score.value_or(0.0) < min_score) continue;
    best = std::max(best, overlap(det));
  }
  return best;
}

}  // namespace stereodet

#endif  // STEREODET_MODELS_MODELS_TEST_UTIL_H_
