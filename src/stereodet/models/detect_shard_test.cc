// The folder-level pieces of sharded detection (no network): the shard's frames, the shard
// record, and `detect merge` on shard folders written by hand. DetectSsdShardTest
// (ssd_train_test.cc) runs real shards of a trained model.
#include "stereodet/models/detect_shard.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/test_paths.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

fs::path TempDir(const std::string& name) {
  const fs::path dir = ::stereodet::TestBinaryDir() / "models_test_tmp" / "detect_shard" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<std::string> Ids(int n) {
  std::vector<std::string> ids;
  for (int i = 0; i < n; ++i) ids.push_back(std::to_string(1000 + 7 * i));
  return ids;
}

// One frame's detection file: different bytes for every id.
std::string FileFor(const std::string& id) {
  return "Car -1 -1 -10 1 2 " + id + " 40 -1 -1 -1 -1000 -1000 -1000 -10 0.5\n";
}

RunManifest Manifest(const std::vector<std::string>& ids, const std::string& settings) {
  RunManifest m;
  m.tool = "detect ssd";
  m.version = "test";
  m.command_line = "stereodet detect ssd ...";
  m.inputs = {{"model", "/m"}, {"data", "/d"}, {"subset", "training"}, {"split", "val"}};
  m.settings_json = settings;
  for (const std::string& id : ids) m.frames.emplace_back(id, HashHex(Fnv1a64(FileFor(id))));
  return m;
}

// What DetectSsd writes for the whole list (no --shard) or one shard of it (0/1 included).
void WriteRun(const fs::path& dir, const std::vector<std::string>& all, const Shard& shard,
              const std::string& settings = R"({"score_threshold": 0.01})", int batch = 2) {
  fs::create_directories(dir);
  const std::vector<std::string> ids = ShardFrames(all, shard, batch);
  for (const std::string& id : ids) WriteFileAtomically(dir / (id + ".txt"), FileFor(id));
  WriteRunManifest(dir, Manifest(ids, settings));
  if (shard.Recorded()) {
    WriteDetectShardRecord(
        dir, {"detect ssd", shard, batch, static_cast<int64_t>(all.size()), FrameListHash(all)});
  }
}

std::map<std::string, std::string> FolderBytes(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    out[e.path().filename().string()] = ReadFile(e.path());
  }
  return out;
}

std::string MessageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no exception";
}

TEST(DetectShardTest, ShardFramesAreContiguousRangesOfWholeBatchesThatCoverTheList) {
  const std::vector<std::string> ids = Ids(5);
  // Batches of 1: floor(K * 5 / 3) = 0, 1, 3, 5.
  EXPECT_EQ(ShardFrames(ids, {0, 3}, 1), std::vector<std::string>({ids[0]}));
  EXPECT_EQ(ShardFrames(ids, {1, 3}, 1), std::vector<std::string>({ids[1], ids[2]}));
  EXPECT_EQ(ShardFrames(ids, {2, 3}, 1), std::vector<std::string>({ids[3], ids[4]}));
  // Batches of 2 (0-1, 2-3, 4): batches floor(K * 3 / 2) = 0, 1, 3.
  EXPECT_EQ(ShardFrames(ids, {0, 2}, 2), std::vector<std::string>({ids[0], ids[1]}));
  EXPECT_EQ(ShardFrames(ids, {1, 2}, 2), std::vector<std::string>({ids[2], ids[3], ids[4]}));
  EXPECT_EQ(ShardFrames(ids, {}, 3), ids);
  EXPECT_TRUE(ShardFrames(ids, {0, 8}, 1).empty());  // more shards than batches: some are empty
  EXPECT_TRUE(ShardFrames(ids, {0, 2}, 8).empty());
  EXPECT_EQ(ShardFrames(ids, {1, 2}, 8), ids);
  EXPECT_THROW(ShardFrames(ids, {3, 3}, 1), std::invalid_argument);
  EXPECT_THROW(ShardFrames(ids, {0, 3}, 0), std::invalid_argument);
  // Property: for every list length, batch size and count, the shards in order are the list, and
  // every shard but the last starts and ends on a batch boundary of the whole list.
  for (int n = 0; n <= 9; ++n) {
    const std::vector<std::string> list = Ids(n);
    for (int batch = 1; batch <= 4; ++batch) {
      for (int count = 1; count <= 6; ++count) {
        std::vector<std::string> joined;
        for (int k = 0; k < count; ++k) {
          const std::vector<std::string> part = ShardFrames(list, {k, count}, batch);
          if (joined.size() < list.size()) {
            EXPECT_EQ(joined.size() % batch, 0u);
          }
          joined.insert(joined.end(), part.begin(), part.end());
        }
        EXPECT_EQ(joined, list) << n << " frames, batch " << batch << ", " << count << " shards";
      }
    }
  }
}

TEST(DetectShardTest, FrameListHashIsFnvOfTheIdsEachEndedByANewline) {
  EXPECT_EQ(FrameListHash({}), HashHex(kFnv1a64Offset));
  EXPECT_EQ(FrameListHash({"000001", "000002"}), HashHex(Fnv1a64("000001\n000002\n")));
  // Order and boundaries count.
  EXPECT_NE(FrameListHash({"000002", "000001"}), FrameListHash({"000001", "000002"}));
  EXPECT_NE(FrameListHash({"0000010", "00002"}), FrameListHash({"000001", "000002"}));
}

TEST(DetectShardTest, RecordRoundTripsAndABadOneNamesTheField) {
  const fs::path dir = TempDir("record");
  const DetectShardRecord record{"detect det3d", {2, 5}, 4, 1234, "0123456789abcdef"};
  WriteDetectShardRecord(dir, record);
  const DetectShardRecord back = ReadDetectShardRecord(dir);
  EXPECT_EQ(back.tool, record.tool);
  EXPECT_EQ(back.shard.index, 2);
  EXPECT_EQ(back.shard.count, 5);
  EXPECT_EQ(back.batch_size, 4);
  EXPECT_EQ(back.list_frames, 1234);
  EXPECT_EQ(back.list_hash, record.list_hash);

  WriteFileAtomically(dir / kDetectShardFile,
                      R"({"format": 1, "tool": "detect ssd", "shard": "5/5", "batch_size": 1,)"
                      R"( "list_frames": 1,)"
                      R"( "list_fnv1a64": "x"})");
  try {
    ReadDetectShardRecord(dir);
    FAIL() << "no exception";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.field(), "shard");
    EXPECT_NE(e.file().find(kDetectShardFile), std::string::npos);
  }
  WriteFileAtomically(dir / kDetectShardFile, R"({"format": 1, "tool": "detect ssd"})");
  try {
    ReadDetectShardRecord(dir);
    FAIL() << "no exception";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.field(), "shard");
  }
  const fs::path empty = TempDir("record_none");
  EXPECT_NE(MessageOf([&] {
              ReadDetectShardRecord(empty);
            }).find("holds no detect_shard.json: not a folder of `detect ssd|det3d --shard"),
            std::string::npos);
}

TEST(DetectShardTest, MergeOfAllShardsInAnyOrderIsTheFolderOfOneRun) {
  const fs::path root = TempDir("merge");
  const std::vector<std::string> ids = Ids(7);
  WriteRun(root / "one", ids, {});
  for (int k : {2, 0, 1}) WriteRun(root / ("s" + std::to_string(k)), ids, {k, 3});
  // A stale file of an earlier run in the merge's folder does not survive.
  WriteRun(root / "merged", Ids(9), {});
  MergeDetectionsOptions options;
  options.shards = {root / "s2", root / "s0", root / "s1"};
  options.out_dir = root / "merged";
  options.command_line = "stereodet detect ssd ...";  // the one run's, to compare whole files
  const MergeDetectionsResult r = MergeDetections(options);
  EXPECT_EQ(r.tool, "detect ssd");
  EXPECT_EQ(r.shards, 3);
  EXPECT_EQ(r.frames, 7);
  const auto one = FolderBytes(root / "one"), merged = FolderBytes(root / "merged");
  EXPECT_EQ(one.size(), 8u);  // seven frames and run.json, no detect_shard.json
  EXPECT_EQ(merged, one);
}

TEST(DetectShardTest, MergeRefusesShardsThatAreNotAllOfOneRun) {
  const fs::path root = TempDir("refuse");
  const std::vector<std::string> ids = Ids(6);
  for (int k = 0; k < 3; ++k) WriteRun(root / ("s" + std::to_string(k)), ids, {k, 3});
  WriteRun(root / "other_settings", ids, {1, 3}, R"({"score_threshold": 0.5})");
  WriteRun(root / "other_count", ids, {1, 2});
  WriteRun(root / "other_batch", ids, {1, 3}, R"({"score_threshold": 0.01})", 1);
  WriteRun(root / "other_list", Ids(7), {1, 3});
  WriteRun(root / "whole", ids, {});
  const auto merge = [&](const std::vector<std::string>& names) {
    MergeDetectionsOptions options;
    for (const std::string& name : names) options.shards.push_back(root / name);
    options.out_dir = root / "out";
    return MessageOf([&] { MergeDetections(options); });
  };
  EXPECT_NE(merge({"s0", "s2"}).find("shard 1/3 is missing"), std::string::npos);
  EXPECT_NE(merge({"s0", "s1"}).find("2 shard folders for 3 shards; shard 2/3 is missing"),
            std::string::npos);
  EXPECT_NE(merge({"s0", "s1", "s1", "s2"}).find("shard 1/3 is given twice"), std::string::npos)
      << merge({"s0", "s1", "s1", "s2"});
  EXPECT_NE(merge({"s0", "other_settings", "s2"}).find("has another settings than"),
            std::string::npos);
  EXPECT_NE(merge({"s0", "other_count", "s2"}).find("is shard 1/2, but"), std::string::npos);
  EXPECT_NE(merge({"s0", "other_batch", "s2"}).find("ran batches of 1 frames"), std::string::npos);
  EXPECT_NE(merge({"s0", "other_list", "s2"}).find("is a shard of another frame list"),
            std::string::npos);
  EXPECT_NE(merge({"s0", "whole", "s2"}).find("whole holds no detect_shard.json"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(root / "out"));  // nothing written by a refused merge

  // A detection file changed after its shard ran.
  WriteFileAtomically(root / "s1" / (ids[2] + ".txt"), "");
  EXPECT_NE(merge({"s0", "s1", "s2"}).find("changed since its shard ran"), std::string::npos);
  EXPECT_FALSE(fs::exists(root / "out"));
  // An --out inside a shard folder.
  MergeDetectionsOptions inside;
  inside.shards = {root / "s0"};
  inside.out_dir = root / "s0" / "merged";
  EXPECT_THROW(MergeDetections(inside), std::invalid_argument);
  // An --out that holds something else.
  WriteRun(root / "s1", ids, {1, 3});
  WriteFileAtomically(root / "notes" / "mine.txt", "mine");
  MergeDetectionsOptions foreign;
  foreign.shards = {root / "s0", root / "s1", root / "s2"};
  foreign.out_dir = root / "notes";
  EXPECT_NE(MessageOf([&] {
              MergeDetections(foreign);
            }).find("notes is a folder of other files (mine.txt); detect merge replaces"),
            std::string::npos);
  EXPECT_EQ(ReadFile(root / "notes" / "mine.txt"), "mine");
}

TEST(DetectShardTest, TwoStagePipelineConsumesInOrderAndRethrows) {
  for (bool overlap : {false, true}) {
    for (int n : {0, 1, 2, 7}) {
      std::vector<int> slot(2, -1), consumed;
      RunTwoStagePipeline(
          n, overlap, [&](int k) { slot[k % 2] = k * 10; },
          [&](int k) {
            EXPECT_EQ(slot[k % 2], k * 10);  // its own preparation, not the next one's
            consumed.push_back(k);
          });
      std::vector<int> expected(n);
      std::iota(expected.begin(), expected.end(), 0);
      EXPECT_EQ(consumed, expected) << "overlap " << overlap << ", " << n << " batches";
    }
    // A failing preparation stops the loop: nothing after it is consumed.
    std::vector<int> consumed;
    EXPECT_THROW(RunTwoStagePipeline(
                     5, overlap,
                     [](int k) {
                       if (k == 2) throw std::runtime_error("frame 2 unreadable");
                     },
                     [&](int k) { consumed.push_back(k); }),
                 std::runtime_error);
    EXPECT_EQ(consumed, (std::vector<int>{0, 1}));
    // So does a failing consumer, after the preparation in flight has finished.
    int prepared = 0;
    EXPECT_THROW(RunTwoStagePipeline(
                     5, overlap, [&](int) { ++prepared; },
                     [](int k) {
                       if (k == 1) throw std::invalid_argument("bad batch");
                     }),
                 std::invalid_argument);
    EXPECT_EQ(prepared, overlap ? 3 : 2);
  }
}

}  // namespace
}  // namespace stereodet
