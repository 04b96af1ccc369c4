// Replays the libFuzzer corpora of the kitti parsers (fuzz/corpus/{label,calib,split,velodyne}/)
// in every normal build: each input either parses or throws ParseError (or std::runtime_error),
// never anything else, and what parses round-trips. Keeps every crash the fuzzers once found fixed.
// The other corpora are replayed beside their parsers (run_manifest: util, disparity: stereo,
// model_json: models_core, coco: eval); EveryCorpusIsReplayed keeps that list complete.
#include "stereodet/util/fuzz_corpus.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/kitti/text_number.h"
#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/test_paths.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path> CorpusFiles(const std::string& name) { return FuzzCorpusFiles(name); }

TEST(FuzzCorpusTest, LabelInputsParseOrThrowParseError) {
  const std::vector<fs::path> files = CorpusFiles("label");
  ASSERT_GE(files.size(), 10u) << "the label corpus is missing";
  int parsed = 0, rejected = 0;
  for (const fs::path& path : files) {
    SCOPED_TRACE(path.filename().string());
    const std::string text = ReadFile(path);
    for (ObjectFileKind kind :
         {ObjectFileKind::kLabel, ObjectFileKind::kDetection, ObjectFileKind::kAny}) {
      ObjectParseOptions options;
      options.kind = kind;
      options.lenient = true;
      ObjectFile lenient;
      ASSERT_NO_THROW(lenient = ParseObjects(text, "corpus", options));
      EXPECT_EQ(lenient.skipped_lines, static_cast<int>(lenient.problems.size()));
      options.lenient = false;
      try {
        const ObjectFile strict = ParseObjects(text, "corpus", options);
        EXPECT_EQ(strict.objects, lenient.objects);
        EXPECT_EQ(lenient.skipped_lines, 0);
        ++parsed;
      } catch (const ParseError& e) {
        EXPECT_GE(e.line(), 1);
        EXPECT_FALSE(e.field().empty());
        EXPECT_GT(lenient.skipped_lines, 0);
        ++rejected;
      } catch (const std::exception& e) {
        ADD_FAILURE() << "unexpected exception: " << e.what();
      }
      ObjectParseOptions any;
      any.kind = ObjectFileKind::kAny;
      EXPECT_EQ(ParseObjects(FormatObjects(lenient.objects), "formatted", any).objects,
                lenient.objects);
    }
  }
  // The corpus exercises both outcomes.
  EXPECT_GT(parsed, 0);
  EXPECT_GT(rejected, 0);
}

TEST(FuzzCorpusTest, CalibInputsParseOrThrowParseError) {
  const std::vector<fs::path> files = CorpusFiles("calib");
  ASSERT_GE(files.size(), 10u) << "the calib corpus is missing";
  int parsed = 0, rejected = 0;
  for (const fs::path& path : files) {
    SCOPED_TRACE(path.filename().string());
    try {
      const Calibration calib = ReadCalibration(path);
      const std::string text = FormatCalibration(calib);
      EXPECT_EQ(FormatCalibration(ParseCalibration(text, "formatted")), text);
      ++parsed;
    } catch (const ParseError& e) {
      EXPECT_FALSE(e.field().empty());
      ++rejected;
    } catch (const std::runtime_error&) {
      ++rejected;  // an I/O error: allowed, if unlikely for a checked-in file
    } catch (const std::exception& e) {
      ADD_FAILURE() << "unexpected exception: " << e.what();
    }
  }
  EXPECT_GT(parsed, 0);
  EXPECT_GT(rejected, 0);
}

TEST(FuzzCorpusTest, SplitInputsParseOrThrowParseError) {
  const std::vector<fs::path> files = CorpusFiles("split");
  ASSERT_GE(files.size(), 5u) << "the split corpus is missing";
  int parsed = 0, rejected = 0;
  for (const fs::path& path : files) {
    SCOPED_TRACE(path.filename().string());
    const std::string text = ReadFile(path);
    try {
      const std::vector<std::string> ids = ParseSplit(text, "corpus");
      std::string written;
      for (const std::string& id : ids) written += id + "\n";
      EXPECT_EQ(ParseSplit(written, "written"), ids);
      ++parsed;
    } catch (const ParseError& e) {
      EXPECT_GE(e.line(), 1);
      EXPECT_EQ(e.field(), "frame id");
      EXPECT_LT(e.message().size(), 200u);
      ++rejected;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "unexpected exception: " << e.what();
    }
  }
  EXPECT_GT(parsed, 0);
  EXPECT_GT(rejected, 0);
}

TEST(FuzzCorpusTest, VelodyneInputsParseOrThrowNamingTheFile) {
  const std::vector<fs::path> files = CorpusFiles("velodyne");
  ASSERT_GE(files.size(), 3u) << "the velodyne corpus is missing";
  int parsed = 0, rejected = 0;
  for (const fs::path& path : files) {
    SCOPED_TRACE(path.filename().string());
    const std::string bytes = ReadFile(path);
    try {
      const std::vector<VeloPoint> points = ReadVelodyne(path);
      EXPECT_EQ(bytes.size() % 16, 0u);
      ASSERT_EQ(points.size() * 16, bytes.size());
      EXPECT_EQ(std::string(reinterpret_cast<const char*>(points.data()), bytes.size()), bytes);
      ++parsed;
    } catch (const std::runtime_error& e) {
      // Refused: a size that is no whole number of points, or a NaN or inf value.
      bool finite = true;
      for (size_t at = 0; at + 4 <= bytes.size() - bytes.size() % 16; at += 4) {
        float v;
        std::memcpy(&v, bytes.data() + at, 4);
        finite = finite && std::isfinite(v);
      }
      EXPECT_TRUE(bytes.size() % 16 != 0 || !finite);
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
      ++rejected;
    }
  }
  EXPECT_GT(parsed, 0);
  EXPECT_GT(rejected, 0);
}

TEST(FuzzCorpusTest, EveryCorpusIsReplayed) {
  // A corpus folder that no test replays would let a fixed crash come back unnoticed.
  const std::vector<std::string> replayed = {"calib",      "coco",         "disparity", "label",
                                             "model_json", "run_manifest", "split",     "velodyne"};
  std::vector<std::string> found;
  for (const auto& entry : fs::directory_iterator(::stereodet::TestSourceDir() / "fuzz/corpus")) {
    if (entry.is_directory()) found.push_back(entry.path().filename().string());
  }
  std::sort(found.begin(), found.end());
  EXPECT_EQ(found, replayed);
  for (const std::string& name : replayed) {
    EXPECT_TRUE(fs::exists(::stereodet::TestSourceDir() / "fuzz" / (name + "_fuzzer.cc"))) << name;
  }
}

}  // namespace
}  // namespace stereodet
