// EncodeDataset with EncodeDatasetOptions::shard: shards running at once into one folder write the
// files of one run, and OUT/run.json lists every frame (docs/scale.md).
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "stereodet/kitti/dataset.h"
#include "stereodet/stereo/dataset_encoder.h"
#include "stereodet/stereo/planar_scene.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

std::map<std::string, std::string> FolderBytes(const fs::path& root) {
  std::map<std::string, std::string> out;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(root)) {
    if (e.is_regular_file()) out[e.path().lexically_relative(root).string()] = ReadFile(e.path());
  }
  return out;
}

EncodeDatasetOptions Small() {
  EncodeDatasetOptions options;
  options.stereo.disparity.num_disparities = 64;
  options.outputs.points = true;
  options.num_threads = 1;
  options.progress.stream = nullptr;
  return options;
}

TEST(DatasetEncoderShardTest, ShardsAtOnceIntoOneFolderAreOneRun) {
  const TestTempDir dir;
  PlanarSceneDatasetOptions scenes;
  scenes.frames = 5;
  scenes.width_px = 256;
  scenes.height_px = 96;
  const std::vector<std::string> ids = WritePlanarSceneDataset(dir / "data", scenes);
  const KittiDataset dataset(dir / "data", "training");
  const EncodeDatasetResult whole = EncodeDataset(dataset, ids, dir / "whole", Small());
  ASSERT_EQ(whole.encoded, 5);

  std::vector<std::thread> threads;
  std::vector<EncodeDatasetResult> parts(3);
  for (int k = 0; k < 3; ++k) {
    threads.emplace_back([&, k] {
      EncodeDatasetOptions options = Small();
      options.shard = Shard{k, 3};
      parts[k] = EncodeDataset(dataset, ids, dir / "sharded", options);
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(parts[0].encoded + parts[1].encoded + parts[2].encoded, 5);
  EXPECT_EQ(parts[2].encoded, 2);  // frames 3 and 4

  const std::map<std::string, std::string> a = FolderBytes(dir / "whole");
  const std::map<std::string, std::string> b = FolderBytes(dir / "sharded");
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [name, bytes] : a) {
    ASSERT_TRUE(b.count(name)) << name;
    EXPECT_TRUE(bytes == b.at(name)) << name << " differs";  // run.json too: same frames
  }
  EXPECT_EQ(ReadRunManifest(dir / "sharded")->frames.size(), 5u);

  // A shard resumed finds its frames done; a shard cannot force.
  EncodeDatasetOptions again = Small();
  again.shard = Shard{1, 3};
  EXPECT_EQ(EncodeDataset(dataset, ids, dir / "sharded", again).skipped, 2);
  again.force = true;
  EXPECT_THROW(EncodeDataset(dataset, ids, dir / "sharded", again), std::invalid_argument);
}

// With --evaluate, disparity_evaluation.json is the folder's: the shards, in any order, leave the
// file of one run (every frame, the pooled figures of all), not the last shard's frames.
TEST(DatasetEncoderShardTest, ShardedEvaluationIsTheWholeRunsFile) {
  const TestTempDir dir;
  PlanarSceneDatasetOptions scenes;
  scenes.frames = 5;
  scenes.width_px = 256;
  scenes.height_px = 96;
  const std::vector<std::string> ids = WritePlanarSceneDataset(dir / "data", scenes);
  const KittiDataset dataset(dir / "data", "training");
  EncodeDatasetOptions options = Small();
  options.outputs.points = false;
  options.outputs.disparity = true;
  options.evaluate = true;
  EncodeDataset(dataset, ids, dir / "whole", options);
  for (const int k : {2, 0, 1}) {
    EncodeDatasetOptions part = options;
    part.shard = Shard{k, 3};
    EncodeDataset(dataset, ids, dir / "sharded", part);
  }
  const std::string whole = ReadFile(dir / "whole" / kDisparityEvaluationFile);
  EXPECT_NE(whole.find("\"frames\": 5"), std::string::npos) << whole;
  EXPECT_EQ(ReadFile(dir / "sharded" / kDisparityEvaluationFile), whole);
}

}  // namespace
}  // namespace stereodet
