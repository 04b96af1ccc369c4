#include "stereodet/synth/generator.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/kitti/plane_io.h"
#include "stereodet/synth/random.h"
#include "stereodet/synth/road.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/output_folder.h"
#include "stereodet/util/parallel.h"

namespace stereodet {

namespace {

// Independent random streams of a frame.
enum Stream : uint64_t {
  kSceneStream = 1,
  kNoiseStream = 2,
  kLidarStream = 3,
  kGainStream = 4,
  kSplitStream = 5
};

// The version of the scene and rendering model, recorded in synth_settings.txt: a folder written
// by another version is refused rather than mixed. 1: the first street model; 2: issue 16's
// textures (asphalt, paving, kerbs, facades, fences), car details, sun glints, per-frame white
// balance and sensor noise; 3: issue 16's curved car hulls (saloon, hatchback, estate) and the
// street mirrored in paint and glass; 4: issue 16's dusty paint, lamps, plates and glass with
// the interior's headrests, the roadside clutter (synth/clutter.h), people with limbs and
// garments, the road shapes (bends, crests and sags, crossfall, the car's pitch and roll, side
// streets; synth/road.h), and planes/ holding the least-squares plane of the true ground where the
// stereo ground fit samples it; 5: the vehicle ahead in the ego lane keeps its rear at least 6 m
// ahead of the camera (version 4 placed its centre there, so a truck could reach the camera); 6:
// paving stones in a random bond with sand-filled joints (a regular grid of dark joints failed
// block matching on most sidewalks).
constexpr int kSettingsVersion = 6;

// The settings (`key=value` tokens) in which two settings lines differ, as "key: a (folder), b
// (this run)", for the refusal message.
std::string SettingsDifference(const std::string& existing, const std::string& wanted) {
  const auto tokens = [](const std::string& line) {
    std::map<std::string, std::string> out;
    std::istringstream in(line);
    std::string token;
    while (in >> token) {
      const size_t eq = token.find('=');
      out[token.substr(0, eq)] = eq == std::string::npos ? "" : token.substr(eq + 1);
    }
    return out;
  };
  const auto a = tokens(existing), b = tokens(wanted);
  std::string diff;
  for (const auto& [key, value] : b) {
    const auto it = a.find(key);
    const std::string old = it == a.end() ? "(none)" : it->second;
    if (old != value)
      diff += fmt::format("{}{}: {} in the folder, {} in this run", diff.empty() ? "" : "; ", key,
                          old, value);
  }
  for (const auto& [key, value] : a) {
    if (!b.count(key))
      diff += fmt::format("{}{}: {} in the folder, (none) in this run", diff.empty() ? "" : "; ",
                          key, value);
  }
  return diff;
}

void WritePng(const std::filesystem::path& path, const cv::Mat& image, int compression) {
  std::filesystem::create_directories(path.parent_path());
  AtomicPath out(path);
  // Huffman-only deflate: sensor noise defeats LZ77 matching anyway, so this is both faster
  // (~28 vs ~32 ms for a 1242x375 colour image at level 1) and smaller (~610 vs ~730 KB) than the
  // default strategy. zlib's output is a pure function of the input and settings: deterministic.
  const std::vector<int> params = {cv::IMWRITE_PNG_COMPRESSION, compression,
                                   cv::IMWRITE_PNG_STRATEGY, cv::IMWRITE_PNG_STRATEGY_HUFFMAN_ONLY};
  STEREODET_CHECK_IO(cv::imwrite(out.temp_path().string(), image, params))
      << "cannot write " << path;
  out.Commit();
}

}  // namespace

void SynthOptions::Check() const {
  STEREODET_CHECK(width >= 8 && height >= 8 && width <= 8192 && height <= 8192)
      << "image size must be within 8..8192, got " << width << "x" << height;
  STEREODET_CHECK(camera_gain_jitter >= 0.0 && camera_gain_jitter < 0.5)
      << "camera_gain_jitter must be in [0, 0.5), got " << camera_gain_jitter;
  scene.Check();
  render.Check();
  lidar_options.Check();
  labels.Check();
  disparity.Check();
}

std::string SynthOptions::Fingerprint() const {
  std::ostringstream s;
  s.precision(17);
  s << "version=" << kSettingsVersion << " size=" << width << "x" << height << " lidar=" << lidar
    << " gain_jitter=" << camera_gain_jitter << " density=" << scene.object_density
    << " streets=" << scene.city_weight << "," << scene.residential_weight << ","
    << scene.road_weight << " along=" << scene.min_along_m << "," << scene.max_along_m
    << " camera_height=" << scene.camera_height_m << "," << scene.camera_height_jitter_m
    << " road_yaw_sd=" << scene.road_yaw_sd_deg << " road_shapes=" << scene.road_shapes
    << " bends=" << scene.bend_fraction << "," << scene.min_bend_radius_m << ","
    << scene.max_bend_radius_m << " vertical=" << scene.vertical_curve_fraction << ","
    << scene.max_grade_change << "," << scene.min_vertical_radius_m << ","
    << scene.max_vertical_radius_m << " crown=" << scene.crown_fraction << ","
    << scene.max_crossfall << " pitch_roll_sd=" << scene.pitch_sd_deg << "," << scene.roll_sd_deg
    << " side_streets=" << scene.side_street_fraction << " shadows=" << render.shadows
    << " blur=" << render.optics_blur_sigma_px << " vignetting=" << render.vignetting
    << " noise=" << render.noise_sigma << " azimuth_step=" << lidar_options.azimuth_step_deg
    << " range=" << lidar_options.min_range_m << "," << lidar_options.max_range_m
    << " range_noise=" << lidar_options.range_noise_m << " dropout=" << lidar_options.dropout
    << " labels=" << labels.min_visible_pixels << "," << labels.min_height_px << ","
    << labels.max_depth_m << "," << labels.visible_fraction_occluded_0 << ","
    << labels.visible_fraction_occluded_1 << "," << labels.visible_fraction_occluded_2;
  return s.str();
}

SynthFrame GenerateFrame(const SynthOptions& options, uint64_t seed, int index, StageTimes* times) {
  options.Check();
  StageTimes local_times;
  StageTimes& t = times != nullptr ? *times : local_times;
  const uint64_t frame = static_cast<uint64_t>(index);
  SynthFrame out;
  out.calib = SynthCalibration(options.width, options.height);
  {
    ScopedStage stage(t, "scene");
    out.scene = SampleScene(options.scene, HashOf({seed, frame, kSceneStream}));
  }
  Rng gains(HashOf({seed, frame, kGainStream}));
  const uint64_t noise_seed = HashOf({seed, frame, kNoiseStream});
  RenderRequest left;
  left.camera = 2;
  left.width = options.width;
  left.height = options.height;
  left.gain = static_cast<float>(1.0 + gains.Normal(0.0, options.camera_gain_jitter));
  left.noise_seed = noise_seed;
  left.object_ids = true;
  left.points = true;
  RenderRequest right = left;
  right.camera = 3;
  right.gain = static_cast<float>(1.0 + gains.Normal(0.0, options.camera_gain_jitter));
  right.object_ids = false;
  right.points = false;
  CameraRender left_render, right_render;
  {
    ScopedStage stage(t, "render left");
    left_render = RenderCamera(out.scene, out.calib, left, options.render);
  }
  {
    ScopedStage stage(t, "render right");
    right_render = RenderCamera(out.scene, out.calib, right, options.render);
  }
  {
    ScopedStage stage(t, "disparity");
    out.disparity = GroundTruthDisparity(out.calib, left_render, right_render, options.disparity);
  }
  {
    ScopedStage stage(t, "labels");
    out.labels = MakeLabels(out.scene, out.calib, left_render.object_id, options.labels).labels;
  }
  if (options.lidar) {
    ScopedStage stage(t, "lidar");
    out.scan = SimulateLidar(out.scene, out.calib, options.lidar_options,
                             HashOf({seed, frame, kLidarStream}));
  }
  out.image_left = left_render.image;
  out.image_right = right_render.image;
  out.depth_left = left_render.depth;
  out.object_id = left_render.object_id;
  // The least-squares plane of the true ground where the stereo ground fit looks (on a flat
  // ground its plane, -y + ground_y_m = 0).
  out.ground_plane = TrueGroundPlane(out.scene, out.calib, options.width, options.height);
  return out;
}

void DatasetOptions::Check() const {
  STEREODET_CHECK(!out.empty()) << "the output folder must be given";
  STEREODET_CHECK(frames >= 0 && frames <= 1000000)
      << "frames must be in 0..1000000, got " << frames;
  STEREODET_CHECK(val_fraction >= 0.0 && val_fraction <= 1.0)
      << "val_fraction must be in [0, 1], got " << val_fraction;
  STEREODET_CHECK(threads >= 0) << "threads must be >= 0 (0 = all cores), got " << threads;
  STEREODET_CHECK(png_compression >= 0 && png_compression <= 9)
      << "png_compression must be in 0..9, got " << png_compression;
  shard.Check();
  synth.Check();
}

std::vector<int> ValFrames(int frames, double val_fraction, uint64_t seed) {
  std::vector<std::pair<uint64_t, int>> keyed;
  for (int i = 0; i < frames; ++i)
    keyed.push_back({HashOf({seed, static_cast<uint64_t>(i), kSplitStream}), i});
  std::sort(keyed.begin(), keyed.end());
  const int n_val = static_cast<int>(std::lround(frames * val_fraction));
  std::vector<int> val;
  for (int i = 0; i < n_val; ++i) val.push_back(keyed[i].second);
  std::sort(val.begin(), val.end());
  return val;
}

DatasetSummaryLine GenerateDataset(const DatasetOptions& options) {
  options.Check();
  Timer timer;
  // synth writes frames and split files: only into a folder it made (its synth_settings.txt),
  // never over a KITTI download, a model or someone's files.
  CheckOutputFolderOwner(options.out, "synth", {kMakerSynth});
  // Refuse to resume into a data set made with another seed or other settings. The settings file
  // is written before any folder inside, so a shard starting beside this one finds either an
  // empty folder or a marked one.
  const std::string settings =
      fmt::format("seed={} {}\n", options.seed, options.synth.Fingerprint());
  const std::filesystem::path settings_path = options.out / "synth_settings.txt";
  if (std::filesystem::exists(settings_path)) {
    const std::string existing = ReadFile(settings_path);
    STEREODET_CHECK(existing == settings)
        << "the data set in " << options.out << " was made with other settings ("
        << SettingsDifference(existing, settings) << "):\n  " << existing << "this run has:\n  "
        << settings << "use another --out folder, or the same settings";
  } else {
    WriteFileAtomically(settings_path, settings);
  }
  std::filesystem::create_directories(options.out / "training");
  RemoveStaleTemporaries(options.out);
  const KittiDataset dataset(options.out, "training");
  StageTimes times;
  std::atomic<int> generated{0}, skipped{0};
  std::atomic<int64_t> objects{0};
  const size_t first = options.shard.Begin(static_cast<size_t>(options.frames));
  const size_t last = options.shard.End(static_cast<size_t>(options.frames));
  ProgressReporter progress("synth", static_cast<int64_t>(last - first), options.progress);
  ParallelFor(
      last - first,
      [&](size_t i) {
        const int index = static_cast<int>(first + i);
        const FramePaths paths = dataset.Paths(FrameId(index));
        const bool complete =
            std::filesystem::exists(paths.image_left) &&
            std::filesystem::exists(paths.image_right) && std::filesystem::exists(paths.label) &&
            std::filesystem::exists(paths.calib) && std::filesystem::exists(paths.velodyne) &&
            std::filesystem::exists(paths.disparity) && std::filesystem::exists(paths.planes);
        if (complete) {
          ++skipped;
          progress.Add(1);
          return;
        }
        const SynthFrame frame = GenerateFrame(options.synth, options.seed, index, &times);
        {
          ScopedStage stage(times, "write");
          WritePng(paths.image_left, frame.image_left, options.png_compression);
          WritePng(paths.image_right, frame.image_right, options.png_compression);
          WritePng(paths.disparity, EncodeKittiDisparity(frame.disparity), options.png_compression);
          std::filesystem::create_directories(paths.calib.parent_path());
          WriteCalibration(paths.calib, frame.calib);
          std::filesystem::create_directories(paths.velodyne.parent_path());
          WriteVelodyne(paths.velodyne, frame.scan);
          std::filesystem::create_directories(paths.planes.parent_path());
          WriteGroundPlane(paths.planes, frame.ground_plane);
          // The label file last: its presence marks a frame most readers consider complete.
          std::filesystem::create_directories(paths.label.parent_path());
          WriteObjects(paths.label, frame.labels);
        }
        objects += static_cast<int64_t>(frame.labels.size());
        ++generated;
        progress.Add(1);
      },
      options.threads);
  progress.Finish();

  const std::vector<int> val = ValFrames(options.frames, options.val_fraction, options.seed);
  std::vector<std::string> val_ids, train_ids, all_ids;
  size_t next_val = 0;
  for (int i = 0; i < options.frames; ++i) {
    all_ids.push_back(FrameId(i));
    if (next_val < val.size() && val[next_val] == i) {
      val_ids.push_back(FrameId(i));
      ++next_val;
    } else {
      train_ids.push_back(FrameId(i));
    }
  }
  std::filesystem::create_directories(options.out / "ImageSets");
  WriteSplit(options.out / "ImageSets" / "train.txt", train_ids);
  WriteSplit(options.out / "ImageSets" / "val.txt", val_ids);
  WriteSplit(options.out / "ImageSets" / "trainval.txt", all_ids);

  DatasetSummaryLine summary;
  summary.generated = generated;
  summary.skipped = skipped;
  summary.train = static_cast<int>(train_ids.size());
  summary.val = static_cast<int>(val_ids.size());
  summary.objects = objects;
  summary.seconds = timer.ElapsedSeconds();
  summary.stage_times = times.Format();
  return summary;
}

}  // namespace stereodet
