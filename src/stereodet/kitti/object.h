// One line of a KITTI label or detection file, and KITTI's difficulty levels.
#ifndef STEREODET_KITTI_OBJECT_H_
#define STEREODET_KITTI_OBJECT_H_

#include <optional>
#include <string>
#include <string_view>

#include "stereodet/geometry/box.h"

namespace stereodet {

// A labelled or detected object, KITTI's 15 fields (labels) or 16 (detections, score last):
//   type truncated occluded alpha left top right bottom h w l x y z rotation_y [score]
// Units and frames as in geometry/box.h. Unknown class names are kept as they are.
// KITTI's sentinels: DontCare regions have truncated = -1, occluded = -1, alpha = -10, dimensions
// -1, location -1000 and rotation_y -10; a 2D-only detector writes the same "not estimated" 3D
// fields (see SetNot3DEstimated).
struct Object {
  std::string type;
  double truncated = 0.0;       // fraction of the object outside the image, [0, 1]
  int occluded = 0;             // 0 fully visible, 1 partly, 2 largely occluded, 3 unknown
  double alpha = 0.0;           // observation angle, radians, [-pi, pi]
  Box2D box;                    // px, left image (camera 2)
  Box3D box3d;                  // rect frame
  std::optional<double> score;  // detections only: confidence, higher is more confident

  bool IsDontCare() const { return type == "DontCare"; }
  // True when the 3D fields carry KITTI's "not estimated" values (h = w = l = -1).
  bool Has3D() const { return !(box3d.h == -1.0 && box3d.w == -1.0 && box3d.l == -1.0); }
  // Sets the 3D fields and alpha to KITTI's "not estimated" values (dimensions -1, location -1000,
  // rotation_y -10, alpha -10), for 2D detectors.
  void SetNot3DEstimated();
  bool operator==(const Object&) const = default;
};

// KITTI's difficulty levels. Easy objects are also Moderate and Hard; Moderate ones also Hard.
enum class Difficulty { kEasy = 0, kModerate = 1, kHard = 2 };
inline constexpr int kNumDifficulties = 3;
const char* DifficultyName(Difficulty difficulty);  // "Easy", "Moderate", "Hard"
// The difficulty named `text`, in any case ("easy", "Moderate", "HARD"), or nullopt.
std::optional<Difficulty> ParseDifficulty(std::string_view text);

// KITTI's per-level limits: minimum 2D box height (px), maximum occlusion level and truncation.
struct DifficultyLimits {
  double min_height_px;
  int max_occlusion;
  double max_truncation;
};
// {40, 0, 0.15}, {25, 1, 0.30}, {25, 2, 0.50} for Easy, Moderate, Hard.
DifficultyLimits KittiDifficultyLimits(Difficulty difficulty);

// Whether a label meets `difficulty`'s limits as KITTI's official devkit tests them: 2D height
// (bottom - top) > min, occluded <= max, truncated <= max. A label exactly 40.00 px tall is
// Moderate, not Easy; one exactly 25.00 px tall meets no level (the prclibo/kitti_eval fork kept
// `>= min`).
bool MeetsDifficulty(const Object& label, Difficulty difficulty);
// The easiest level the label meets, or nullopt if it meets none (too small, too occluded or too
// truncated even for Hard; DontCare regions).
std::optional<Difficulty> EasiestDifficulty(const Object& label);

}  // namespace stereodet

#endif  // STEREODET_KITTI_OBJECT_H_
