#include "stereodet/realtime/frame_source.h"

#include <fmt/format.h>
#include <glob.h>

#include <algorithm>
#include <cmath>
#include <opencv2/videoio.hpp>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/models/det3d/det3d_boxes.h"
#include "stereodet/models/detect_shard.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/util/check.h"
#include "stereodet/util/timer.h"

namespace stereodet {

namespace fs = std::filesystem;

namespace {

constexpr double kKittiFps = 10.0;  // KITTI's cameras and LiDAR run at 10 Hz

// A calibration fits an image when its principal point lies inside it: KITTI's calib files hold
// no image size, and a calibration of another camera (or another resolution) puts it elsewhere.
void CheckCalibrationFits(const Calibration& calib, const cv::Size& size,
                          const std::string& calib_source, const std::string& image_source) {
  const Eigen::Vector2d c = calib.PrincipalPointPx();
  STEREODET_CHECK_IO(c.x() > 0 && c.y() > 0 && c.x() < size.width && c.y() < size.height)
      << "the calibration " << calib_source << " does not fit the images of " << image_source
      << ": its principal point (" << c.x() << ", " << c.y() << ") px is outside their "
      << size.width << "x" << size.height << " px (a calibration of another camera or resolution?)";
}

// Fills `out` with what went wrong when `read` throws: the frame is reported, the stream goes on.
template <typename Read>
void ReadOrNote(SourceFrame& out, Read read) {
  const Timer timer;
  try {
    read();
  } catch (const std::exception& e) {
    out.error = UserMessage(e);
  }
  out.read_s = timer.ElapsedSeconds();
}

// --- KITTI split -------------------------------------------------------------------------------

class KittiSource : public FrameSource {
 public:
  explicit KittiSource(const FrameSourceOptions& options)
      : options_(options), dataset_(options.data_root, options.subset) {
    ids_ = DetectFrameList(dataset_, options.split, options.max_frames);
  }

  std::optional<SourceFrame> Next() override {
    if (next_ >= ids_.size()) return std::nullopt;
    SourceFrame out;
    out.index = static_cast<int64_t>(next_);
    const std::string& id = ids_[next_++];
    out.frame.id = id;
    out.frame.timestamp_s = out.index / fps();
    ReadOrNote(out, [&] {
      const FramePaths paths = dataset_.Paths(id);
      const DetectorNeeds& needs = options_.needs;
      if (needs.left_image || needs.right_image) {
        out.frame.left = ReadColourImage(paths.image_left);
      } else {
        const auto [width, height] = PngImageSize(paths.image_left);
        out.frame.image_size = cv::Size(width, height);
      }
      if (needs.right_image) {
        out.frame.right = ReadColourImage(paths.image_right);
        CheckStereoPairSize(out.frame.left, out.frame.right, paths.image_left, paths.image_right);
      }
      if (needs.calibration) out.frame.calib = ReadCalibration(paths.calib);
      if (needs.points) out.frame.points = ReadVelodyne(paths.velodyne);
    });
    return out;
  }
  double fps() const override { return options_.fps > 0 ? options_.fps : kKittiFps; }
  int64_t size() const override { return static_cast<int64_t>(ids_.size()); }
  std::string Describe() const override {
    return fmt::format("KITTI {}, split {} ({} frames)", options_.data_root.string(),
                       options_.split, ids_.size());
  }

 private:
  FrameSourceOptions options_;
  KittiDataset dataset_;
  std::vector<std::string> ids_;
  size_t next_ = 0;
};

// --- image sequences ---------------------------------------------------------------------------

class SequenceSource : public FrameSource {
 public:
  explicit SequenceSource(const FrameSourceOptions& options) : options_(options) {
    left_ = SequenceFiles(options.left);
    if (options.needs.right_image) right_ = SequenceFiles(options.right);
    if (options.max_frames > 0 && static_cast<int>(left_.size()) > options.max_frames) {
      left_.resize(options.max_frames);
    }
    if (!options.calib.empty()) {
      calib_ = ReadCalibration(options.calib);
      const cv::Mat first = ReadColourImage(left_.front());
      CheckCalibrationFits(*calib_, first.size(), options.calib.string(), options.left);
    }
  }

  std::optional<SourceFrame> Next() override {
    if (next_ >= left_.size()) return std::nullopt;
    SourceFrame out;
    out.index = static_cast<int64_t>(next_);
    const fs::path& left = left_[next_++];
    out.frame.id = left.stem().string();
    out.frame.timestamp_s = out.index / fps();
    ReadOrNote(out, [&] {
      out.frame.left = ReadColourImage(left);
      if (options_.needs.right_image) {
        STEREODET_CHECK_IO(static_cast<size_t>(out.index) < right_.size())
            << "no right image for " << left.string() << ": the right sequence " << options_.right
            << " has " << right_.size() << " files, the left one more";
        out.frame.right = ReadColourImage(right_[out.index]);
        CheckStereoPairSize(out.frame.left, out.frame.right, left, right_[out.index]);
      }
      if (calib_) out.frame.calib = *calib_;
    });
    return out;
  }
  double fps() const override { return options_.fps > 0 ? options_.fps : kKittiFps; }
  int64_t size() const override { return static_cast<int64_t>(left_.size()); }
  std::string Describe() const override {
    return fmt::format("image sequence {} ({} frames){}", options_.left, left_.size(),
                       options_.needs.right_image ? " with " + options_.right : std::string());
  }

 private:
  FrameSourceOptions options_;
  std::vector<fs::path> left_, right_;
  std::optional<Calibration> calib_;
  size_t next_ = 0;
};

// --- videos and cameras (OpenCV VideoCapture) --------------------------------------------------

class VideoSource : public FrameSource {
 public:
  explicit VideoSource(const FrameSourceOptions& options) : options_(options) {
    if (options.camera >= 0) {
      name_ = fmt::format("camera {}", options.camera);
      Open(left_, cv::VideoCapture(options.camera), name_);
    } else if (!options.video.empty()) {
      name_ = options.video.string();
      Open(left_, cv::VideoCapture(options.video.string()), name_);
    } else {
      name_ = options.left_video.string() + " + " + options.right_video.string();
      Open(left_, cv::VideoCapture(options.left_video.string()), options.left_video.string());
      Open(right_, cv::VideoCapture(options.right_video.string()), options.right_video.string());
    }
    if (!options.calib.empty()) calib_ = ReadCalibration(options.calib);
    // The first frame now: the calibration is checked against it before anything runs.
    first_ = Read();
    STEREODET_CHECK_IO(first_.has_value() && first_->error.empty())
        << "cannot read the first frame of " << name_
        << (first_ && !first_->error.empty() ? ": " + first_->error : std::string());
    if (calib_) {
      CheckCalibrationFits(*calib_, first_->frame.left.size(), options.calib.string(), name_);
    }
  }

  std::optional<SourceFrame> Next() override {
    if (first_) {
      std::optional<SourceFrame> out = std::move(first_);
      first_.reset();
      return out;
    }
    if (ended_ || (options_.max_frames > 0 && next_ >= options_.max_frames)) return std::nullopt;
    return Read();
  }
  double fps() const override {
    if (options_.fps > 0) return options_.fps;
    const double reported = left_.get(cv::CAP_PROP_FPS);
    return std::isfinite(reported) && reported > 0 ? reported : 30.0;
  }
  int64_t size() const override {
    if (options_.camera >= 0) return -1;
    const double n = left_.get(cv::CAP_PROP_FRAME_COUNT);
    int64_t frames = n > 0 ? static_cast<int64_t>(n) : -1;
    if (frames > 0 && options_.max_frames > 0)
      frames = std::min<int64_t>(frames, options_.max_frames);
    return frames;
  }
  std::string Describe() const override {
    const int64_t n = size();
    return fmt::format("{} {}{}", options_.camera >= 0 ? "camera" : "video", name_,
                       n > 0 ? fmt::format(" ({} frames at {:.3g} fps)", n, fps()) : "");
  }

 private:
  static void Open(cv::VideoCapture& to, cv::VideoCapture from, const std::string& name) {
    STEREODET_CHECK_IO(from.isOpened())
        << "cannot open " << name << " (OpenCV's VideoCapture: a missing file, or a format its "
        << "backends cannot decode)";
    to = std::move(from);
  }

  // The next frame of the file(s), or nullopt at the end (a record of an early end first).
  std::optional<SourceFrame> Read() {
    SourceFrame out;
    out.index = next_;
    out.frame.id = fmt::format("{:06d}", next_);
    const Timer timer;
    cv::Mat left, right;
    if (!left_.read(left) || left.empty()) {
      ended_ = true;
      return std::nullopt;
    }
    out.frame.timestamp_s =
        options_.camera >= 0 ? next_ / fps() : left_.get(cv::CAP_PROP_POS_MSEC) / 1000.0;
    if (right_.isOpened()) {
      if (!right_.read(right) || right.empty()) {
        // A source that ends early: the frame says so, and it is the last.
        ended_ = true;
        out.error = fmt::format("{} ended after {} frames; {} has more",
                                options_.right_video.string(), next_, options_.left_video.string());
        out.read_s = timer.ElapsedSeconds();
        ++next_;
        return out;
      }
      out.frame.left = left;
      out.frame.right = right;
      if (left.size() != right.size()) {
        try {
          CheckStereoPairSize(left, right, options_.left_video, options_.right_video);
        } catch (const std::exception& e) {
          out.error = UserMessage(e);
        }
      }
    } else {
      // Side by side: the left camera's image in the left half.
      if (left.cols % 2 != 0) {
        out.error =
            fmt::format("a side-by-side frame must have an even width, got {} px", left.cols);
      } else {
        const int half = left.cols / 2;
        out.frame.left = left(cv::Rect(0, 0, half, left.rows)).clone();
        out.frame.right = left(cv::Rect(half, 0, half, left.rows)).clone();
      }
    }
    if (calib_) out.frame.calib = *calib_;
    out.read_s = timer.ElapsedSeconds();
    ++next_;
    return out;
  }

  FrameSourceOptions options_;
  std::string name_;
  cv::VideoCapture left_, right_;
  std::optional<Calibration> calib_;
  std::optional<SourceFrame> first_;
  int64_t next_ = 0;
  bool ended_ = false;
};

// Every frame of another source, read before the first is given.
class PreloadedSource : public FrameSource {
 public:
  explicit PreloadedSource(std::unique_ptr<FrameSource> inner)
      : fps_(inner->fps()), description_(inner->Describe() + ", preloaded") {
    while (std::optional<SourceFrame> frame = inner->Next()) {
      frame->read_s = 0.0;  // nothing is read while the stream runs
      frames_.push_back(std::move(*frame));
    }
  }
  std::optional<SourceFrame> Next() override {
    if (next_ >= frames_.size()) return std::nullopt;
    return std::move(frames_[next_++]);
  }
  double fps() const override { return fps_; }
  int64_t size() const override { return static_cast<int64_t>(frames_.size()); }
  std::string Describe() const override { return description_; }

 private:
  double fps_;
  std::string description_;
  std::vector<SourceFrame> frames_;
  size_t next_ = 0;
};

}  // namespace

void FrameSourceOptions::Check() const {
  const int sources = !data_root.empty() + !left.empty() + !video.empty() +
                      (!left_video.empty() || !right_video.empty()) + (camera >= 0);
  STEREODET_CHECK(sources == 1)
      << (sources == 0 ? "no source: give --data (a KITTI layout), --left/--right (image "
                         "sequences), --video, --left-video/--right-video or --camera"
                       : "give one source, not several (--data, --left, --video, --left-video, "
                         "--camera)");
  STEREODET_CHECK(left_video.empty() == right_video.empty())
      << "--left-video and --right-video go together";
  STEREODET_CHECK(right.empty() || !left.empty()) << "--right needs --left";
  STEREODET_CHECK(std::isfinite(fps) && fps >= 0) << "fps must be >= 0, got " << fps;
  STEREODET_CHECK(max_frames >= 0) << "max_frames must be >= 0, got " << max_frames;
  const bool kitti = !data_root.empty();
  STEREODET_CHECK(kitti || !needs.points)
      << "this model reads LiDAR scans, which only a KITTI source (--data) has";
  STEREODET_CHECK(kitti || !needs.calibration || !calib.empty())
      << "this model needs the stereo calibration: give --calib FILE (a KITTI calib file)";
  STEREODET_CHECK(left.empty() || !needs.right_image || !right.empty())
      << "this model matches stereo: give --right too";
  STEREODET_CHECK(!preload || camera < 0) << "--preload needs a finite source, not a camera";
}

std::unique_ptr<FrameSource> OpenFrameSource(const FrameSourceOptions& options) {
  options.Check();
  std::unique_ptr<FrameSource> source;
  if (!options.data_root.empty()) {
    source = std::make_unique<KittiSource>(options);
  } else if (!options.left.empty()) {
    source = std::make_unique<SequenceSource>(options);
  } else {
    source = std::make_unique<VideoSource>(options);
  }
  if (options.preload) source = std::make_unique<PreloadedSource>(std::move(source));
  return source;
}

std::vector<fs::path> SequenceFiles(const std::string& folder_or_glob) {
  std::vector<fs::path> files;
  std::error_code ec;
  if (fs::is_directory(folder_or_glob, ec)) {
    for (const fs::directory_entry& entry : fs::directory_iterator(folder_or_glob)) {
      std::string ext = entry.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
      if (entry.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg")) {
        files.push_back(entry.path());
      }
    }
  } else {
    glob_t matches{};
    if (glob(folder_or_glob.c_str(), 0, nullptr, &matches) == 0) {
      for (size_t i = 0; i < matches.gl_pathc; ++i) files.emplace_back(matches.gl_pathv[i]);
    }
    globfree(&matches);
  }
  STEREODET_CHECK_IO(!files.empty())
      << "no image files in " << folder_or_glob
      << " (a folder of .png/.jpg files or a glob such as 'cam/left_*.png')";
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace stereodet
