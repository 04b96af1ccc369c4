#include "stereodet/util/atomic_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {
namespace fs = std::filesystem;

class AtomicFileTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = temp_.path(); }
  size_t CountFiles() const {
    size_t n = 0;
    for (const auto& entry : fs::recursive_directory_iterator(dir_)) n += entry.is_regular_file();
    return n;
  }
  TestTempDir temp_;
  fs::path dir_;
};

TEST_F(AtomicFileTest, WritesContentsCreatingParentsAndLeavesNoTemporary) {
  const fs::path path = dir_ / "a" / "b" / "out.txt";
  WriteFileAtomically(path, std::string("hello\0world", 11));
  EXPECT_EQ(ReadFile(path), std::string("hello\0world", 11));
  EXPECT_EQ(CountFiles(), 1u);
}

TEST_F(AtomicFileTest, ReplacesAnExistingFile) {
  const fs::path path = dir_ / "out.txt";
  WriteFileAtomically(path, "old contents that are longer");
  WriteFileAtomically(path, "new");
  EXPECT_EQ(ReadFile(path), "new");
  EXPECT_EQ(CountFiles(), 1u);
}

TEST_F(AtomicFileTest, UncommittedAtomicPathLeavesDestinationUntouched) {
  const fs::path path = dir_ / "image.png";
  WriteFileAtomically(path, "original");
  {
    AtomicPath out(path);
    EXPECT_EQ(out.temp_path().extension(), ".png");  // encoders choose by extension
    EXPECT_EQ(out.temp_path().parent_path(),
              path.parent_path());  // same filesystem: rename is atomic
    std::ofstream(out.temp_path()) << "half written";
    // No Commit(): as if the writer threw.
  }
  EXPECT_EQ(ReadFile(path), "original");
  EXPECT_EQ(CountFiles(), 1u);
}

TEST_F(AtomicFileTest, CommitWithoutTemporaryThrows) {
  AtomicPath out(dir_ / "never_written.txt");
  EXPECT_THROW(out.Commit(), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir_ / "never_written.txt"));
}

TEST_F(AtomicFileTest, ReadingAMissingFileNamesIt) {
  try {
    ReadFile(dir_ / "missing.txt");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.txt"), std::string::npos);
  }
}

TEST_F(AtomicFileTest, WritingIntoAFileAsIfAFolderFails) {
  WriteFileAtomically(dir_ / "plain", "x");
  EXPECT_THROW(WriteFileAtomically(dir_ / "plain" / "child.txt", "y"), std::runtime_error);
}

// StagedFolder: one run per folder.
TEST_F(AtomicFileTest, StagedFolderReplacesAnEarlierRunWhole) {
  const fs::path out = dir_ / "results";
  {
    StagedFolder run1(out, "results.json");
    WriteFileAtomically(run1.path() / "results.json", "1");
    WriteFileAtomically(run1.path() / "curves" / "only_in_run1.csv", "x");
    EXPECT_FALSE(fs::exists(out));  // nothing visible before the commit
    run1.Commit();
  }
  EXPECT_EQ(ReadFile(out / "results.json"), "1");
  {
    StagedFolder run2(out / "", "results.json");  // a trailing separator names the same folder
    WriteFileAtomically(run2.path() / "results.json", "2");
    EXPECT_EQ(ReadFile(out / "results.json"), "1");  // the old run stays whole until the commit
    run2.Commit();
  }
  EXPECT_EQ(ReadFile(out / "results.json"), "2");
  EXPECT_FALSE(fs::exists(out / "curves" / "only_in_run1.csv"));  // no stale file of run 1
  EXPECT_EQ(CountFiles(), 1u);  // no staging or old folder left beside it
}

TEST_F(AtomicFileTest, UncommittedStagedFolderLeavesThePreviousRun) {
  const fs::path out = dir_ / "results";
  WriteFileAtomically(out / "results.json", "old");
  {
    StagedFolder run(out, "results.json");
    WriteFileAtomically(run.path() / "results.json", "new");
  }  // interrupted: no Commit()
  EXPECT_EQ(ReadFile(out / "results.json"), "old");
  EXPECT_EQ(CountFiles(), 1u);
}

TEST_F(AtomicFileTest, StagedFolderRefusesAFolderOfSomethingElse) {
  WriteFileAtomically(dir_ / "home" / "thesis.tex", "precious");
  EXPECT_THROW(StagedFolder(dir_ / "home", "results.json"), std::runtime_error);
  try {
    StagedFolder refused(dir_ / "home", "results.json");
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("holds no results.json"), std::string::npos) << e.what();
  }
  WriteFileAtomically(dir_ / "plain_file", "x");
  EXPECT_THROW(StagedFolder(dir_ / "plain_file", "results.json"), std::runtime_error);
  EXPECT_EQ(ReadFile(dir_ / "home" / "thesis.tex"), "precious");
  fs::create_directories(dir_ / "empty");
  StagedFolder ok(dir_ / "empty", "results.json");  // an empty folder is fine
  ok.Commit();
  EXPECT_TRUE(fs::is_directory(dir_ / "empty"));
}

TEST_F(AtomicFileTest, ReadFileRefusesAFifoAndAFolderWithoutBlocking) {
  const fs::path fifo = dir_ / "label.txt";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  try {
    ReadFile(fifo);  // no writer: a blocking open would hang here
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReadFile(dir_), std::runtime_error);
  EXPECT_THROW(ReadFile(dir_ / "missing.txt"), std::runtime_error);
}

TEST_F(AtomicFileTest, ReadFileReadsProcFilesWhoseSizeIsZero) {
  EXPECT_FALSE(ReadFile("/proc/self/cmdline").empty());
}

}  // namespace
}  // namespace stereodet
