#include "stereodet/kitti/calib_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <utility>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// KITTI object training/calib/000000.txt, byte for byte.
constexpr char kKittiCalib000000[] =
    "P0: 7.215377000000e+02 0.000000000000e+00 6.095593000000e+02 0.000000000000e+00 "
    "0.000000000000e+00 7.215377000000e+02 1.728540000000e+02 0.000000000000e+00 "
    "0.000000000000e+00 "
    "0.000000000000e+00 1.000000000000e+00 0.000000000000e+00\n"
    "P1: 7.215377000000e+02 0.000000000000e+00 6.095593000000e+02 -3.875744000000e+02 "
    "0.000000000000e+00 7.215377000000e+02 1.728540000000e+02 0.000000000000e+00 "
    "0.000000000000e+00 "
    "0.000000000000e+00 1.000000000000e+00 0.000000000000e+00\n"
    "P2: 7.215377000000e+02 0.000000000000e+00 6.095593000000e+02 4.485728000000e+01 "
    "0.000000000000e+00 7.215377000000e+02 1.728540000000e+02 2.163791000000e-01 "
    "0.000000000000e+00 "
    "0.000000000000e+00 1.000000000000e+00 2.745884000000e-03\n"
    "P3: 7.215377000000e+02 0.000000000000e+00 6.095593000000e+02 -3.395242000000e+02 "
    "0.000000000000e+00 7.215377000000e+02 1.728540000000e+02 2.199936000000e+00 "
    "0.000000000000e+00 "
    "0.000000000000e+00 1.000000000000e+00 2.729905000000e-03\n"
    "R0_rect: 9.999239000000e-01 9.837760000000e-03 -7.445048000000e-03 -9.869795000000e-03 "
    "9.999421000000e-01 -4.278459000000e-03 7.402527000000e-03 4.351614000000e-03 "
    "9.999631000000e-01\n"
    "Tr_velo_to_cam: 7.533745000000e-03 -9.999714000000e-01 -6.166020000000e-04 "
    "-4.069766000000e-03 1.480249000000e-02 7.280733000000e-04 -9.998902000000e-01 "
    "-7.631618000000e-02 9.998621000000e-01 7.523790000000e-03 1.480755000000e-02 "
    "-2.717806000000e-01\n"
    "Tr_imu_to_velo: 9.999976000000e-01 7.553071000000e-04 -2.035826000000e-03 "
    "-8.086759000000e-01 -7.854027000000e-04 9.998898000000e-01 -1.482298000000e-02 "
    "3.195559000000e-01 2.024406000000e-03 1.482454000000e-02 9.998881000000e-01 "
    "-7.997231000000e-01\n"
    "\n";

void ExpectSameCalibration(const Calibration& a, const Calibration& b) {
  for (int i = 0; i < 4; ++i) EXPECT_EQ(a.projection[i], b.projection[i]) << "P" << i;
  EXPECT_EQ(a.rect_from_cam0, b.rect_from_cam0);
  EXPECT_EQ(a.cam0_from_velo.matrix(), b.cam0_from_velo.matrix());
  EXPECT_EQ(a.velo_from_imu.matrix(), b.velo_from_imu.matrix());
}

ParseError ExpectParseError(const std::string& text) {
  try {
    ParseCalibration(text, "calib/000042.txt");
  } catch (const ParseError& e) {
    return e;
  }
  ADD_FAILURE() << "no ParseError for:\n" << text;
  return ParseError("", 0, "", "");
}

// The KITTI text with line `index` (0-based) replaced.
std::string WithLine(int index, const std::string& replacement) {
  std::string text = kKittiCalib000000;
  size_t start = 0;
  for (int i = 0; i < index; ++i) start = text.find('\n', start) + 1;
  const size_t end = text.find('\n', start);
  return text.replace(start, end - start, replacement);
}

TEST(CalibIoTest, ParsesTheRealKittiFileToTheKittiLikeCalibration) {
  const Calibration calib = ParseCalibration(kKittiCalib000000, "calib/000000.txt");
  ExpectSameCalibration(calib, KittiLikeCalibration());
  EXPECT_EQ(calib.projection[2](0, 3), 4.485728e+01);
  EXPECT_EQ(calib.cam0_from_velo.matrix().row(3), Eigen::RowVector4d(0, 0, 0, 1));
  EXPECT_NEAR(calib.BaselineM(), 0.54, 0.01);
}

TEST(CalibIoTest, RealKittiFileRoundTripsByteForByte) {
  EXPECT_EQ(FormatCalibration(ParseCalibration(kKittiCalib000000, "x")), kKittiCalib000000);
  EXPECT_EQ(FormatCalibration(KittiLikeCalibration()), kKittiCalib000000);
}

TEST(CalibIoTest, ParseOfFormatIsIdentityOnRandomCalibrations) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-30, 30);
  for (int trial = 0; trial < 200; ++trial) {
    Calibration calib;
    auto number = [&]() {
      const double v = u(rng) * std::pow(10.0, exponent(rng));
      return trial % 2 == 0 ? v : std::round(v * 1e6) / 1e6;
    };
    for (auto& p : calib.projection) {
      for (int i = 0; i < 12; ++i) p(i / 4, i % 4) = number();
    }
    for (int i = 0; i < 9; ++i) calib.rect_from_cam0(i / 3, i % 3) = number();
    for (int i = 0; i < 12; ++i) calib.cam0_from_velo.matrix()(i / 4, i % 4) = number();
    for (int i = 0; i < 12; ++i) calib.velo_from_imu.matrix()(i / 4, i % 4) = number();
    const std::string text = FormatCalibration(calib);
    ExpectSameCalibration(ParseCalibration(text, "x"), calib);
    EXPECT_EQ(FormatCalibration(ParseCalibration(text, "x")), text);
  }
}

TEST(CalibIoTest, TrackingSpellingsAndMissingImuAreAccepted) {
  // KITTI tracking files: "R_rect", "Tr_velo_cam", "Tr_imu_velo", written without the colon.
  std::string text = WithLine(4,
                              "R_rect 9.999239e-01 9.837760e-03 -7.445048e-03 -9.869795e-03 "
                              "9.999421e-01 -4.278459e-03 7.402527e-03 4.351614e-03 9.999631e-01");
  text = WithLine(5,
                  "Tr_velo_cam 7.533745e-03 -9.999714e-01 -6.166020e-04 -4.069766e-03 "
                  "1.480249e-02 7.280733e-04 -9.998902e-01 -7.631618e-02 9.998621e-01 "
                  "7.523790e-03 1.480755e-02 -2.717806e-01");
  // Drop Tr_imu_to_velo: it is optional.
  text = text.substr(0, text.find("Tr_imu_to_velo"));
  const Calibration calib = ParseCalibration(text, "x");
  EXPECT_EQ(calib.rect_from_cam0, KittiLikeCalibration().rect_from_cam0);
  EXPECT_EQ(calib.cam0_from_velo.matrix(), KittiLikeCalibration().cam0_from_velo.matrix());
  EXPECT_TRUE(calib.velo_from_imu.matrix().isIdentity(0.0));
}

TEST(CalibIoTest, IgnoresBlankLinesCrlfAndOtherKeys) {
  const std::string lf = std::string("calib_time: 09-Jan-2012 13:57:47\n\n") + kKittiCalib000000;
  std::string text;
  for (char c : lf) {
    if (c == '\n') text.push_back('\r');
    text.push_back(c);
  }
  ExpectSameCalibration(ParseCalibration(text, "x"), KittiLikeCalibration());
}

TEST(CalibIoTest, ALeadingUtf8ByteOrderMarkIsIgnored) {
  // Without the strip the first key would read "\xef\xbb\xbfP0", unknown, and P0 be "missing".
  ExpectSameCalibration(ParseCalibration(std::string("\xEF\xBB\xBF") + kKittiCalib000000, "x"),
                        KittiLikeCalibration());
}

TEST(CalibIoErrorTest, MissingKeyIsNamed) {
  const ParseError e = ExpectParseError(WithLine(2, ""));
  EXPECT_EQ(e.file(), "calib/000042.txt");
  EXPECT_EQ(e.line(), 0);
  EXPECT_EQ(e.field(), "P2");
  EXPECT_THAT(e.message(), HasSubstr("missing"));
  EXPECT_EQ(ExpectParseError("").field(), "P0");
}

TEST(CalibIoErrorTest, WrongNumberCountNamesLineAndKey) {
  const ParseError few = ExpectParseError(WithLine(4, "R0_rect: 1 0 0 0 1 0 0 0"));
  EXPECT_EQ(few.line(), 5);
  EXPECT_EQ(few.field(), "R0_rect");
  EXPECT_THAT(few.message(), HasSubstr("expected 9 numbers (3x3), got 8"));
  const ParseError many = ExpectParseError(WithLine(1, "P1: 1 2 3 4 5 6 7 8 9 10 11 12 13"));
  EXPECT_EQ(many.line(), 2);
  EXPECT_EQ(many.field(), "P1");
  EXPECT_THAT(many.message(), HasSubstr("got 13"));
  EXPECT_EQ(ExpectParseError(WithLine(0, "P0:")).field(), "P0");
}

TEST(CalibIoErrorTest, NonNumbersNanAndInfinityNameTheEntry) {
  const ParseError text = ExpectParseError(WithLine(2, "P2: 1 2 3 4 5 6 7 abc 9 10 11 12"));
  EXPECT_EQ(text.line(), 3);
  EXPECT_EQ(text.field(), "P2(1,3)");
  EXPECT_THAT(text.message(), HasSubstr("'abc' is not a number"));
  EXPECT_THAT(std::string(text.what()), HasSubstr("calib/000042.txt:3: field P2(1,3):"));
  const ParseError nan =
      ExpectParseError(WithLine(5, "Tr_velo_to_cam: nan 2 3 4 5 6 7 8 9 10 11 12"));
  EXPECT_EQ(nan.field(), "Tr_velo_to_cam(0,0)");
  EXPECT_THAT(nan.message(), HasSubstr("not a finite number"));
  const ParseError inf = ExpectParseError(WithLine(4, "R0_rect: 1 0 0 0 1 0 0 0 -inf"));
  EXPECT_EQ(inf.field(), "R0_rect(2,2)");
  const ParseError huge = ExpectParseError(WithLine(3, "P3: 1e999 0 0 0 0 0 0 0 0 0 0 0"));
  EXPECT_EQ(huge.field(), "P3(0,0)");
}

TEST(CalibIoErrorTest, DuplicateKeysIncludingAliases) {
  const ParseError e =
      ExpectParseError(std::string(kKittiCalib000000) + "R_rect: 1 0 0 0 1 0 0 0 1\n");
  EXPECT_EQ(e.line(), 9);
  EXPECT_EQ(e.field(), "R0_rect");
  EXPECT_THAT(e.message(), HasSubstr("duplicate key (first on line 5)"));
}

TEST(CalibIoTest, FormatRejectsNonFinite) {
  Calibration calib = KittiLikeCalibration();
  calib.projection[3](2, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(FormatCalibration(calib), std::invalid_argument);
}

TEST(CalibIoTest, WriteAndRead) {
  const TestTempDir temp;
  const fs::path dir = temp.path();
  WriteCalibration(dir / "calib" / "000000.txt", KittiLikeCalibration());
  ExpectSameCalibration(ReadCalibration(dir / "calib" / "000000.txt"), KittiLikeCalibration());
  EXPECT_THROW(ReadCalibration(dir / "calib" / "000001.txt"), std::runtime_error);
  EXPECT_THROW(ReadCalibration(dir / "calib"), std::runtime_error);  // a folder
}

// CheckCalibration: what a stereo pipeline cannot use is named by file and field.
ParseError ExpectCheckError(const Calibration& calib) {
  try {
    CheckCalibration(calib, "calib/000042.txt");
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), "calib/000042.txt");
    return e;
  }
  ADD_FAILURE() << "no ParseError";
  return ParseError("", 0, "", "");
}

TEST(CalibCheckTest, TheRealKittiFilePasses) {
  EXPECT_NO_THROW(CheckCalibration(ParseCalibration(kKittiCalib000000, "x"), "x"));
  EXPECT_NO_THROW(CheckCalibration(KittiLikeCalibration(), "x"));
}

TEST(CalibCheckTest, AllZeroRotationsAreRejected) {
  Calibration calib = KittiLikeCalibration();
  calib.rect_from_cam0.setZero();
  ParseError e = ExpectCheckError(calib);
  EXPECT_EQ(e.field(), "R0_rect");
  EXPECT_THAT(e.message(), HasSubstr("not a rotation (det 0"));

  calib = KittiLikeCalibration();
  calib.cam0_from_velo.matrix().setZero();
  EXPECT_EQ(ExpectCheckError(calib).field(), "Tr_velo_to_cam");

  // A scale of 2 is not KITTI's rounding; a reflection (det -1) is not a rotation either.
  calib = KittiLikeCalibration();
  calib.rect_from_cam0 *= 2;
  EXPECT_EQ(ExpectCheckError(calib).field(), "R0_rect");
  calib = KittiLikeCalibration();
  calib.rect_from_cam0 = Eigen::Vector3d(1, 1, -1).asDiagonal();
  EXPECT_THAT(ExpectCheckError(calib).message(), HasSubstr("det -1"));
  // KITTI's printed rotations are off by about 1e-6: accepted.
  calib = KittiLikeCalibration();
  calib.rect_from_cam0(0, 1) += 1e-4;
  EXPECT_NO_THROW(CheckCalibration(calib, "x"));
}

TEST(CalibCheckTest, FocalLengthsOutsideTheRangeAreNamed) {
  Calibration calib = KittiLikeCalibration();
  calib.projection[2](0, 0) = 1e300;
  ParseError e = ExpectCheckError(calib);
  EXPECT_EQ(e.field(), "P2(0,0)");
  EXPECT_THAT(e.message(), HasSubstr("focal length 1e+300 px is outside [1, 1e+06]"));

  calib = KittiLikeCalibration();
  calib.projection[3](1, 1) = 0;
  EXPECT_EQ(ExpectCheckError(calib).field(), "P3(1,1)");
  calib = KittiLikeCalibration();
  calib.projection[2](1, 1) = -721.5377;
  EXPECT_EQ(ExpectCheckError(calib).field(), "P2(1,1)");
}

TEST(CalibCheckTest, BaselineMustPutCamera3RightOfCamera2) {
  Calibration calib = KittiLikeCalibration();
  calib.projection[3] = calib.projection[2];  // one place: no baseline
  ParseError e = ExpectCheckError(calib);
  EXPECT_EQ(e.field(), "P3");
  EXPECT_THAT(e.message(), HasSubstr("stereo baseline 0 m"));

  calib = KittiLikeCalibration();
  std::swap(calib.projection[2], calib.projection[3]);  // camera 3 on the left
  EXPECT_THAT(ExpectCheckError(calib).message(), HasSubstr("camera 3 must be right of camera 2"));
}

TEST(CalibCheckTest, ReadCalibrationChecksAndNamesTheFile) {
  const TestTempDir temp;
  const fs::path path = temp / "000007.txt";
  // R0_rect all zero, as the audit's file had it.
  WriteFileAtomically(path, WithLine(4, "R0_rect: 0 0 0 0 0 0 0 0 0"));
  try {
    ReadCalibration(path);
    ADD_FAILURE() << "no error";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), path.string());
    EXPECT_EQ(e.field(), "R0_rect");
    EXPECT_THAT(e.what(), HasSubstr(path.string() + ": field R0_rect: not a rotation"));
  }
  // ParseCalibration alone checks the syntax only: the same text parses.
  EXPECT_NO_THROW(ParseCalibration(WithLine(4, "R0_rect: 0 0 0 0 0 0 0 0 0"), "x"));
}

}  // namespace
}  // namespace stereodet
