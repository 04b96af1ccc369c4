#include "stereodet/kitti/object.h"

#include <gtest/gtest.h>

namespace stereodet {
namespace {

Object MakeLabel(double height_px, int occluded, double truncated,
                 const std::string& type = "Car") {
  Object o;
  o.type = type;
  o.box = {100.0, 200.0, 150.0, 200.0 + height_px};
  o.occluded = occluded;
  o.truncated = truncated;
  return o;
}

TEST(ObjectTest, DifficultyNamesAndLimits) {
  EXPECT_STREQ(DifficultyName(Difficulty::kEasy), "Easy");
  EXPECT_STREQ(DifficultyName(Difficulty::kModerate), "Moderate");
  EXPECT_STREQ(DifficultyName(Difficulty::kHard), "Hard");
  const DifficultyLimits easy = KittiDifficultyLimits(Difficulty::kEasy);
  EXPECT_EQ(easy.min_height_px, 40.0);
  EXPECT_EQ(easy.max_occlusion, 0);
  EXPECT_EQ(easy.max_truncation, 0.15);
  const DifficultyLimits hard = KittiDifficultyLimits(Difficulty::kHard);
  EXPECT_EQ(hard.min_height_px, 25.0);
  EXPECT_EQ(hard.max_occlusion, 2);
  EXPECT_EQ(hard.max_truncation, 0.50);
}

TEST(ObjectTest, DifficultyNamesParseBackInAnyCase) {
  for (Difficulty d : {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard}) {
    EXPECT_EQ(ParseDifficulty(DifficultyName(d)), d) << DifficultyName(d);
  }
  EXPECT_EQ(ParseDifficulty("easy"), Difficulty::kEasy);
  EXPECT_EQ(ParseDifficulty("MODERATE"), Difficulty::kModerate);
  EXPECT_EQ(ParseDifficulty("hArD"), Difficulty::kHard);
  for (const char* bad : {"", "Eas", "Easy ", "medium", "0", "Easiest"}) {
    EXPECT_EQ(ParseDifficulty(bad), std::nullopt) << "'" << bad << "'";
  }
}

// The official devkit's rule: a label is ignored when height <= the minimum (40 / 25 / 25 px),
// occluded > max or truncated > max; so exactly 40.00 px is not Easy and exactly 25.00 px is
// nothing.
TEST(ObjectTest, EasiestDifficultyAtTheBoundaries) {
  EXPECT_EQ(EasiestDifficulty(MakeLabel(40.01, 0, 0.15)), Difficulty::kEasy);
  EXPECT_EQ(EasiestDifficulty(MakeLabel(40.0, 0, 0.15)), Difficulty::kModerate);
  EXPECT_EQ(EasiestDifficulty(MakeLabel(39.99, 0, 0.0)), Difficulty::kModerate);
  EXPECT_EQ(EasiestDifficulty(MakeLabel(100.0, 1, 0.0)), Difficulty::kModerate);
  EXPECT_EQ(EasiestDifficulty(MakeLabel(100.0, 0, 0.16)), Difficulty::kModerate);
  EXPECT_EQ(EasiestDifficulty(MakeLabel(25.01, 1, 0.30)), Difficulty::kModerate);
  EXPECT_EQ(EasiestDifficulty(MakeLabel(25.0, 1, 0.30)), std::nullopt);
  EXPECT_EQ(EasiestDifficulty(MakeLabel(25.0, 0, 0.0)), std::nullopt);
  EXPECT_EQ(EasiestDifficulty(MakeLabel(100.0, 2, 0.0)), Difficulty::kHard);
  EXPECT_EQ(EasiestDifficulty(MakeLabel(100.0, 0, 0.31)), Difficulty::kHard);
  EXPECT_EQ(EasiestDifficulty(MakeLabel(24.99, 0, 0.0)), std::nullopt);
  EXPECT_EQ(EasiestDifficulty(MakeLabel(100.0, 3, 0.0)), std::nullopt);
  EXPECT_EQ(EasiestDifficulty(MakeLabel(100.0, 0, 0.51)), std::nullopt);
  EXPECT_EQ(EasiestDifficulty(MakeLabel(100.0, 0, 0.0, "DontCare")), std::nullopt);
}

// Heights as KITTI's two-decimal files give them: bottom - top of the parsed numbers.
TEST(ObjectTest, TwoDecimalBoxesExactly25And40PxTall) {
  Object o = MakeLabel(0.0, 0, 0.0);
  o.box = {612.37, 150.37, 700.12, 190.37};  // 190.37 - 150.37 == 40.0 in double
  ASSERT_EQ(o.box.Height(), 40.0);
  EXPECT_FALSE(MeetsDifficulty(o, Difficulty::kEasy));
  EXPECT_TRUE(MeetsDifficulty(o, Difficulty::kModerate));
  EXPECT_TRUE(MeetsDifficulty(o, Difficulty::kHard));
  o.box = {612.37, 180.12, 700.12, 205.12};  // 25.0
  ASSERT_EQ(o.box.Height(), 25.0);
  EXPECT_FALSE(MeetsDifficulty(o, Difficulty::kHard));
  o.box.bottom = 205.13;
  EXPECT_TRUE(MeetsDifficulty(o, Difficulty::kHard));
  EXPECT_FALSE(MeetsDifficulty(o, Difficulty::kEasy));
}

TEST(ObjectTest, EasyImpliesModerateImpliesHard) {
  for (double h : {10.0, 25.0, 30.0, 40.0, 80.0}) {
    for (int occ = 0; occ <= 3; ++occ) {
      for (double tr : {0.0, 0.15, 0.2, 0.3, 0.4, 0.5, 0.9}) {
        const Object o = MakeLabel(h, occ, tr);
        if (MeetsDifficulty(o, Difficulty::kEasy)) {
          EXPECT_TRUE(MeetsDifficulty(o, Difficulty::kModerate));
        }
        if (MeetsDifficulty(o, Difficulty::kModerate)) {
          EXPECT_TRUE(MeetsDifficulty(o, Difficulty::kHard));
        }
      }
    }
  }
}

TEST(ObjectTest, NotEstimated3D) {
  Object o = MakeLabel(50, 0, 0);
  o.box3d.h = o.box3d.w = o.box3d.l = 1.0;
  EXPECT_TRUE(o.Has3D());
  o.SetNot3DEstimated();
  EXPECT_FALSE(o.Has3D());
  EXPECT_EQ(o.alpha, -10.0);
  EXPECT_EQ(o.box3d.location, Eigen::Vector3d(-1000, -1000, -1000));
  EXPECT_EQ(o.box3d.rotation_y, -10.0);
  EXPECT_EQ(o.box, (Box2D{100.0, 200.0, 150.0, 250.0}));  // the 2D box stays
}

}  // namespace
}  // namespace stereodet
