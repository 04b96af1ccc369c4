#include "stereodet/util/run_manifest.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/fuzz_corpus.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

TEST(RunManifestTest, RoundTripsEveryField) {
  RunManifest m;
  m.tool = "detect ssd";
  m.version = "0.1.0";
  m.command_line = "stereodet detect ssd --out x";
  m.inputs = {{"model", "models/a"}, {"data", "/d"}};
  m.settings_json = R"({"blur_sigma_px": 1.5})";
  m.frames = {{"000002", "00000000000000aa"}, {"000001", "00000000000000bb"}};
  const std::string text = RunManifestToJson(m);
  EXPECT_EQ(text.back(), '\n');
  const RunManifest back = RunManifestFromJson(text, "run.json");
  EXPECT_EQ(back.tool, m.tool);
  EXPECT_EQ(back.version, m.version);
  EXPECT_EQ(back.command_line, m.command_line);
  EXPECT_EQ(back.inputs, m.inputs);  // order kept
  EXPECT_EQ(back.settings_json, R"({"blur_sigma_px":1.5})");
  EXPECT_EQ(back.frames, m.frames);
  m.settings_json = "[1]";
  EXPECT_THROW(RunManifestToJson(m), std::invalid_argument);
}

TEST(RunManifestTest, ReadsNothingFromAFolderWithoutOneAndNamesABadFile) {
  TestTempDir dir;
  EXPECT_FALSE(ReadRunManifest(dir.path()).has_value());
  RunManifest m;
  m.tool = "train ssd";
  WriteRunManifest(dir / "sub", m);
  ASSERT_TRUE(ReadRunManifest(dir / "sub").has_value());
  EXPECT_EQ(ReadRunManifest(dir / "sub")->tool, "train ssd");
  WriteFileAtomically(dir / kRunManifestFile, R"({"tool": "x"})");
  try {
    ReadRunManifest(dir.path());
    FAIL() << "no exception";
  } catch (const ParseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("run.json"));
    EXPECT_THAT(e.what(), HasSubstr("version"));
  }
}

// The run_manifest fuzzer's corpus (fuzz/run_manifest_fuzzer.cc), replayed: each input parses or
// throws ParseError, and what parses is written and read back unchanged.
TEST(RunManifestTest, FuzzCorpusInputsParseOrThrowParseError) {
  const std::vector<fs::path> files = FuzzCorpusFiles("run_manifest");
  ASSERT_GE(files.size(), 5u) << "the run_manifest corpus is missing";
  int parsed = 0, rejected = 0;
  for (const fs::path& path : files) {
    SCOPED_TRACE(path.filename().string());
    try {
      const RunManifest manifest = RunManifestFromJson(ReadFile(path), path.string());
      const std::string written = RunManifestToJson(manifest);
      const RunManifest again = RunManifestFromJson(written, "written");
      EXPECT_EQ(again.tool, manifest.tool);
      EXPECT_EQ(again.inputs, manifest.inputs);
      EXPECT_EQ(again.frames, manifest.frames);
      EXPECT_EQ(again.settings_json, manifest.settings_json);
      EXPECT_EQ(RunManifestToJson(again), written);
      ++parsed;
    } catch (const ParseError& e) {
      EXPECT_EQ(e.file(), path.string());
      ++rejected;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "unexpected exception: " << e.what();
    }
  }
  EXPECT_GT(parsed, 0);
  EXPECT_GT(rejected, 0);
}

TEST(OverlapCheckTest, RefusesTheSameFolderInsideAndAroundButNotASibling) {
  TestTempDir dir;
  fs::create_directories(dir / "data/training/label_2");
  const fs::path data = dir / "data/training";
  auto check = [&](const fs::path& out) {
    CheckOutputDoesNotOverlapInputs("--out", out, {{"--data", data}, {"--model", ""}});
  };
  EXPECT_NO_THROW(check(dir / "data/stereo"));         // a sibling of the input
  EXPECT_NO_THROW(check(dir / "data/training2"));      // a name that only starts alike
  EXPECT_NO_THROW(check(dir / "elsewhere/new/deep"));  // missing folders are fine
  try {
    check(dir / "data/training/label_2");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("label_2 is inside the input --data"));
    EXPECT_THAT(e.what(), HasSubstr("data/training"));
  }
  EXPECT_THROW(check(dir / "data/training/"), std::invalid_argument);  // the same folder
  EXPECT_THROW(check(dir / "data/training/../training"), std::invalid_argument);
  EXPECT_THROW(check(dir / "data/training/new/sub"), std::invalid_argument);  // not there yet
  try {
    check(dir / "data");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("holds the input --data"));
  }
  // Through a symbolic link.
  fs::create_directory_symlink(data, dir / "link");
  EXPECT_THROW(check(dir / "link/label_2"), std::invalid_argument);
}

TEST(HashFileHexTest, IsTheHashOfTheBytes) {
  TestTempDir dir;
  WriteFileAtomically(dir / "a", "abc");
  EXPECT_EQ(HashFileHex(dir / "a"), HashHex(Fnv1a64("abc")));
  EXPECT_THROW(HashFileHex(dir / "missing"), std::runtime_error);
}

TEST(CheckFolderWritableTest, CreatesAFolderAndRefusesOneBelowAFile) {
  TestTempDir dir;
  CheckFolderWritable(dir / "new/model");
  EXPECT_TRUE(fs::is_directory(dir / "new/model"));
  EXPECT_TRUE(fs::is_empty(dir / "new/model"));  // the probe is gone
  WriteFileAtomically(dir / "file", "x");
  try {
    CheckFolderWritable(dir / "file/model");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("cannot create folder"));
    EXPECT_THAT(e.what(), HasSubstr("file/model"));
  }
}

TEST(CheckFolderWritableTest, RefusesAReadOnlyFolder) {
  TestTempDir dir;
  if (::geteuid() == 0) GTEST_SKIP() << "root writes into read-only folders";
  fs::create_directory(dir / "ro");
  fs::permissions(dir / "ro", fs::perms::owner_read | fs::perms::owner_exec);
  try {
    CheckFolderWritable(dir / "ro");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("cannot write into folder"));
    EXPECT_THAT(e.what(), HasSubstr("/ro"));
  }
  fs::permissions(dir / "ro", fs::perms::owner_all);
}

TEST(OutputLockTest, OneHolderAtATimeAndNoFileLeft) {
  TestTempDir dir;
  const fs::path out = dir / "out";
  {
    const OutputLock lock(out / "");
    EXPECT_TRUE(fs::exists(dir / ".out.lock"));
    // flock locks belong to the open file, so a second open in this process is refused as well.
    try {
      const OutputLock second(out);
      FAIL() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_THAT(e.what(), HasSubstr("another run is writing into"));
      EXPECT_THAT(e.what(), HasSubstr("/out"));
    }
    EXPECT_NO_THROW(OutputLock(dir / "other"));
  }
  EXPECT_FALSE(fs::exists(dir / ".out.lock"));
  EXPECT_NO_THROW(OutputLock{out});
}

}  // namespace
}  // namespace stereodet
