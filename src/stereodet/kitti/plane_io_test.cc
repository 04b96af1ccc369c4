#include "stereodet/kitti/plane_io.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "stereodet/util/check.h"

namespace stereodet {
namespace {

TEST(PlaneIoTest, ParsesAnAvodStylePlaneFile) {
  // A file as KITTI tools write them (upper-case header words, CRLF line ends tolerated).
  const Eigen::Vector4d p = ParseGroundPlane(
      "# Plane\r\nWIDTH 4\r\nHEIGHT 1\r\n0.000000e+00 -1.000000e+00 0.000000e+00 1.650000e+00\r\n",
      "p.txt");
  EXPECT_EQ(p, Eigen::Vector4d(0.0, -1.0, 0.0, 1.65));
}

TEST(PlaneIoTest, FormatReadsBack) {
  // A plane tilted by 0.02 rad about x: the normal stays unit length.
  const Eigen::Vector4d plane(0.0, -std::cos(0.02), std::sin(0.02), 1.7);
  const std::string text = FormatGroundPlane(plane);
  EXPECT_EQ(text.substr(0, 25), "# Plane\nWidth 4\nHeight 1\n");
  const Eigen::Vector4d back = ParseGroundPlane(text, "t");
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(back[k], plane[k], 1e-6);
}

TEST(PlaneIoTest, ErrorsNameTheLine) {
  const auto line_of = [](const std::string& text) {
    try {
      ParseGroundPlane(text, "bad.txt");
    } catch (const ParseError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.txt"), std::string::npos) << e.what();
      return e.line();
    }
    ADD_FAILURE() << "accepted: " << text;
    return -1;
  };
  EXPECT_EQ(line_of("# Matrix\nWidth 4\nHeight 1\n0 -1 0 1.65\n"), 1);
  EXPECT_EQ(line_of("# Plane\nWidth 3\nHeight 1\n0 -1 0 1.65\n"), 2);
  EXPECT_EQ(line_of("# Plane\nWidth 4\nHeight 1\n"), 4);
  EXPECT_EQ(line_of("# Plane\nWidth 4\nHeight 1\n0 -1 0\n"), 4);
  EXPECT_EQ(line_of("# Plane\nWidth 4\nHeight 1\n0 -1 nan 1.65\n"), 4);
  EXPECT_EQ(line_of("# Plane\nWidth 4\nHeight 1\n0 -2 0 1.65\n"), 4);  // not a unit normal
  EXPECT_THROW(FormatGroundPlane(Eigen::Vector4d(0, -2, 0, 1)), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
