// GenerateDataset with DatasetOptions::shard: N shards written into one folder, in any order, are
// byte for byte the folder of one run (docs/scale.md), because every frame's bytes depend only on
// (seed, index) and the splits only on (frames, val_fraction, seed).
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <string>

#include "stereodet/synth/generator.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

// Every regular file under `root`: path relative to root -> bytes.
std::map<std::string, std::string> FolderBytes(const fs::path& root) {
  std::map<std::string, std::string> out;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(root)) {
    if (e.is_regular_file()) out[e.path().lexically_relative(root).string()] = ReadFile(e.path());
  }
  return out;
}

DatasetOptions Tiny(const fs::path& out) {
  DatasetOptions options;
  options.out = out;
  options.frames = 7;
  options.seed = 11;
  options.threads = 2;
  options.progress.stream = nullptr;
  options.synth.width = 96;
  options.synth.height = 32;
  options.synth.lidar_options.azimuth_step_deg = 2.0;
  return options;
}

TEST(GeneratorShardTest, ShardsInAnyOrderGiveTheBytesOfOneRun) {
  const TestTempDir whole("whole"), sharded("sharded");
  DatasetOptions one = Tiny(whole.path());
  one.threads = 1;
  const DatasetSummaryLine s = GenerateDataset(one);
  ASSERT_EQ(s.generated, 7);

  int generated = 0;
  for (const int k : {2, 0, 1}) {  // out of order, one thread count different from the whole run
    DatasetOptions part = Tiny(sharded.path());
    part.shard = Shard{k, 3};
    const DatasetSummaryLine p = GenerateDataset(part);
    EXPECT_EQ(p.generated, static_cast<int>(part.shard.End(7) - part.shard.Begin(7)));
    EXPECT_EQ(p.skipped, 0);
    EXPECT_EQ(p.train + p.val, 7);  // the splits are the whole data set's
    generated += p.generated;
  }
  EXPECT_EQ(generated, 7);
  const std::map<std::string, std::string> a = FolderBytes(whole.path());
  const std::map<std::string, std::string> b = FolderBytes(sharded.path());
  EXPECT_EQ(a.size(), 7u * 7 + 3 + 1);  // seven files a frame, three splits, synth_settings.txt
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [name, bytes] : a) {
    ASSERT_TRUE(b.count(name)) << name;
    EXPECT_TRUE(b.at(name) == bytes) << name << " differs";
  }
}

TEST(GeneratorShardTest, AShardMakesOnlyItsRangeAndResumes) {
  const TestTempDir dir("part");
  DatasetOptions part = Tiny(dir.path());
  part.shard = Shard{1, 2};  // frames 3..6
  EXPECT_EQ(GenerateDataset(part).generated, 4);
  EXPECT_FALSE(fs::exists(dir.path() / "training" / "label_2" / "000002.txt"));
  EXPECT_TRUE(fs::exists(dir.path() / "training" / "label_2" / "000003.txt"));
  EXPECT_TRUE(fs::exists(dir.path() / "training" / "label_2" / "000006.txt"));
  const DatasetSummaryLine again = GenerateDataset(part);
  EXPECT_EQ(again.generated, 0);
  EXPECT_EQ(again.skipped, 4);
  part.shard = Shard{2, 2};
  EXPECT_THROW(GenerateDataset(part), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
