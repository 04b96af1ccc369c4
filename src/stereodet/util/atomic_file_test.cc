#include "stereodet/util/atomic_file.h"
#include "stereodet/util/test_temp_dir.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

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
    EXPECT_EQ(out.temp_path().parent_path(), path.parent_path());  // same filesystem: rename is atomic
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

}  // namespace
}  // namespace stereodet
