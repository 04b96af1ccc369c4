// synth_realism: the evidence in docs/synth.md that synthetic frames are realistic enough.
//
//   synth_realism [--frames 200] [--stereo-frames 20] [--seed 1] [--threads 0] [--images DIR]
//                 [--picture-frame 0] [--speed-frames 0] [--speed-rounds 1] [--road-shapes 1]
//                 [--keep-buffers 1]
//
// Generates frames in memory and prints, as Markdown tables:
//  - label statistics (objects per frame, class mix, difficulty mix, occlusion and truncation mix,
//    distance histogram), to set beside KITTI's published ones;
//  - OpenCV StereoBM and StereoSGBM on the stereo frames against the exact ground truth: KITTI's D1
//    (error > 3 px and > 5% of the true disparity) and density, over all pixels with ground truth
//    and over the ground-truth pixels inside the 2D boxes of Car, Pedestrian and Cyclist labels
//    (all, near < 20 m, far >= 20 m): issue 16's targets; BM inside Car boxes by the car's
//    surface, and over the whole image by what the left ray hits (the ground on and beyond the
//    carriageway, labelled objects, background by material) and by depth;
//  - with --speed-frames N, the generation speed: N whole frames (1242 x 375 or the size given,
//    both cameras, disparity, labels, LiDAR; nothing written) on --threads threads, frames/s,
//    and the same frames with straight, flat roads (SceneOptions::road_shapes = false), in
//    --speed-rounds alternating rounds, with the ratio of the two (paired in one process);
//  --road-shapes 0 makes all frames with straight, flat roads; --keep-buffers 0 leaves glibc's
//  allocator at its defaults instead of the stereodet executables' policy (util/malloc_tuning.h),
//  to measure what that policy is worth;
// and, with --images, writes the pictures of docs/synth.md (a sample pair, the ground-truth and
// SGBM disparity, BM's disparity (synth_bm.png), a bird's-eye view of the LiDAR scan with the
// label boxes).
#include <fmt/format.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <map>
#include <mutex>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "stereodet/kitti/object.h"
#include "stereodet/synth/generator.h"
#include "stereodet/util/malloc_tuning.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/strings.h"

namespace stereodet {
namespace {

struct Args {
  int frames = 200;
  int stereo_frames = 20;
  uint64_t seed = 1;
  int threads = 0;
  int picture_frame = 0;  // the frame drawn for the pictures (must be a stereo frame)
  int speed_frames = 0;   // frames timed for the generation speed (0: not measured)
  int speed_rounds = 1;   // alternating rounds of shaped and flat roads
  bool road_shapes = true;
  std::string images;
};

// Ground-truth pixels inside 2D boxes: the classes of issue 16's stereo targets.
const std::array<const char*, 3> kBoxClasses = {"Car", "Pedestrian", "Cyclist"};
constexpr double kNearM = 20.0;  // "near" objects: sqrt(x^2 + z^2) of the label below this
// KITTI-typical settings: 128 disparities cover 3 m at full resolution. BM and SGBM leave the first
// kNumDisparities columns empty, so the breakdowns also count "right of" them.
constexpr int kNumDisparities = 128;

struct StereoScore {
  int64_t gt = 0, estimated = 0, bad = 0;  // GT pixels, of which estimated, of which D1-bad
  int64_t bad2 = 0;                        // of the estimated, error > 2 px (Middlebury's bad-2.0)
};

// Counts one ground-truth pixel (true disparity g > 0) whose estimate is e (<= 0: none).
void Count(StereoScore& s, float e, float g) {
  ++s.gt;
  if (e <= 0.0f) return;
  ++s.estimated;
  const float err = std::abs(e - g);
  if (err > 3.0f && err > 0.05f * g) ++s.bad;
  if (err > 2.0f) ++s.bad2;
}

StereoScore Score(const cv::Mat& estimate, const cv::Mat& gt) {
  StereoScore s;
  for (int v = 0; v < gt.rows; ++v) {
    for (int u = 0; u < gt.cols; ++u) {
      const float g = gt.at<float>(v, u);
      if (g > 0.0f) Count(s, estimate.at<float>(v, u), g);
    }
  }
  return s;
}

// OpenCV's fixed-point disparities (x16) to pixels, invalid (< 0) to 0.
// BM's score over the ground-truth pixels inside the 2D boxes of the frame's labels of `type`
// (a pixel in two boxes counts once), near or far ones (`near` = 1 / 0) or all (`near` = -1).
// With `min_u` > 0 only the columns from min_u on count (BM leaves its first numDisparities columns
// empty).
StereoScore ScoreInBoxes(const cv::Mat& estimate, const cv::Mat& gt,
                         const std::vector<Object>& labels, const std::string& type, int near,
                         int min_u = 0) {
  cv::Mat mask(gt.size(), CV_8U, cv::Scalar(0));
  for (const Object& o : labels) {
    if (o.type != type) continue;
    const bool is_near = std::hypot(o.box3d.location.x(), o.box3d.location.z()) < kNearM;
    if (near >= 0 && is_near != (near == 1)) continue;
    const int u0 = std::max(0, static_cast<int>(std::floor(o.box.left)));
    const int v0 = std::max(0, static_cast<int>(std::floor(o.box.top)));
    const int u1 = std::min(gt.cols - 1, static_cast<int>(std::ceil(o.box.right)));
    const int v1 = std::min(gt.rows - 1, static_cast<int>(std::ceil(o.box.bottom)));
    if (u1 < u0 || v1 < v0) continue;
    mask(cv::Rect(u0, v0, u1 - u0 + 1, v1 - v0 + 1)).setTo(255);
  }
  if (min_u > 0) mask.colRange(0, std::min(min_u, gt.cols)).setTo(0);
  cv::Mat masked_gt(gt.size(), CV_32F, cv::Scalar(0.0f));
  gt.copyTo(masked_gt, mask);
  return Score(estimate, masked_gt);
}

// What the left camera's ray through pixel (u, v) hits at its ground-truth depth (re-traced within
// a window around that depth, so the hit is the pixel's own surface).
SurfaceHit TraceLeftPixel(const SynthFrame& f, int u, int v) {
  const Eigen::Vector3f centre = f.calib.CameraCentreInRect(2).cast<float>();
  const Eigen::Vector3f point =
      f.calib.UnprojectImageToRect({u, v}, f.depth_left.at<float>(v, u), 2).cast<float>();
  return f.scene.Trace(Ray(centre, point - centre), 0.5f, 1.5f);
}

// What the ground-truth pixels inside Car boxes show, for the breakdown of BM's density there.
enum CarSurface {
  kBackground,
  kPaintSide,
  kPaintEnd,
  kPaintTop,
  kGlass,
  kWheel,
  kOtherPart,
  kNumCarSurfaces
};
const std::array<const char*, kNumCarSurfaces> kCarSurfaceNames = {
    "background (not a car)",  "paint, sides", "paint, front and rear",
    "paint, bonnet/roof/boot", "glass",        "wheels",
    "other car parts"};

// The surface of each ground-truth pixel inside a Car box: the left camera's ray re-traced
// through the pixel (depth buffer), its primitive's material and face.
std::array<StereoScore, kNumCarSurfaces> ScoreCarSurfaces(const cv::Mat& estimate,
                                                          const SynthFrame& f, int min_u) {
  std::array<StereoScore, kNumCarSurfaces> out{};
  cv::Mat mask(f.disparity.size(), CV_8U, cv::Scalar(0));
  for (const Object& o : f.labels) {
    if (o.type != "Car") continue;
    const int u0 = std::max(0, static_cast<int>(std::floor(o.box.left)));
    const int v0 = std::max(0, static_cast<int>(std::floor(o.box.top)));
    const int u1 = std::min(mask.cols - 1, static_cast<int>(std::ceil(o.box.right)));
    const int v1 = std::min(mask.rows - 1, static_cast<int>(std::ceil(o.box.bottom)));
    if (u1 < u0 || v1 < v0) continue;
    mask(cv::Rect(u0, v0, u1 - u0 + 1, v1 - v0 + 1)).setTo(255);
  }
  if (min_u > 0) mask.colRange(0, std::min(min_u, mask.cols)).setTo(0);
  for (int v = 0; v < mask.rows; ++v) {
    for (int u = 0; u < mask.cols; ++u) {
      const float g = f.disparity.at<float>(v, u);
      if (mask.at<uchar>(v, u) == 0 || g <= 0.0f) continue;
      const int id = f.object_id.at<int>(v, u);
      int surface = kBackground;
      if (id >= 0 && f.scene.objects[id].type == "Car") {
        const SurfaceHit hit = TraceLeftPixel(f, u, v);
        surface = kOtherPart;
        if (hit.kind == SurfaceHit::Kind::kPrimitive) {
          const Primitive& p = f.scene.primitives[hit.primitive];
          const Pattern pattern = f.scene.materials[hit.material].pattern;
          const Eigen::Vector3f n = p.world_from_local.transpose() * hit.normal;
          int axis = 0;
          n.cwiseAbs().maxCoeff(&axis);
          if (pattern == Pattern::kCarPaint) {
            surface = axis == 1 ? kPaintTop : axis == 0 ? kPaintEnd : kPaintSide;
          } else if (pattern == Pattern::kGlass) {
            surface = kGlass;
          } else if (pattern == Pattern::kWheel) {
            surface = kWheel;
          }
        }
      }
      Count(out[surface], estimate.at<float>(v, u), g);
    }
  }
  return out;
}

void Add(StereoScore& total, const StereoScore& s) {
  total.gt += s.gt, total.estimated += s.estimated, total.bad += s.bad, total.bad2 += s.bad2;
}

// What every ground-truth pixel of the image shows, for the breakdown of BM's whole-image density:
// the ground (on the carriageway or beyond it) or a primitive's material pattern, labelled objects
// apart; and the depth bin of the pixel.
enum ImageSurface {
  kRoadGround,
  kOffroadGround,
  kLabelledObject,
  kFacadeWall,  // facade, brick
  kPavingSurface,
  kVegetation,  // foliage, grass
  kFenceSurface,
  kOtherBackground,
  kNumImageSurfaces
};
const std::array<const char*, kNumImageSurfaces> kImageSurfaceNames = {
    "ground, carriageway", "ground, beyond it", "labelled objects", "facades and brick",
    "paving (sidewalks)",  "vegetation",        "fences",           "other background"};
constexpr std::array<double, 5> kDepthBinsM = {10.0, 20.0, 40.0, 80.0, 1e9};
constexpr std::array<const char*, 5> kDepthBinNames = {"0-10", "10-20", "20-40", "40-80", "80+"};

struct ImageSurfaceScores {
  // [surface][depth bin]; [0] all columns, [1] right of BM's empty first kNumDisparities.
  std::array<std::array<std::array<StereoScore, kDepthBinsM.size()>, kNumImageSurfaces>, 2> s{};
};

ImageSurfaceScores ScoreImageSurfaces(const cv::Mat& estimate, const SynthFrame& f) {
  ImageSurfaceScores out;
  for (int v = 0; v < f.disparity.rows; ++v) {
    for (int u = 0; u < f.disparity.cols; ++u) {
      const float g = f.disparity.at<float>(v, u);
      if (g <= 0.0f) continue;
      const float depth = f.depth_left.at<float>(v, u);
      const SurfaceHit hit = TraceLeftPixel(f, u, v);
      int surface = kOtherBackground;
      if (hit.kind == SurfaceHit::Kind::kGround) {
        surface = hit.material == f.scene.road_material ? kRoadGround : kOffroadGround;
      } else if (hit.kind == SurfaceHit::Kind::kPrimitive) {
        const Pattern pattern = f.scene.materials[hit.material].pattern;
        if (f.object_id.at<int>(v, u) >= 0) {
          surface = kLabelledObject;
        } else if (pattern == Pattern::kFacade || pattern == Pattern::kBrick) {
          surface = kFacadeWall;
        } else if (pattern == Pattern::kPaving) {
          surface = kPavingSurface;
        } else if (pattern == Pattern::kFoliage || pattern == Pattern::kGrass) {
          surface = kVegetation;
        } else if (pattern == Pattern::kFence) {
          surface = kFenceSurface;
        }
      }
      int bin = 0;
      while (depth >= kDepthBinsM[bin]) ++bin;
      for (int k = 0; k < (u >= kNumDisparities ? 2 : 1); ++k) {
        Count(out.s[k][surface][bin], estimate.at<float>(v, u), g);
      }
    }
  }
  return out;
}

cv::Mat ToPixels(const cv::Mat& fixed) {
  cv::Mat d;
  fixed.convertTo(d, CV_32F, 1.0 / 16.0);
  cv::threshold(d, d, 0.0, 0.0, cv::THRESH_TOZERO);
  return d;
}

cv::Mat ColourDisparity(const cv::Mat& d, double max_d) {
  cv::Mat d8;
  d.convertTo(d8, CV_8U, 255.0 / max_d);
  cv::Mat colour;
  cv::applyColorMap(d8, colour, cv::COLORMAP_TURBO);
  colour.setTo(cv::Scalar(0, 0, 0), d <= 0.0f);
  return colour;
}

void WriteSmallPng(const std::string& path, const cv::Mat& image) {
  cv::imwrite(path, image, {cv::IMWRITE_PNG_COMPRESSION, 9});
  std::printf("wrote %s\n", path.c_str());
}

// Bird's-eye view: velo x forward (up in the picture), y left; 0.16 m a pixel, 80 m ahead, 40 m
// either side. Points coloured by height, label boxes in green (DontCare not drawn).
cv::Mat BirdsEye(const SynthFrame& f) {
  constexpr double kRes = 0.16, kAhead = 80.0, kSide = 40.0;
  const int rows = static_cast<int>(kAhead / kRes), cols = static_cast<int>(2 * kSide / kRes);
  cv::Mat bev(rows, cols, CV_8UC3, cv::Scalar(20, 20, 20));
  const auto to_px = [&](double x, double y) {
    return cv::Point(static_cast<int>((kSide - y) / kRes), static_cast<int>((kAhead - x) / kRes));
  };
  for (const VeloPoint& p : f.scan) {
    const cv::Point q = to_px(p.x, p.y);
    if (q.x < 0 || q.y < 0 || q.x >= cols || q.y >= rows) continue;
    const double h = std::clamp((p.z + 1.8) / 4.0, 0.0, 1.0);
    bev.at<cv::Vec3b>(q) =
        cv::Vec3b(static_cast<uchar>(255 * (1 - h)), static_cast<uchar>(120 + 135 * h),
                  static_cast<uchar>(255 * h));
  }
  const Eigen::Affine3d velo_from_rect = f.calib.VeloFromRect();
  for (const Object& o : f.labels) {
    if (o.IsDontCare()) continue;
    const auto corners = BevCorners(o.box3d);
    std::vector<cv::Point> poly;
    for (const BevPoint& c : corners) {
      const Eigen::Vector3d v =
          velo_from_rect * Eigen::Vector3d(c.x(), o.box3d.location.y(), c.y());
      poly.push_back(to_px(v.x(), v.y()));
    }
    cv::polylines(bev, poly, true,
                  o.type == "Car" ? cv::Scalar(80, 255, 80) : cv::Scalar(80, 200, 255), 1,
                  cv::LINE_AA);
  }
  // The camera's field of view.
  const double half_fov = std::atan2(f.calib.PrincipalPointPx().x(), f.calib.FocalPx());
  for (double s : {-1.0, 1.0}) {
    cv::line(bev, to_px(0, 0), to_px(kAhead, -s * kAhead * std::tan(half_fov)),
             cv::Scalar(90, 90, 90), 1);
  }
  return bev;
}

int Run(const Args& args) {
  SynthOptions options;
  options.scene.road_shapes = args.road_shapes;
  std::mutex mutex;
  std::vector<std::vector<Object>> labels(args.frames);
  StereoScore bm_total, sgbm_total;
  // BM inside the boxes of kBoxClasses: [class][all, near, far].
  std::array<std::array<StereoScore, 4>, kBoxClasses.size()> bm_boxes{};
  std::array<std::array<StereoScore, kNumCarSurfaces>, 2> bm_car_surfaces{};
  ImageSurfaceScores bm_image_surfaces;
  ParallelFor(
      static_cast<size_t>(args.frames),
      [&](size_t i) {
        SynthOptions o = options;
        const bool stereo = static_cast<int>(i) < args.stereo_frames;
        o.lidar = static_cast<int>(i) == args.picture_frame;
        const SynthFrame f = GenerateFrame(o, args.seed, static_cast<int>(i));
        labels[i] = f.labels;
        if (!stereo) return;
        cv::Mat left, right;
        cv::cvtColor(f.image_left, left, cv::COLOR_BGR2GRAY);
        cv::cvtColor(f.image_right, right, cv::COLOR_BGR2GRAY);
        cv::Ptr<cv::StereoBM> bm =
            cv::StereoBM::create(kNumDisparities, 11);  // the stereo module's default block
        bm->setPreFilterCap(31);
        bm->setTextureThreshold(10);
        bm->setUniquenessRatio(15);
        bm->setSpeckleWindowSize(100);
        bm->setSpeckleRange(32);
        const int block = 5;
        cv::Ptr<cv::StereoSGBM> sgbm =
            cv::StereoSGBM::create(0, kNumDisparities, block, 8 * block * block, 32 * block * block,
                                   1, 63, 10, 100, 32, cv::StereoSGBM::MODE_SGBM);
        cv::Mat bm_fixed, sgbm_fixed;
        bm->compute(left, right, bm_fixed);
        sgbm->compute(left, right, sgbm_fixed);
        const cv::Mat bm_d = ToPixels(bm_fixed), sgbm_d = ToPixels(sgbm_fixed);
        const StereoScore b = Score(bm_d, f.disparity), s = Score(sgbm_d, f.disparity);
        std::array<std::array<StereoScore, 4>, kBoxClasses.size()> boxes;
        for (size_t c = 0; c < kBoxClasses.size(); ++c) {
          for (int k = 0; k < 3; ++k) {
            const int near = k == 0 ? -1 : (k == 1 ? 1 : 0);
            boxes[c][k] = ScoreInBoxes(bm_d, f.disparity, f.labels, kBoxClasses[c], near);
          }
          boxes[c][3] =
              ScoreInBoxes(bm_d, f.disparity, f.labels, kBoxClasses[c], -1, kNumDisparities);
        }
        const auto surfaces = ScoreCarSurfaces(bm_d, f, 0);
        const auto surfaces_right = ScoreCarSurfaces(bm_d, f, kNumDisparities);
        const ImageSurfaceScores image_surfaces = ScoreImageSurfaces(bm_d, f);
        std::lock_guard<std::mutex> lock(mutex);
        for (int k = 0; k < 2; ++k) {
          for (int m = 0; m < kNumImageSurfaces; ++m) {
            for (size_t b = 0; b < kDepthBinsM.size(); ++b) {
              Add(bm_image_surfaces.s[k][m][b], image_surfaces.s[k][m][b]);
            }
          }
        }
        for (int k = 0; k < kNumCarSurfaces; ++k) {
          Add(bm_car_surfaces[0][k], surfaces[k]);
          Add(bm_car_surfaces[1][k], surfaces_right[k]);
        }
        Add(bm_total, b);
        Add(sgbm_total, s);
        for (size_t c = 0; c < kBoxClasses.size(); ++c) {
          for (int k = 0; k < 4; ++k) Add(bm_boxes[c][k], boxes[c][k]);
        }
        if (static_cast<int>(i) == args.picture_frame && !args.images.empty()) {
          cv::Mat pair, half_l, half_r;
          cv::resize(f.image_left, half_l, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
          cv::resize(f.image_right, half_r, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
          cv::vconcat(half_l, half_r, pair);
          WriteSmallPng(args.images + "/synth_pair.png", pair);
          cv::Mat disp, half_gt, half_sgbm;
          cv::resize(ColourDisparity(f.disparity, 96), half_gt, cv::Size(), 0.5, 0.5,
                     cv::INTER_NEAREST);
          cv::resize(ColourDisparity(sgbm_d, 96), half_sgbm, cv::Size(), 0.5, 0.5,
                     cv::INTER_NEAREST);
          cv::vconcat(half_gt, half_sgbm, disp);
          WriteSmallPng(args.images + "/synth_disparity.png", disp);
          cv::Mat half_bm;
          cv::resize(ColourDisparity(bm_d, 96), half_bm, cv::Size(), 0.5, 0.5, cv::INTER_NEAREST);
          WriteSmallPng(args.images + "/synth_bm.png", half_bm);
          WriteSmallPng(args.images + "/synth_bev.png", BirdsEye(f));
          // Full-resolution crop for a look at texture detail.
          WriteSmallPng(args.images + "/synth_crop.png",
                        f.image_left(cv::Rect(420, 140, 400, 150)));
          // The largest car, left image above BM's disparity (black: none).
          cv::Rect car;
          for (const Object& o : f.labels) {
            if (o.type != "Car") continue;
            const cv::Rect r(
                cv::Point(static_cast<int>(o.box.left), static_cast<int>(o.box.top)),
                cv::Point(static_cast<int>(o.box.right), static_cast<int>(o.box.bottom)));
            if (r.area() > car.area()) car = r;
          }
          if (car.area() > 0) {
            cv::Mat stack;
            cv::vconcat(f.image_left(car), ColourDisparity(bm_d, 96)(car), stack);
            WriteSmallPng(args.images + "/synth_car.png", stack);
          }
        }
      },
      args.threads);

  // Label statistics.
  const std::vector<std::string> classes = {
      "Car", "Van", "Truck", "Pedestrian", "Person_sitting", "Cyclist", "Tram", "Misc"};
  std::map<std::string, int64_t> count;
  std::map<std::string, std::array<int64_t, 4>> difficulty;
  std::array<int64_t, 4> occlusion{};
  std::array<int64_t, 4> truncation{};  // 0, (0, 0.15], (0.15, 0.5], > 0.5
  std::vector<int64_t> distance(9, 0);  // 10 m bins, the last open-ended
  int64_t labelled = 0, dont_care = 0;
  for (const auto& frame : labels) {
    for (const Object& o : frame) {
      if (o.IsDontCare()) {
        ++dont_care;
        continue;
      }
      ++labelled;
      ++count[o.type];
      const auto easiest = EasiestDifficulty(o);
      ++difficulty[o.type][easiest ? static_cast<int>(*easiest) : 3];
      ++occlusion[std::clamp(o.occluded, 0, 3)];
      ++truncation[o.truncated <= 0.0 ? 0 : o.truncated <= 0.15 ? 1 : o.truncated <= 0.5 ? 2 : 3];
      const double d = std::hypot(o.box3d.location.x(), o.box3d.location.z());
      ++distance[std::min<int>(8, static_cast<int>(d / 10.0))];
    }
  }
  const double n = args.frames;
  std::printf("\n## Labels (%d frames, seed %llu)\n\n", args.frames,
              static_cast<unsigned long long>(args.seed));
  std::printf("objects per frame: %.2f labelled + %.2f DontCare\n\n", labelled / n, dont_care / n);
  std::printf(
      "| class | count | share | easy | moderate only | hard only | none "
      "|\n|---|---:|---:|---:|---:|---:|---:|\n");
  for (const std::string& c : classes) {
    const auto& d = difficulty[c];
    std::printf("| %s | %lld | %.1f%% | %lld | %lld | %lld | %lld |\n", c.c_str(),
                static_cast<long long>(count[c]), 100.0 * count[c] / std::max<int64_t>(1, labelled),
                static_cast<long long>(d[0]), static_cast<long long>(d[1]),
                static_cast<long long>(d[2]), static_cast<long long>(d[3]));
  }
  std::printf("\nocclusion 0/1/2/3: %.1f%% / %.1f%% / %.1f%% / %.1f%%\n",
              100.0 * occlusion[0] / labelled, 100.0 * occlusion[1] / labelled,
              100.0 * occlusion[2] / labelled, 100.0 * occlusion[3] / labelled);
  std::printf("truncation 0 / <=0.15 / <=0.5 / >0.5: %.1f%% / %.1f%% / %.1f%% / %.1f%%\n",
              100.0 * truncation[0] / labelled, 100.0 * truncation[1] / labelled,
              100.0 * truncation[2] / labelled, 100.0 * truncation[3] / labelled);
  std::printf("\n| distance (m) |");
  for (int b = 0; b < 9; ++b) std::printf(b < 8 ? " %d-%d |" : " %d+ |", 10 * b, 10 * b + 10);
  std::printf("\n|---|");
  for (int b = 0; b < 9; ++b) std::printf("---:|");
  std::printf("\n| share |");
  for (int b = 0; b < 9; ++b) std::printf(" %.1f%% |", 100.0 * distance[b] / labelled);
  std::printf("\n");

  // Per-class statistics of issue 16: count per frame, occlusion and truncation mixes, distance
  // and 2D box height histograms, the 3D height's mean and spread.
  {
    const std::array<double, 7> height_edges = {0, 25, 40, 60, 100, 150, 1e9};  // pixels
    std::printf("\n### Per class (%d frames)\n\n", args.frames);
    std::printf(
        "| class | per frame | occluded 0 / 1 / 2 / 3 | truncated 0 / <=0.15 / <=0.5 / >0.5 | "
        "3D height mean (sd), m |\n|---|---:|---|---|---:|\n");
    std::map<std::string, std::vector<int64_t>> distance_by_class, height_by_class;
    for (const char* name : {"Car", "Pedestrian", "Cyclist"}) {
      const std::string c = name;
      std::array<int64_t, 4> occ{}, trunc{};
      std::vector<int64_t> dist(9, 0), box_h(6, 0);
      double sum = 0.0, sum2 = 0.0;
      int64_t total = 0;
      for (const auto& frame : labels) {
        for (const Object& o : frame) {
          if (o.type != c) continue;
          ++total;
          ++occ[std::clamp(o.occluded, 0, 3)];
          ++trunc[o.truncated <= 0.0 ? 0 : o.truncated <= 0.15 ? 1 : o.truncated <= 0.5 ? 2 : 3];
          const double d = std::hypot(o.box3d.location.x(), o.box3d.location.z());
          ++dist[std::min<int>(8, static_cast<int>(d / 10.0))];
          const double hp = o.box.bottom - o.box.top;
          for (int b = 0; b < 6; ++b) {
            if (hp < height_edges[b + 1]) {
              ++box_h[b];
              break;
            }
          }
          sum += o.box3d.h;
          sum2 += o.box3d.h * o.box3d.h;
        }
      }
      const double t = std::max<int64_t>(1, total);
      const double mean = sum / t, sd = std::sqrt(std::max(0.0, sum2 / t - mean * mean));
      std::printf(
          "| %s | %.2f | %.0f / %.0f / %.0f / %.0f %% | %.0f / %.0f / %.0f / %.0f %% | %.2f (%.2f) "
          "|\n",
          c.c_str(), total / n, 100 * occ[0] / t, 100 * occ[1] / t, 100 * occ[2] / t,
          100 * occ[3] / t, 100 * trunc[0] / t, 100 * trunc[1] / t, 100 * trunc[2] / t,
          100 * trunc[3] / t, mean, sd);
      distance_by_class[c] = dist;
      height_by_class[c] = box_h;
      for (int64_t& x : distance_by_class[c]) x = static_cast<int64_t>(std::lround(1000 * x / t));
      for (int64_t& x : height_by_class[c]) x = static_cast<int64_t>(std::lround(1000 * x / t));
    }
    std::printf("\n| distance (m), share per class |");
    for (int b = 0; b < 9; ++b) std::printf(b < 8 ? " %d-%d |" : " %d+ |", 10 * b, 10 * b + 10);
    std::printf("\n|---|");
    for (int b = 0; b < 9; ++b) std::printf("---:|");
    std::printf("\n");
    for (const auto& [c, d] : distance_by_class) {
      std::printf("| %s |", c.c_str());
      for (int64_t x : d) std::printf(" %.1f%% |", x / 10.0);
      std::printf("\n");
    }
    std::printf(
        "\n| 2D box height (px), share per class | < 25 | 25-40 | 40-60 | 60-100 | 100-150 | "
        ">= 150 |\n|---|---:|---:|---:|---:|---:|---:|\n");
    for (const auto& [c, h] : height_by_class) {
      std::printf("| %s |", c.c_str());
      for (int64_t x : h) std::printf(" %.1f%% |", x / 10.0);
      std::printf("\n");
    }
  }

  if (args.stereo_frames > 0) {
    std::printf("\n## Stereo (%d frames, 1242x375, exact ground truth, non-occluded pixels)\n\n",
                args.stereo_frames);
    std::printf(
        "| method | D1 of estimated pixels | bad-2.0 of estimated pixels | density | D1-all "
        "(missing = wrong) |\n|---|---:|---:|---:|---:|\n");
    for (const auto& [name, s] :
         {std::pair<const char*, StereoScore>{"StereoBM (11x11)", bm_total},
          std::pair<const char*, StereoScore>{"StereoSGBM (5x5)", sgbm_total}}) {
      std::printf("| %s | %.1f%% | %.1f%% | %.1f%% | %.1f%% |\n", name,
                  100.0 * s.bad / std::max<int64_t>(1, s.estimated),
                  100.0 * s.bad2 / std::max<int64_t>(1, s.estimated),
                  100.0 * s.estimated / std::max<int64_t>(1, s.gt),
                  100.0 * (s.bad + s.gt - s.estimated) / std::max<int64_t>(1, s.gt));
    }
    std::printf(
        "\nStereoBM inside the 2D boxes (ground-truth pixels in the boxes; near: < %.0f m):\n\n"
        "| class | density | D1 of estimated | density near | D1 near | density far | D1 far | "
        "GT pixels | share in BM's empty first 128 columns | density right of them "
        "|\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        kNearM);
    for (size_t c = 0; c < kBoxClasses.size(); ++c) {
      std::printf("| %s |", kBoxClasses[c]);
      for (int k = 0; k < 3; ++k) {
        const StereoScore& s = bm_boxes[c][k];
        std::printf(" %.1f%% | %.1f%% |", 100.0 * s.estimated / std::max<int64_t>(1, s.gt),
                    100.0 * s.bad / std::max<int64_t>(1, s.estimated));
      }
      const StereoScore& right = bm_boxes[c][3];
      std::printf(" %lld | %.1f%% | %.1f%% |\n", static_cast<long long>(bm_boxes[c][0].gt),
                  100.0 - 100.0 * right.gt / std::max<int64_t>(1, bm_boxes[c][0].gt),
                  100.0 * right.estimated / std::max<int64_t>(1, right.gt));
    }
    int64_t car_gt = 0;
    for (const StereoScore& s : bm_car_surfaces[0]) car_gt += s.gt;
    std::printf(
        "\nStereoBM inside Car boxes by surface (the left ray re-traced through each pixel):\n\n"
        "| surface | share of the GT pixels | density | D1 of estimated | density right of "
        "column 128 |\n|---|---:|---:|---:|---:|\n");
    for (int k = 0; k < kNumCarSurfaces; ++k) {
      const StereoScore& s = bm_car_surfaces[0][k];
      const StereoScore& r = bm_car_surfaces[1][k];
      std::printf("| %s | %.1f%% | %.1f%% | %.1f%% | %.1f%% |\n", kCarSurfaceNames[k],
                  100.0 * s.gt / std::max<int64_t>(1, car_gt),
                  100.0 * s.estimated / std::max<int64_t>(1, s.gt),
                  100.0 * s.bad / std::max<int64_t>(1, s.estimated),
                  100.0 * r.estimated / std::max<int64_t>(1, r.gt));
    }
    int64_t image_gt = 0;
    for (const auto& bins : bm_image_surfaces.s[0]) {
      for (const StereoScore& s : bins) image_gt += s.gt;
    }
    std::printf(
        "\nStereoBM over the whole image by surface and depth (the left ray re-traced through "
        "each ground-truth pixel; share of all GT pixels, density; density right of column "
        "128):\n\n| surface | share | density | D1 | right of 128 |");
    for (size_t b = 0; b < kDepthBinsM.size(); ++b) {
      std::printf(" %s m: share, density |", kDepthBinNames[b]);
    }
    std::printf("\n|---|---:|---:|---:|---:|");
    for (size_t b = 0; b < kDepthBinsM.size(); ++b) std::printf("---:|");
    std::printf("\n");
    for (int m = 0; m < kNumImageSurfaces; ++m) {
      StereoScore all, right;
      for (size_t b = 0; b < kDepthBinsM.size(); ++b) {
        Add(all, bm_image_surfaces.s[0][m][b]);
        Add(right, bm_image_surfaces.s[1][m][b]);
      }
      std::printf("| %s | %.1f%% | %.1f%% | %.1f%% | %.1f%% |", kImageSurfaceNames[m],
                  100.0 * all.gt / std::max<int64_t>(1, image_gt),
                  100.0 * all.estimated / std::max<int64_t>(1, all.gt),
                  100.0 * all.bad / std::max<int64_t>(1, all.estimated),
                  100.0 * right.estimated / std::max<int64_t>(1, right.gt));
      for (size_t b = 0; b < kDepthBinsM.size(); ++b) {
        const StereoScore& s = bm_image_surfaces.s[0][m][b];
        std::printf(" %.1f%%, %.1f%% |", 100.0 * s.gt / std::max<int64_t>(1, image_gt),
                    100.0 * s.estimated / std::max<int64_t>(1, s.gt));
      }
      std::printf("\n");
    }
  }

  if (args.speed_frames > 0) {
    const auto timed = [&](bool road_shapes) {
      SynthOptions o = options;
      o.lidar = true;
      o.scene.road_shapes = road_shapes;
      const auto start = std::chrono::steady_clock::now();
      const std::clock_t cpu_start = std::clock();
      std::vector<size_t> points(args.speed_frames);
      ParallelFor(
          static_cast<size_t>(args.speed_frames),
          [&](size_t i) {
            // Frames after the statistics' ones: the timing does not reuse any cache of theirs.
            points[i] = GenerateFrame(o, args.seed, args.frames + static_cast<int>(i)).scan.size();
          },
          args.threads);
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      // CPU time of the process: on a shared machine it is steadier than the wall clock.
      const double cpu_per_frame =
          static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC / args.speed_frames;
      std::printf(
          "\n## Generation speed\n\n%d frames at %dx%d with LiDAR on %s threads (%s roads): %.2f "
          "s, %.2f frames/s; %.3f CPU s a frame\n",
          args.speed_frames, o.width, o.height,
          args.threads > 0 ? std::to_string(args.threads).c_str() : "all",
          road_shapes ? "shaped" : "straight, flat", seconds, args.speed_frames / seconds,
          cpu_per_frame);
      return cpu_per_frame;
    };
    for (int round = 0; round < args.speed_rounds; ++round) {
      const double shaped = timed(args.road_shapes);
      if (!args.road_shapes) continue;
      const double flat = timed(false);
      std::printf("\nround %d: CPU time a frame, shaped / straight-flat: %.3f\n", round,
                  shaped / flat);
    }
  }
  return 0;
}

}  // namespace
}  // namespace stereodet

int main(int argc, char** argv) {
  stereodet::Args args;
  bool keep_buffers = true;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    const auto number = stereodet::ParseInt(value);
    if (key == "--images") {
      args.images = value;
    } else if (number && key == "--frames") {
      args.frames = static_cast<int>(*number);
    } else if (number && key == "--stereo-frames") {
      args.stereo_frames = static_cast<int>(*number);
    } else if (number && key == "--seed") {
      args.seed = static_cast<uint64_t>(*number);
    } else if (number && key == "--picture-frame") {
      args.picture_frame = static_cast<int>(*number);
    } else if (number && key == "--speed-frames") {
      args.speed_frames = static_cast<int>(*number);
    } else if (number && key == "--speed-rounds") {
      args.speed_rounds = static_cast<int>(*number);
    } else if (number && key == "--road-shapes") {
      args.road_shapes = *number != 0;
    } else if (number && key == "--threads") {
      args.threads = static_cast<int>(*number);
    } else if (number && key == "--keep-buffers") {
      keep_buffers = *number != 0;
    } else {
      std::fprintf(
          stderr,
          "usage: synth_realism [--frames N] [--stereo-frames K] [--seed S] [--threads T]\n"
          "                     [--images DIR] [--picture-frame I] [--speed-frames N]\n"
          "                     [--speed-rounds R] [--road-shapes 0|1] [--keep-buffers 0|1]\n");
      return 2;
    }
  }
  // As the stereodet executables do (RunCli), so that the speed is the one `stereodet synth` has.
  if (keep_buffers) stereodet::KeepLargeBuffersInHeap();
  std::printf("allocator: %s\n",
              keep_buffers ? "large buffers kept in the heap (as stereodet)" : "glibc defaults");
  return stereodet::Run(args);
}
