// Non-finite network outputs (network_output.h): CheckFiniteRows by hand, and for each family a
// model whose weights are finite (so opening it succeeds) but overflow the network: Detector::Run
// names the model and the frame instead of giving empty or arbitrary boxes.
#include "stereodet/models/network_output.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <filesystem>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "stereodet/geometry/calibration.h"
#include "stereodet/models/det3d/det3d_model.h"
#include "stereodet/models/detector.h"
#include "stereodet/models/device_internal.h"
#include "stereodet/models/models_test_util.h"
#include "stereodet/models/rpn/rpn_model.h"
#include "stereodet/models/ssd/ssd_model.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/hash.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// The batch index CheckFiniteRows reports for `t`, or -1 when it throws nothing.
int64_t Reported(const torch::Tensor& t, const std::vector<size_t>& input_of_row = {}) {
  try {
    internal::CheckFiniteRows(t, "scores", input_of_row);
  } catch (const NonFiniteOutputError& e) {
    EXPECT_EQ(e.output(), "scores");
    return static_cast<int64_t>(e.batch_index());
  }
  return -1;
}

TEST(NetworkOutputTest, CheckFiniteRowsNamesTheFirstInputWithANaNOrAnInf) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  torch::Tensor t = torch::zeros({4, 3, 2});
  EXPECT_EQ(Reported(t), -1);
  EXPECT_EQ(Reported(torch::zeros({0, 5})), -1);  // an empty batch has nothing to check
  t[2][1][0] = nan;
  EXPECT_EQ(Reported(t), 2);
  t[3][0][1] = -inf;
  EXPECT_EQ(Reported(t), 2);  // the first one
  t[1][2][1] = inf;
  EXPECT_EQ(Reported(t), 1);
  // Rows of several inputs (regions of interest, image by image): row 3 is input 1's.
  torch::Tensor rois = torch::ones({5, 4});
  rois[3][2] = nan;
  EXPECT_EQ(Reported(rois, {0, 0, 1, 1, 2}), 1);
  try {
    internal::CheckFiniteRows(rois, "class scores", {0, 0, 1, 1, 2});
    ADD_FAILURE() << "no exception";
  } catch (const NonFiniteOutputError& e) {
    EXPECT_STREQ(e.what(),
                 "the network's class scores for input 1 of the batch are not finite (NaN or inf)");
  }
}

// Writes every floating tensor of `in` (a model.pt archive, nested by submodule) to `out`
// multiplied by `factor`.
void ScaleArchive(torch::serialize::InputArchive& in, torch::serialize::OutputArchive& out,
                  double factor) {
  for (const std::string& key : in.keys()) {
    torch::Tensor t;
    if (in.try_read(key, t)) {
      out.write(key, t.is_floating_point() ? t * factor : t);
      continue;
    }
    torch::serialize::InputArchive in_sub;
    ASSERT_TRUE(in.try_read(key, in_sub)) << key;
    torch::serialize::OutputArchive out_sub;
    ScaleArchive(in_sub, out_sub, factor);
    out.write(key, out_sub);
  }
}

// Makes the model folder `dir` hold weights that are finite but 1e30 times its own, with model.json
// recording their hash: a model that opens (no NaN or inf in it) and overflows on any input.
void OverflowWeights(const fs::path& dir) {
  const fs::path weights = dir / "model.pt";
  const std::string old_hash = HashHex(Fnv1a64(ReadFile(weights)));
  torch::serialize::InputArchive in;
  in.load_from(weights.string());
  torch::serialize::OutputArchive out;
  ScaleArchive(in, out, 1e30);
  out.save_to(weights.string());
  const std::string new_hash = HashHex(Fnv1a64(ReadFile(weights)));
  std::string json = ReadFile(dir / "model.json");
  const size_t at = json.find(old_hash);
  ASSERT_NE(at, std::string::npos);
  json.replace(at, old_hash.size(), new_hash);
  WriteFileAtomically(dir / "model.json", json);
}

cv::Mat NoiseImage(int rows, int cols, unsigned seed) {
  cv::Mat image(rows, cols, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

// A saved model of `family_input` whose weights overflow (OverflowWeights), and a frame for it.
struct OverflowCase {
  std::string family_input;  // "ssd rgb"
  std::function<void(const fs::path&)> save;
  StereoFrame frame;
};

TEST(NetworkOutputTest, EveryFamilyRefusesAnOverflowingNetworkNamingTheFrame) {
  SetTorchThreads(1);
  StereoFrame image;
  image.left = NoiseImage(96, 128, 1);
  StereoFrame scan;
  scan.image_size = cv::Size(1242, 375);
  scan.calib = KittiLikeCalibration();
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> x(2, 25), y(-10, 10), z(-1.5f, 1);
  scan.points.emplace();
  for (int i = 0; i < 500; ++i) scan.points->push_back({x(rng), y(rng), z(rng), 0.5f});
  const std::vector<OverflowCase> cases = {
      {"ssd rgb", [](const fs::path& dir) { SsdModel(TinySsdConfig(), 3).Save(dir); }, image},
      {"rpn rgb", [](const fs::path& dir) { RpnModel(TinyRpnConfig(), 3).Save(dir); }, image},
      {"det3d lidar", [](const fs::path& dir) { Det3dModel(TinyDet3dConfig(), 3).Save(dir); },
       scan}};
  for (OverflowCase c : cases) {
    const fs::path dir = ModelsTestDir("overflow");
    c.save(dir);
    OverflowWeights(dir);
    Detector detector = Detector::Open(dir);  // finite weights: opening succeeds
    c.frame.id = "000007";
    EXPECT_THAT([&] { detector.Detect(c.frame); },
                ::testing::ThrowsMessage<std::runtime_error>(HasSubstr(
                    "frame 000007: " + dir.string() + " (" + c.family_input + "): the network's ")))
        << c.family_input;
    EXPECT_THAT([&] { detector.Detect(c.frame); }, ::testing::ThrowsMessage<std::runtime_error>(
                                                       HasSubstr("are not finite (NaN or inf)")));
  }
}

}  // namespace
}  // namespace stereodet
