#include "stereodet/synth/labels.h"

#include <gtest/gtest.h>

#include <cmath>

#include "stereodet/synth/camera.h"
#include "stereodet/synth/test_scene.h"

namespace stereodet {
namespace {

using testing::AddBoxObject;
using testing::GroundOnlyScene;
using testing::MakeBox3D;

// Half KITTI resolution keeps the tests fast; the label thresholds scale with the image size.
constexpr int kWidth = 621, kHeight = 188;

cv::Mat ObjectIds(const Scene& scene, const Calibration& calib) {
  RenderRequest request;
  request.width = kWidth;
  request.height = kHeight;
  request.object_ids = true;
  RenderOptions options;
  options.shadows = false;
  return RenderCamera(scene, calib, request, options).object_id;
}

// The bounding box of the projected corners of a box (all in front of the camera).
Box2D ProjectedBox(const Box3D& box, const Calibration& calib) {
  const Eigen::Matrix<double, 3, 8> corners = Corners(box);
  Box2D b{1e9, 1e9, -1e9, -1e9};
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector2d p = calib.ProjectRectToImage(corners.col(i), 2);
    b.left = std::min(b.left, p.x()), b.right = std::max(b.right, p.x());
    b.top = std::min(b.top, p.y()), b.bottom = std::max(b.bottom, p.y());
  }
  return b;
}

TEST(LabelsTest, BoxAtKnownPoseGivesExpectedLabel) {
  const Calibration calib = SynthCalibration(kWidth, kHeight);
  Scene scene = GroundOnlyScene();
  const Box3D box = MakeBox3D(1.5, 1.6, 4.0, 2.0, 1.65, 15.0, 0.3);
  AddBoxObject(scene, "Car", box);
  scene.Finalize();
  const LabelSet set = MakeLabels(scene, calib, ObjectIds(scene, calib));
  ASSERT_EQ(set.labels.size(), 1u);
  const Object& label = set.labels[0];
  EXPECT_EQ(label.type, "Car");
  EXPECT_EQ(set.source[0], 0);
  EXPECT_EQ(label.truncated, 0.0);
  EXPECT_EQ(label.occluded, 0);
  EXPECT_EQ(label.box3d, box);
  EXPECT_NEAR(label.alpha, AlphaFromRotationY(0.3, box.location), 0.005);
  const Box2D expected = ProjectedBox(box, calib);
  EXPECT_NEAR(label.box.left, expected.left, 0.006);
  EXPECT_NEAR(label.box.top, expected.top, 0.006);
  EXPECT_NEAR(label.box.right, expected.right, 0.006);
  EXPECT_NEAR(label.box.bottom, expected.bottom, 0.006);
  // Two decimals, as in KITTI's files.
  EXPECT_DOUBLE_EQ(label.box.left, std::round(label.box.left * 100) / 100);
}

// A thin board facing the camera whose centre projects onto column `u_centre` at depth 10 m.
Box3D Board(const Calibration& calib, double u_centre) {
  const Eigen::Vector3d centre = calib.UnprojectImageToRect(Eigen::Vector2d(u_centre, 75.0), 10.0);
  return MakeBox3D(1.0, 0.02, 2.0, centre.x(), 1.65, 10.0, 0.0);
}

TEST(LabelsTest, BoardCutByTheImageBorderIsHalfTruncated) {
  const Calibration calib = SynthCalibration(kWidth, kHeight);
  Scene scene = GroundOnlyScene();
  AddBoxObject(scene, "Car", Board(calib, 0.0));
  scene.Finalize();
  const LabelSet set = MakeLabels(scene, calib, ObjectIds(scene, calib));
  ASSERT_EQ(set.labels.size(), 1u);
  EXPECT_NEAR(set.labels[0].truncated, 0.5, 0.02);
  EXPECT_EQ(set.labels[0].box.left, 0.0);  // clipped to the image
  EXPECT_EQ(set.labels[0].occluded, 0);
}

TEST(LabelsTest, OcclusionLevelFollowsTheVisibleFraction) {
  const Calibration calib = SynthCalibration(kWidth, kHeight);
  for (const auto& [cover, expected_level] :
       std::vector<std::pair<double, int>>{{0.1, 0}, {0.5, 1}, {0.75, 2}, {0.95, 3}}) {
    Scene scene = GroundOnlyScene();
    const Box3D board = Board(calib, 300.0);
    AddBoxObject(scene, "Car", board);
    // A background wall at 5 m covering the left `cover` of the board's width in the image.
    const std::vector<ObjectVisibility> before =
        MeasureVisibility(scene, calib, ObjectIds(scene, calib), {});
    ASSERT_EQ(before.size(), 1u);
    const Box2D b = before[0].box;
    const double u_edge = b.left + cover * b.Width();
    const Eigen::Vector3d edge = calib.UnprojectImageToRect(Eigen::Vector2d(u_edge, 75.0), 5.0);
    scene.primitives.push_back(
        MakeBox(Eigen::Vector3f(static_cast<float>(edge.x() - 5.0), 0.0f, 5.0f),
                Eigen::Vector3f(5.0f, 5.0f, 0.05f), Eigen::Matrix3f::Identity(), 1));
    scene.Finalize();
    const cv::Mat ids = ObjectIds(scene, calib);
    const std::vector<ObjectVisibility> after = MeasureVisibility(scene, calib, ids, {});
    ASSERT_EQ(after.size(), 1u);
    EXPECT_NEAR(after[0].visible_fraction, 1.0 - cover, 0.03) << "cover " << cover;
    const LabelSet set = MakeLabels(scene, calib, ids);
    ASSERT_EQ(set.labels.size(), 1u);
    EXPECT_EQ(set.labels[0].occluded, expected_level) << "cover " << cover;
    // The 2D box is amodal: it does not shrink to the visible part.
    EXPECT_NEAR(set.labels[0].box.left, b.left, 0.01);
  }
}

TEST(LabelsTest, FarAndSmallObjectsBecomeDontCare) {
  const Calibration calib = SynthCalibration(kWidth, kHeight);
  Scene scene = GroundOnlyScene();
  AddBoxObject(scene, "Car", MakeBox3D(1.5, 1.6, 4.0, 0.0, 1.65, 85.0, 0.0));          // too far
  AddBoxObject(scene, "Pedestrian", MakeBox3D(0.4, 0.3, 0.3, -3.0, 1.65, 40.0, 0.0));  // tiny
  AddBoxObject(scene, "Car", MakeBox3D(1.5, 1.6, 4.0, 3.0, 1.65, 20.0, 0.0));          // labelled
  AddBoxObject(scene, "Car", MakeBox3D(1.5, 1.6, 4.0, 0.0, 1.65, -20.0, 0.0));         // behind
  scene.Finalize();
  const LabelSet set = MakeLabels(scene, calib, ObjectIds(scene, calib));
  ASSERT_EQ(set.labels.size(), 2u);
  EXPECT_EQ(set.labels[0].type, "Car");
  EXPECT_EQ(set.source[0], 2);
  EXPECT_EQ(set.labels[1].type, "DontCare");  // DontCare regions come last
  EXPECT_EQ(set.source[1], 0);
  EXPECT_EQ(set.labels[1].occluded, -1);
  EXPECT_FALSE(set.labels[1].Has3D());
}

TEST(LabelsTest, RejectsBadOptions) {
  LabelOptions options;
  options.visible_fraction_occluded_1 = 0.9;  // above level 0's threshold
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
