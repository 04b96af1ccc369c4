// Replays the libFuzzer corpora (fuzz/corpus/{label,calib}/) through the parsers in every normal
// build: each input either parses or throws ParseError (or std::runtime_error), never anything
// else, and what parses round-trips. Keeps every crash the fuzzers once found fixed.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/kitti/text_number.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path> CorpusFiles(const std::string& name) {
  const fs::path dir = fs::path(STEREODET_SOURCE_DIR) / "fuzz" / "corpus" / name;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

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

}  // namespace
}  // namespace stereodet
