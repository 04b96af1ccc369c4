#include "stereodet/kitti/object.h"

#include <algorithm>
#include <cctype>

namespace stereodet {

void Object::SetNot3DEstimated() {
  alpha = -10.0;
  box3d.h = box3d.w = box3d.l = -1.0;
  box3d.location = Eigen::Vector3d(-1000.0, -1000.0, -1000.0);
  box3d.rotation_y = -10.0;
}

const char* DifficultyName(Difficulty difficulty) {
  switch (difficulty) {
    case Difficulty::kEasy:
      return "Easy";
    case Difficulty::kModerate:
      return "Moderate";
    case Difficulty::kHard:
      return "Hard";
  }
  return "?";
}

std::optional<Difficulty> ParseDifficulty(std::string_view text) {
  for (Difficulty d : {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard}) {
    const std::string_view name = DifficultyName(d);
    if (text.size() == name.size() &&
        std::equal(text.begin(), text.end(), name.begin(), [](char a, char b) {
          return std::tolower(static_cast<unsigned char>(a)) ==
                 std::tolower(static_cast<unsigned char>(b));
        })) {
      return d;
    }
  }
  return std::nullopt;
}

DifficultyLimits KittiDifficultyLimits(Difficulty difficulty) {
  switch (difficulty) {
    case Difficulty::kEasy:
      return {40.0, 0, 0.15};
    case Difficulty::kModerate:
      return {25.0, 1, 0.30};
    case Difficulty::kHard:
      return {25.0, 2, 0.50};
  }
  return {25.0, 2, 0.50};
}

bool MeetsDifficulty(const Object& label, Difficulty difficulty) {
  if (label.IsDontCare()) return false;
  const DifficultyLimits limits = KittiDifficultyLimits(difficulty);
  // KITTI's official devkit (devkit_object, evaluate_object.cpp) ignores a label when
  // `height <= MIN_HEIGHT`: a label exactly 40.00 px tall is not Easy, one of 25.00 px meets no
  // level.
  return label.box.Height() > limits.min_height_px && label.occluded <= limits.max_occlusion &&
         label.truncated <= limits.max_truncation;
}

std::optional<Difficulty> EasiestDifficulty(const Object& label) {
  for (Difficulty d : {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard}) {
    if (MeetsDifficulty(label, d)) return d;
  }
  return std::nullopt;
}

}  // namespace stereodet
