#include "stereodet/eval/random_frames.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "stereodet/geometry/box.h"
#include "stereodet/kitti/dataset.h"

namespace stereodet {

namespace {

// KITTI's camera 2 (rounded) and image size.
constexpr double kFocalPx = 721.5377, kCxPx = 609.5593, kCyPx = 172.854;
constexpr double kImageWidth = 1242.0, kImageHeight = 375.0;

struct Shape {
  const char* type;
  double h, w, l;
};
constexpr Shape kShapes[] = {{"Car", 1.53, 1.63, 3.88},
                             {"Van", 2.2, 1.9, 5.1},
                             {"Pedestrian", 1.76, 0.66, 0.84},
                             {"Cyclist", 1.74, 0.6, 1.76},
                             {"Person_sitting", 1.27, 0.54, 0.8}};

// Projects the box and fills the 2D box and truncation; false if nothing of it is in the image.
bool ProjectBox(Object* o) {
  const Eigen::Matrix<double, 3, 8> corners = Corners(o->box3d);
  double left = 1e9, right = -1e9, top = 1e9, bottom = -1e9;
  for (int c = 0; c < 8; ++c) {
    const double z = std::max(corners(2, c), 0.1);
    const double u = kFocalPx * corners(0, c) / z + kCxPx;
    const double v = kFocalPx * corners(1, c) / z + kCyPx;
    left = std::min(left, u);
    right = std::max(right, u);
    top = std::min(top, v);
    bottom = std::max(bottom, v);
  }
  const double full = (right - left) * (bottom - top);
  Box2D clipped{std::clamp(left, 0.0, kImageWidth - 1), std::clamp(top, 0.0, kImageHeight - 1),
                std::clamp(right, 0.0, kImageWidth - 1), std::clamp(bottom, 0.0, kImageHeight - 1)};
  if (clipped.Width() < 2 || clipped.Height() < 2 || !(full > 0)) return false;
  o->box = clipped;
  o->truncated = std::clamp(1.0 - clipped.Area() / full, 0.0, 1.0);
  return true;
}

double Alpha(const Object& o) {
  double a = o.box3d.rotation_y - std::atan2(o.box3d.location.x(), o.box3d.location.z());
  while (a >= M_PI) a -= 2 * M_PI;
  while (a < -M_PI) a += 2 * M_PI;
  return a;
}

double Round(double v, int decimals) {
  if (decimals <= 0) return v;
  const double scale = std::pow(10.0, decimals);
  return std::round(v * scale) / scale;
}

}  // namespace

std::vector<EvalFrame> RandomFrames(const RandomFramesOptions& options) {
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto U = [&](double a, double b) { return a + (b - a) * uniform(rng); };
  std::poisson_distribution<int> num_labels(options.labels_per_frame);
  std::poisson_distribution<int> num_fp(options.false_positives_per_frame);

  auto random_box = [&](const Shape& shape, Object* o) {
    const double z = options.crowded ? U(6.0, 14.0) : U(4.0, 60.0);
    const double x = options.crowded ? U(-4.0, 4.0) : std::clamp(U(-0.6, 0.6) * z, -20.0, 20.0);
    o->box3d.h = shape.h * U(0.9, 1.1);
    o->box3d.w = shape.w * U(0.9, 1.1);
    o->box3d.l = shape.l * U(0.9, 1.1);
    o->box3d.location = Eigen::Vector3d(x, 1.65 + 0.1 * normal(rng), z);
    o->box3d.rotation_y = U(-M_PI, M_PI);
  };

  std::vector<EvalFrame> frames(options.num_frames);
  for (int f = 0; f < options.num_frames; ++f) {
    EvalFrame& frame = frames[f];
    frame.id = FrameId(f);
    const int n = num_labels(rng);
    for (int k = 0; k < n; ++k) {
      Object label;
      const double r = uniform(rng);
      if (r < 0.1) {  // DontCare region
        label.type = "DontCare";
        const double w = U(10, 120), h = U(8, 60);
        const double left = U(0, kImageWidth - w), top = U(120, kImageHeight - h);
        label.box = Box2D{left, top, left + w, top + h};
        label.SetNot3DEstimated();
        label.truncated = -1;
        label.occluded = -1;
        frame.labels.push_back(label);
        continue;
      }
      const Shape& shape = r < 0.62   ? kShapes[0]
                           : r < 0.68 ? kShapes[1]
                           : r < 0.84 ? kShapes[2]
                           : r < 0.97 ? kShapes[3]
                                      : kShapes[4];
      label.type = shape.type;
      random_box(shape, &label);
      if (!ProjectBox(&label)) continue;
      const double o = uniform(rng);
      label.occluded = o < 0.5 ? 0 : o < 0.8 ? 1 : o < 0.97 ? 2 : 3;
      label.alpha = Alpha(label);
      label.truncated = Round(label.truncated, 2);
      frame.labels.push_back(label);
    }
    // Detections of the labels.
    for (const Object& label : frame.labels) {
      if (label.type == "DontCare") continue;
      if (uniform(rng) >= options.detection_probability) continue;
      const int copies = uniform(rng) < options.duplicate_probability ? 2 : 1;
      for (int c = 0; c < copies; ++c) {
        Object det = label;
        if (label.type == "Van" && uniform(rng) < 0.3) det.type = "Car";
        if (label.type == "Person_sitting" && uniform(rng) < 0.5) det.type = "Pedestrian";
        const double z = label.box3d.location.z();
        const double noise = options.position_noise * (c + 1);
        det.box3d.location += Eigen::Vector3d((0.05 + noise * z) * normal(rng), 0.05 * normal(rng),
                                              (0.05 + noise * z) * normal(rng));
        det.box3d.h *= 1 + 0.02 * normal(rng);
        det.box3d.w *= 1 + 0.02 * normal(rng);
        det.box3d.l *= 1 + 0.02 * normal(rng);
        det.box3d.rotation_y += 0.05 * normal(rng);
        if (!ProjectBox(&det)) continue;
        det.box.left += normal(rng);
        det.box.right += normal(rng);
        det.box.top += normal(rng);
        det.box.bottom += normal(rng);
        det.alpha = Alpha(det);
        det.truncated = -1;
        det.occluded = -1;
        det.score = Round(std::clamp(U(0.3, 1.0) - 0.25 * c, 0.0, 1.0), options.score_decimals);
        frame.detections.push_back(det);
      }
    }
    // False positives.
    const int n_fp = num_fp(rng);
    for (int k = 0; k < n_fp; ++k) {
      Object det;
      const double r = uniform(rng);
      const Shape& shape = r < 0.6 ? kShapes[0] : r < 0.85 ? kShapes[2] : kShapes[3];
      det.type = shape.type;
      random_box(shape, &det);
      if (!ProjectBox(&det)) continue;
      det.alpha = Alpha(det);
      det.truncated = -1;
      det.occluded = -1;
      det.score = Round(U(0.0, 0.7), options.score_decimals);
      frame.detections.push_back(det);
    }
    // Detection files are not sorted by score.
    std::shuffle(frame.detections.begin(), frame.detections.end(), rng);
  }
  return frames;
}

}  // namespace stereodet
