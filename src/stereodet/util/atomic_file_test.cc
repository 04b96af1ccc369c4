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

TEST_F(AtomicFileTest, ReadFileRefusesAFileLargerThanItsBoundNamingTheSize) {
  const fs::path path = dir_ / "scan.bin";
  WriteFileAtomically(path, std::string(3000, 'x'));
  EXPECT_EQ(ReadFile(path, 3000).size(), 3000u);  // the bound itself is allowed
  try {
    ReadFile(path, 2000, "velodyne scan");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(
        std::string(e.what()).find("cannot read velodyne scan " + path.string() +
                                   ": it is 3000 bytes, more than the 2000 bytes read of one file"),
        std::string::npos)
        << e.what();
  }
  // A sparse file far larger than memory: a message, not std::bad_alloc.
  const fs::path huge = dir_ / "huge.bin";
  WriteFileAtomically(huge, "");
  fs::resize_file(huge, uint64_t{64} << 30);
  try {
    ReadFile(huge);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("it is 68.7 GB, more than the 4.3 GB read of one file"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(AtomicFileTest, ReadFileHeadReadsThePrefixAndRefusesAFifo) {
  WriteFileAtomically(dir_ / "a.png", "0123456789");
  EXPECT_EQ(ReadFileHead(dir_ / "a.png", 4), "0123");
  EXPECT_EQ(ReadFileHead(dir_ / "a.png", 40), "0123456789");  // shorter than asked: all of it
  ASSERT_EQ(::mkfifo((dir_ / "fifo.png").c_str(), 0600), 0);
  EXPECT_THROW(ReadFileHead(dir_ / "fifo.png", 24), std::runtime_error);
}

TEST_F(AtomicFileTest, ReadFileReadsProcFilesWhoseSizeIsZero) {
  EXPECT_FALSE(ReadFile("/proc/self/cmdline").empty());
}

}  // namespace
}  // namespace stereodet
