#include "stereodet/models/ssd/ssd_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "stereodet/util/test_paths.h"

namespace stereodet {
namespace {

std::filesystem::path TempDir(const std::string& name) {
  const std::filesystem::path dir = ::stereodet::TestBinaryDir() / "models_test_tmp" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

SsdConfig SmallConfig(InputEncoding encoding) {
  SsdConfig config;
  config.encoding = encoding;
  config.boxes.input_width = 124;
  config.boxes.input_height = 38;
  config.base_channels = 4;
  return config;
}

// A 248 x 76 frame (twice the network size): dark, with one bright "car" whose height codes are
// high, everywhere else the codes are low. Colour and height agree, so any augmentation must keep
// them so.
constexpr int kFullW = 248, kFullH = 76;
const cv::Rect kCar(150, 30, 60, 30);

TrainingFrame CarFrame(const std::filesystem::path& dir, const std::string& id) {
  cv::Mat bgr(kFullH, kFullW, CV_8UC3, cv::Scalar(20, 20, 20));
  bgr(kCar).setTo(cv::Scalar(250, 250, 250));
  const std::filesystem::path path = dir / (id + ".png");
  cv::imwrite(path.string(), bgr);
  cv::Mat code(kFullH / 2, kFullW / 2, CV_16UC1, cv::Scalar(10));
  code(cv::Rect(kCar.x / 2, kCar.y / 2, kCar.width / 2, kCar.height / 2)).setTo(cv::Scalar(500));
  TrainingFrame frame;
  frame.id = id;
  frame.image_path = path;
  frame.targets = {
      {Box2D{double(kCar.x), double(kCar.y), double(kCar.br().x), double(kCar.br().y)}, 1}};
  frame.height_code = code;
  return frame;
}

TEST(SsdDataTest, TargetsFromLabels) {
  Object car, van, truck, small_car;
  car.type = "Car";
  car.box = {0, 0, 50, 40};
  van.type = "Van";
  van.box = {0, 0, 50, 40};
  truck.type = "Truck";
  truck.box = {0, 0, 50, 40};
  small_car = car;
  small_car.box = {0, 0, 10, 10};
  Object cyclist = car;
  cyclist.type = "Cyclist";
  const SsdDataOptions defaults;  // ignores DontCare, Van and Person_sitting; below 20 px
  const std::vector<TargetBox> t = TargetsFromLabels({car, van, truck, small_car, cyclist},
                                                     {"Car", "Pedestrian", "Cyclist"}, defaults);
  ASSERT_EQ(t.size(), 4u);  // the truck is background
  EXPECT_EQ(t[0].label, 1);
  EXPECT_EQ(t[1].label, kIgnoreLabel);
  EXPECT_EQ(t[2].label, kIgnoreLabel);  // below 20 px
  EXPECT_EQ(t[3].label, 3);
}

TEST(SsdDataTest, AugmentationKeepsHeightAndBoxesWithTheImage) {
  const auto dir = TempDir("augment");
  const SsdConfig config = SmallConfig(InputEncoding::kRgbhLearned);
  SsdDataOptions options;
  options.augment.min_zoom = 0.7;
  options.augment.max_zoom = 1.5;
  // Geometry only here (jitter has its own test); padding is grey 128, so threshold colour at 0.7.
  options.augment.brightness = options.augment.contrast = options.augment.saturation = 0.0;
  const SsdTrainingData data({CarFrame(dir, "000000")}, config, options);
  int flipped_or_zoomed = 0;
  for (uint64_t seed = 0; seed < 40; ++seed) {
    const TrainSample s = data.Sample(0, seed);
    ASSERT_EQ(s.input.channels, 4);
    const int w = s.input.cols, h = s.input.rows;
    // Masks: red channel bright vs height code high.
    int both = 0, either = 0;
    int min_u = w, max_u = -1, min_v = h, max_v = -1;
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const bool colour = s.input.At(0, v, u) > 0.7f;
        const bool height = s.input.At(3, v, u) > 0.5f;
        both += colour && height;
        either += colour || height;
        if (colour) {
          min_u = std::min(min_u, u), max_u = std::max(max_u, u);
          min_v = std::min(min_v, v), max_v = std::max(max_v, v);
        }
      }
    }
    if (either == 0) continue;  // the car was cropped away
    EXPECT_GT(static_cast<double>(both) / either, 0.75) << "seed " << seed;
    // The one target is the bright region (when it is fully visible).
    ASSERT_FALSE(s.targets.empty()) << "seed " << seed;
    const Box2D& box = s.targets[0].box;
    if (s.targets[0].label == 1 && min_u > 0 && max_u < w - 1 && min_v > 0 && max_v < h - 1) {
      EXPECT_NEAR(box.left, min_u, 1.5) << "seed " << seed;
      EXPECT_NEAR(box.right, max_u + 1, 1.5) << "seed " << seed;
      EXPECT_NEAR(box.top, min_v, 1.5) << "seed " << seed;
      EXPECT_NEAR(box.bottom, max_v + 1, 1.5) << "seed " << seed;
      // The car sits right of centre; a flip moves it left.
      if (box.right < w / 2.0 || std::abs(box.Width() - 30.0) > 2.0) ++flipped_or_zoomed;
    }
  }
  EXPECT_GT(flipped_or_zoomed, 5);  // the augmentation did something
}

TEST(SsdDataTest, JitterTouchesColourOnlyAndSeedsRepeat) {
  const auto dir = TempDir("jitter");
  const SsdConfig config = SmallConfig(InputEncoding::kRgbhLearned);
  SsdDataOptions options;
  options.augment.min_zoom = options.augment.max_zoom = 1.0;  // no geometric change
  options.augment.flip_probability = 0.0;
  const TrainingFrame frame = CarFrame(dir, "000000");
  const SsdTrainingData data({frame}, config, options);
  const TrainSample a = data.Sample(0, 1), b = data.Sample(0, 1), c = data.Sample(0, 2);
  EXPECT_EQ(a.input.data, b.input.data);
  EXPECT_NE(a.input.data, c.input.data);
  // Height plane: exactly the cached codes / 511.
  for (int v = 0; v < a.input.rows; ++v) {
    for (int u = 0; u < a.input.cols; ++u) {
      ASSERT_FLOAT_EQ(a.input.At(3, v, u), frame.height_code.at<uint16_t>(v, u) / 511.0f);
    }
  }
  ASSERT_EQ(a.targets.size(), 1u);
  EXPECT_DOUBLE_EQ(a.targets[0].box.left, kCar.x / 2.0);
  EXPECT_GE(a.match.num_positive, 1);
}

TEST(SsdDataTest, NoAugmentationMatchesTheInferencePath) {
  const auto dir = TempDir("inference");
  const SsdConfig config = SmallConfig(InputEncoding::kRgb);
  SsdDataOptions options;
  options.augment.enabled = false;
  const TrainingFrame frame = CarFrame(dir, "000000");
  const SsdTrainingData data({frame}, config, options);
  const PlanarImage expected =
      PrepareNetworkInput(cv::imread(frame.image_path.string()), cv::Mat(), config);
  EXPECT_EQ(data.Sample(0, 5).input.data, expected.data);
}

TEST(SsdDataTest, EpochOrderIsAPermutationThatChanges) {
  const std::vector<int> a = EpochOrder(50, 1, 0), b = EpochOrder(50, 1, 1);
  EXPECT_EQ(std::set<int>(a.begin(), a.end()).size(), 50u);
  EXPECT_EQ(*std::max_element(a.begin(), a.end()), 49);
  EXPECT_NE(a, b);
  EXPECT_EQ(a, EpochOrder(50, 1, 0));
  EXPECT_NE(SampleSeed(1, 0, 3), SampleSeed(1, 1, 3));
}

TEST(SsdDataTest, LoaderYieldsEveryFrameOnceInOrder) {
  const auto dir = TempDir("loader");
  const SsdConfig config = SmallConfig(InputEncoding::kRgb);
  std::vector<TrainingFrame> frames;
  for (int i = 0; i < 7; ++i) frames.push_back(CarFrame(dir, FrameId(i)));
  const SsdTrainingData data(std::move(frames), config, {});
  const std::vector<int> order = EpochOrder(7, 3, 0);
  BatchLoader loader(data, order, 3, 3, 0, 1);
  EXPECT_EQ(loader.num_batches(), 3);
  std::vector<int> sizes;
  int b = 0;
  while (auto batch = loader.Next()) {
    sizes.push_back(batch->batch_size);
    // Same content as sampling directly with the documented seeds.
    const int first = order[3 * b];
    const TrainSample expected = data.Sample(first, SampleSeed(3, 0, first));
    const size_t n = expected.input.data.size();
    EXPECT_TRUE(
        std::equal(expected.input.data.begin(), expected.input.data.end(), batch->images.begin()));
    EXPECT_EQ(batch->images.size(), n * batch->batch_size);
    EXPECT_EQ(batch->labels.size(), data.default_boxes().size() * batch->batch_size);
    ++b;
  }
  EXPECT_EQ(sizes, (std::vector<int>{3, 3, 1}));
}

TEST(SsdDataTest, LoaderRethrowsReadErrorsAndStopsEarlyCleanly) {
  const auto dir = TempDir("loader_error");
  const SsdConfig config = SmallConfig(InputEncoding::kRgb);
  std::vector<TrainingFrame> frames = {CarFrame(dir, "000000"), CarFrame(dir, "000001")};
  frames[1].image_path = dir / "missing.png";
  const SsdTrainingData data(std::move(frames), config, {});
  {
    BatchLoader loader(data, {0, 1}, 1, 1, 0);
    EXPECT_TRUE(loader.Next().has_value());
    EXPECT_THROW(loader.Next(), std::runtime_error);
  }
  {
    // Destroyed while the producer may still be waiting on a full queue.
    BatchLoader loader(data, {0, 0, 0, 0}, 1, 1, 0, 1);
  }
}

}  // namespace
}  // namespace stereodet
