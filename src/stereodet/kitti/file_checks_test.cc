#include "stereodet/kitti/file_checks.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <stdexcept>
#include <string>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

using ::testing::HasSubstr;

// A complete 1 x 1 RGBA PNG (67 bytes): signature, IHDR, one IDAT, IEND.
const std::string kOnePixelPng(
    "\x89PNG\r\n\x1a\n"
    "\0\0\0\x0dIHDR\0\0\0\x01\0\0\0\x01\x08\x06\0\0\0\x1f\x15\xc4\x89"
    "\0\0\0\x0aIDAT\x78\x9c\x63\0\x01\0\0\x05\0\x01\x0d\x0a\x2d\xb4"
    "\0\0\0\0IEND\xae\x42\x60\x82",
    67);

std::string ErrorOf(void (*check)(const std::filesystem::path&), const std::string& path) {
  try {
    check(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(FileChecksTest, ACompletePngPasses) {
  const TestTempDir temp;
  WriteFileAtomically(temp / "a.png", kOnePixelPng);
  EXPECT_NO_THROW(CheckPngFile(temp / "a.png"));
}

TEST(FileChecksTest, ZeroByteTruncatedAndForeignFilesAreNamed) {
  const TestTempDir temp;
  const std::string zero = (temp / "zero.png").string();
  WriteFileAtomically(zero, "");
  EXPECT_THAT(ErrorOf(CheckPngFile, zero), HasSubstr(zero + ": not a PNG image (0 bytes"));

  const std::string cut = (temp / "cut.png").string();
  WriteFileAtomically(cut, kOnePixelPng.substr(0, 66));
  EXPECT_THAT(ErrorOf(CheckPngFile, cut), HasSubstr(cut + ": truncated PNG image (66 bytes"));

  const std::string text = (temp / "text.png").string();
  WriteFileAtomically(text, std::string(100, 'x'));
  EXPECT_THAT(ErrorOf(CheckPngFile, text),
              HasSubstr(text + ": not a PNG image (no PNG signature)"));

  std::string no_size = kOnePixelPng;
  no_size[19] = 0;  // width 0
  const std::string empty = (temp / "empty.png").string();
  WriteFileAtomically(empty, no_size);
  EXPECT_THAT(ErrorOf(CheckPngFile, empty), HasSubstr("header says 0 x 1 px"));

  const std::string missing = (temp / "missing.png").string();
  EXPECT_THAT(ErrorOf(CheckPngFile, missing), HasSubstr("cannot open " + missing));
}

TEST(FileChecksTest, AFifoIsRefusedWithoutBlocking) {
  const TestTempDir temp;
  const std::string fifo = (temp / "000000.png").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THAT(ErrorOf(CheckPngFile, fifo), HasSubstr(fifo + " is not a regular file"));
  EXPECT_THAT(ErrorOf(CheckVelodyneFile, fifo), HasSubstr(fifo + " is not a regular file"));
}

TEST(FileChecksTest, VelodyneSizeMustBeAMultipleOf16) {
  const TestTempDir temp;
  WriteFileAtomically(temp / "empty.bin", "");
  EXPECT_NO_THROW(CheckVelodyneFile(temp / "empty.bin"));
  WriteFileAtomically(temp / "two.bin", std::string(32, '\0'));
  EXPECT_NO_THROW(CheckVelodyneFile(temp / "two.bin"));
  const std::string odd = (temp / "odd.bin").string();
  WriteFileAtomically(odd, std::string(17, '\0'));
  EXPECT_THAT(ErrorOf(CheckVelodyneFile, odd),
              HasSubstr(odd + ": a velodyne scan must be a multiple of 16 bytes"));
  EXPECT_THAT(ErrorOf(CheckVelodyneFile, odd), HasSubstr("got 17 bytes"));
}

}  // namespace
}  // namespace stereodet
