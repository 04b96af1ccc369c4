// eval --shard and eval merge (pipelines/evaluation.h): random frames split into 1 (a named 0/1),
// 2 and 3 shards, evaluated shard by shard and merged, give the files of one run byte for byte
// (results.json up to its provenance), with every matcher, a filter in both modes, two overlap
// sets and records.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "stereodet/eval/breakdown.h"
#include "stereodet/eval/openpcdet_compat.h"
#include "stereodet/eval/random_frames.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/pipelines/evaluation.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// Every file under `root` but the shard's own: relative path -> bytes.
std::map<std::string, std::string> FolderBytes(const fs::path& root) {
  std::map<std::string, std::string> out;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(root)) {
    if (!e.is_regular_file()) continue;
    const std::string name = e.path().lexically_relative(root).string();
    if (name == "eval_shard.json" || name == "eval_frames.dat") continue;
    out[name] = ReadFile(e.path());
  }
  return out;
}

// results.json without what differs between two runs of the same evaluation.
nlohmann::json WithoutProvenance(const std::string& text) {
  nlohmann::json j = nlohmann::json::parse(text);
  j.erase("command_line");
  j.erase("seconds");
  j.erase("tool");
  return j;
}

// Random frames as label and detection folders; frame 5 has no detection file.
struct RandomFolders {
  TestTempDir dir{"shard-data"};
  fs::path gt = dir.path() / "label_2";
  fs::path det = dir.path() / "det";
  explicit RandomFolders(int frames, uint64_t seed) {
    RandomFramesOptions o;
    o.num_frames = frames;
    o.seed = seed;
    o.score_decimals = 2;  // ties, as in KITTI files
    for (const EvalFrame& f : RandomFrames(o)) {
      WriteObjects(gt / (f.id + ".txt"), f.labels);
      if (f.id != "000005") WriteObjects(det / (f.id + ".txt"), f.detections);
    }
  }
};

EvaluationOptions Options(const RandomFolders& data, Matcher matcher, FilterMode mode,
                          const fs::path& out) {
  EvaluationOptions options;
  options.input.gt = data.gt;
  options.input.det = data.det;
  options.input.missing_as_empty = true;  // frame 000005 has no detection file on purpose
  EvalOptions run;
  run.matcher = matcher;
  run.filter.conditions = ParseFilterConditions("min-area=400,max-distance=45");
  run.filter.mode = mode;
  run.score_threshold = 0.3;
  // Breakdowns merge as the rest does: every bin from the merged frames (issue 37).
  run.breakdowns = {ParseBreakdown("distance=0,20,40,inf"), ParseBreakdown("occlusion=0,1,4")};
  options.runs = OverlapSetRuns(run, {OverlapSet::kStrict, OverlapSet::kLoose});
  options.records = true;
  options.out = out;
  return options;
}

struct Case {
  Matcher matcher;
  FilterMode mode;
  int shards;
};

class EvalShardByMatcherTest : public ::testing::TestWithParam<Case> {};

TEST_P(EvalShardByMatcherTest, MergedShardsAreOneRun) {
  const Case c = GetParam();
  const RandomFolders data(41, 7 + c.shards);
  const TestTempDir out("shard-out");
  const EvaluationResult whole =
      RunEvaluation(Options(data, c.matcher, c.mode, out.path() / "whole"));

  EvaluationMergeOptions merge;
  for (int k = c.shards - 1; k >= 0; --k) {  // given in reverse order
    const fs::path dir = out.path() / ("shard" + std::to_string(k));
    EvaluationOptions part = Options(data, c.matcher, c.mode, dir);
    part.input.shard = Shard{k, c.shards, /*named=*/true};
    part.input.num_threads = 1 + k % 2;
    const EvaluationResult r = RunEvaluation(part);
    EXPECT_EQ(static_cast<size_t>(r.input.frames.size()),
              part.input.shard.End(41) - part.input.shard.Begin(41));
    merge.shards.push_back(dir);
  }
  merge.evaluation = Options(data, c.matcher, c.mode, out.path() / "merged");
  merge.evaluation.input = EvalInputOptions{};  // the merge takes the shards' input
  const EvaluationResult merged = RunEvaluationMerge(merge);
  EXPECT_EQ(merged.input.input_hash, whole.input.input_hash);
  EXPECT_EQ(merged.input.frames_without_detections, std::vector<std::string>{"000005"});

  const std::map<std::string, std::string> a = FolderBytes(out.path() / "whole");
  const std::map<std::string, std::string> b = FolderBytes(out.path() / "merged");
  ASSERT_EQ(a.size(), b.size());
  EXPECT_GT(a.size(), 4u);
  for (const auto& [name, bytes] : a) {
    ASSERT_TRUE(b.count(name)) << name;
    if (name == "results.json") {
      EXPECT_EQ(WithoutProvenance(bytes), WithoutProvenance(b.at(name)));
    } else {
      EXPECT_TRUE(bytes == b.at(name)) << name << " differs";
    }
  }
  // Not vacuous: the results hold curves and records.
  ASSERT_FALSE(whole.runs.front().result.results.empty());
  EXPECT_FALSE(whole.runs.front().result.results.front().records.empty());
  EXPECT_GT(whole.runs.front().result.results.front().num_valid_labels, 0);
  EXPECT_EQ(whole.runs.front().result.results.front().breakdown.size(), 3u + 2u);
  EXPECT_TRUE(a.count("breakdown.csv"));
}

INSTANTIATE_TEST_SUITE_P(Matchers, EvalShardByMatcherTest,
                         ::testing::Values(Case{Matcher::kKitti, FilterMode::kStable, 1},
                                           Case{Matcher::kKitti, FilterMode::kStable, 2},
                                           Case{Matcher::kKitti, FilterMode::kNaive, 3},
                                           Case{Matcher::kOptimal, FilterMode::kStable, 3},
                                           Case{Matcher::kOptimal, FilterMode::kNaive, 2},
                                           Case{Matcher::kVoc, FilterMode::kStable, 2},
                                           Case{Matcher::kVoc, FilterMode::kNaive, 3}),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           return std::string(MatcherName(info.param.matcher)) + "_" +
                                  FilterModeName(info.param.mode) + "_" +
                                  std::to_string(info.param.shards) + "shards";
                         });

TEST(EvalShardTest, RefusesMissingDuplicateOrMismatchedShards) {
  const RandomFolders data(9, 3);
  const TestTempDir out("shard-bad");
  std::vector<fs::path> dirs;
  for (int k = 0; k < 3; ++k) {
    EvaluationOptions part =
        Options(data, Matcher::kKitti, FilterMode::kStable, out.path() / ("s" + std::to_string(k)));
    part.input.shard = Shard{k, 3};
    RunEvaluation(part);
    dirs.push_back(part.out);
  }
  EvaluationMergeOptions merge;
  merge.evaluation = Options(data, Matcher::kKitti, FilterMode::kStable, out.path() / "m");
  merge.shards = {dirs[0], dirs[2]};
  EXPECT_THAT([&] { RunEvaluationMerge(merge); },
              ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("shard 1/3 is missing")));
  merge.shards = {dirs[0], dirs[1], dirs[1]};
  EXPECT_THAT(
      [&] { RunEvaluationMerge(merge); },
      ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr(
          "shard 1/3 is given twice (at " + dirs[1].string() + " and " + dirs[1].string() + ")")));
  merge.shards = {dirs[0], dirs[2], dirs[2]};
  EXPECT_THAT([&] { RunEvaluationMerge(merge); },
              ::testing::ThrowsMessage<std::invalid_argument>(
                  HasSubstr("shard 1/3 is missing (the next given is 2/3")));
  merge.shards = {dirs[0], dirs[1], dirs[2]};
  merge.evaluation.runs.front().score_threshold = 0.5;
  EXPECT_THAT([&] { RunEvaluationMerge(merge); },
              ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("other options")));
  EXPECT_FALSE(fs::exists(out.path() / "m"));  // nothing committed
  merge.shards = {data.gt};
  EXPECT_THAT([&] { RunEvaluationMerge(merge); },
              ::testing::ThrowsMessage<std::runtime_error>(HasSubstr("not an evaluation shard")));
}

// A shard's frames edited after it ran (a label changed, a detection dropped) would change the
// merged AP silently; the merge checks them against the hash the shard recorded.
TEST(EvalShardTest, RefusesAShardWhoseFramesChangedSinceItRan) {
  const RandomFolders data(6, 4);
  const TestTempDir out("shard-tampered");
  std::vector<fs::path> dirs;
  for (int k = 0; k < 2; ++k) {
    EvaluationOptions part =
        Options(data, Matcher::kKitti, FilterMode::kStable, out.path() / ("s" + std::to_string(k)));
    part.input.shard = Shard{k, 2};
    RunEvaluation(part);
    dirs.push_back(part.out);
  }
  EvaluationMergeOptions merge;
  merge.evaluation = Options(data, Matcher::kKitti, FilterMode::kStable, out.path() / "m");
  merge.shards = dirs;
  RunEvaluationMerge(merge);  // as written: merges
  const fs::path frames = dirs[1] / "eval_frames.dat";
  std::string text = ReadFile(frames);
  const size_t at = text.find("Car ");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 4, "Van ");  // same length: only the hash can tell
  WriteFileAtomically(frames, text);
  merge.evaluation.out = out.path() / "m2";
  EXPECT_THAT([&] { RunEvaluationMerge(merge); },
              ::testing::ThrowsMessage<std::runtime_error>(
                  HasSubstr(frames.string() + " is not the file its eval_shard.json records")));
  EXPECT_FALSE(fs::exists(out.path() / "m2"));
}

// A shard record of the wrong shape (an edited file, nested JSON where a value belongs) is refused
// naming the field and what it holds, not in nlohmann's words alone.
TEST(EvalShardTest, AShardRecordOfTheWrongShapeNamesTheField) {
  const RandomFolders data(4, 3);
  const TestTempDir out("shard-shape");
  EvaluationOptions part = Options(data, Matcher::kKitti, FilterMode::kStable, out.path() / "s0");
  part.input.shard = Shard{0, 2};
  RunEvaluation(part);
  const fs::path record = part.out / "eval_shard.json";
  const std::string good = ReadFile(record);
  for (const auto& [edit, expected] : std::vector<std::pair<std::string, std::string>>{
           {R"({"frames": {"a": [1, {"b": 2}]}})", "field frames: expected an integer, got {"},
           {R"({"input": {"det": [[[[1]]]]}})", "field input.det: expected a string, got [[[["},
           {R"({"input": "x"})", "field input.gt: expected an object holding 'gt'"},
           {R"({"shard": 3})", "field shard: expected a string K/N, got 3"}}) {
    nlohmann::json j = nlohmann::json::parse(good);
    j.merge_patch(nlohmann::json::parse(edit));
    WriteFileAtomically(record, j.dump(2));
    EXPECT_THAT([&] { ReadEvalShard(part.out); },
                ::testing::ThrowsMessage<ParseError>(HasSubstr(expected)))
        << edit;
  }
  WriteFileAtomically(record, std::string(1000, '[') + std::string(1000, ']'));
  EXPECT_THAT([&] { ReadEvalShard(part.out); },
              ::testing::ThrowsMessage<ParseError>(HasSubstr("expected an object holding")));
}

// `eval sweep|compare --shards`: the frames of eval shards give the rows of one run's sweep and
// comparison, byte for byte in their CSV.
TEST(EvalShardTest, SweepAndCompareOfShardsAreThoseOfOneRun) {
  const RandomFolders data(23, 11);
  // Detections B: A's, 0.5 m farther and with other scores.
  const fs::path det_b = data.dir.path() / "det_b";
  for (const fs::directory_entry& e : fs::directory_iterator(data.det)) {
    ObjectParseOptions parse;
    parse.kind = ObjectFileKind::kDetection;
    std::vector<Object> objects = ReadObjects(e.path(), parse).objects;
    for (Object& o : objects) {
      if (o.Has3D()) o.box3d.location.z() += 0.5;
      if (o.score) o.score = std::round(*o.score * 70.0) / 100.0;
    }
    WriteObjects(det_b / e.path().filename(), objects);
  }
  const TestTempDir out("shard-sweep");
  std::vector<fs::path> shards_a, shards_b;
  for (int k = 2; k >= 0; --k) {
    for (const auto& [det, name] : {std::pair{data.det, "a"}, std::pair{det_b, "b"}}) {
      EvaluationOptions part = Options(data, Matcher::kKitti, FilterMode::kStable,
                                       out.path() / (name + std::to_string(k)));
      part.input.det = det;
      part.input.shard = Shard{k, 3};
      part.records = false;
      RunEvaluation(part);
      (det == data.det ? shards_a : shards_b).push_back(part.out);
    }
  }
  EvalOptions run;
  run.filter.conditions = ParseFilterConditions("max-distance=45");
  EvaluationSweepOptions sweep;
  sweep.input.gt = data.gt;
  sweep.input.det = data.det;
  sweep.eval = run;
  sweep.from = 0;
  sweep.to = 1000;
  sweep.step = 250;
  const EvaluationSweepResult whole = RunEvaluationSweep(sweep);
  sweep.input = EvalInputOptions{};
  sweep.shards = shards_a;
  const EvaluationSweepResult sharded = RunEvaluationSweep(sweep);
  EXPECT_GT(whole.rows.size(), 5u);  // 5 bounds per class and difficulty
  EXPECT_EQ(sharded.csv, whole.csv);
  EXPECT_EQ(sharded.input.input_hash, whole.input.input_hash);

  EvaluationCompareOptions compare;
  compare.input.gt = data.gt;
  compare.input.det = data.det;
  compare.det_b = det_b;
  compare.eval.metrics = {OverlapKind::k2D};
  const EvaluationCompareResult whole_compare = RunEvaluationCompare(compare);
  ASSERT_FALSE(whole_compare.rows.empty());
  compare.input = EvalInputOptions{};
  compare.det_b.clear();
  compare.shards = shards_a;
  compare.shards_b = shards_b;
  EXPECT_EQ(RunEvaluationCompare(compare).csv, whole_compare.csv);
  // B's shards must be of A's labels, and come with A's.
  compare.shards_b = {};
  EXPECT_THROW(RunEvaluationCompare(compare), std::invalid_argument);
  compare.shards_b = {shards_b.back()};  // shard 0/3 alone
  EXPECT_THAT([&] { RunEvaluationCompare(compare); },
              ::testing::ThrowsMessage<std::invalid_argument>(
                  HasSubstr("eval shards: 1 shard folders for 3 shards")));
}

}  // namespace
}  // namespace stereodet
