#include "stereodet/models/detector.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "stereodet/kitti/score_calibration.h"
#include "stereodet/models/det3d/det3d_boxes.h"
#include "stereodet/models/device.h"
#include "stereodet/models/model_json.h"
#include "stereodet/models/network_output.h"
#include "stereodet/models/rpn/rpn_data.h"
#include "stereodet/models/ssd/input_encoding.h"
#include "stereodet/models/ssd/ssd_data.h"
#include "stereodet/models/ssd/ssd_detect.h"
#include "stereodet/models/ssd/ssd_model.h"
#include "stereodet/stereo/degradation.h"
#include "stereodet/stereo/disparity.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/stereo/reprojection.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/timer.h"

namespace stereodet {
namespace fs = std::filesystem;

void DetectorOptions::Check() const {
  STEREODET_CHECK(ParseComputeDevice(device).has_value())
      << "unknown device '" << device << "' (expected cpu or cuda)";
  STEREODET_CHECK(threads >= 0) << "threads must be >= 0, got " << threads;
  STEREODET_CHECK(blur_sigma_px >= 0.0 && std::isfinite(blur_sigma_px))
      << "blur sigma must be >= 0, got " << blur_sigma_px;
  if (stereo) stereo->Check();
  ssd.Check();
  rpn.Check();
  det3d.Check();
  det3d_points.Check();
}

std::string ModelFamily(const fs::path& model_dir) {
  const fs::path path = model_dir / kModelConfigFile;
  const std::string text = ReadFile(path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(path.string(), 0, "", std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) throw ParseError(path.string(), 0, "", "not a JSON object");
  if (!j.contains("architecture")) return "ssd";  // the first models did not record it
  if (!j["architecture"].is_string()) {
    throw ParseError(path.string(), 0, "architecture", "not a string");
  }
  const std::string family = j["architecture"].get<std::string>();
  if (family != "ssd" && family != "rpn" && family != "det3d") {
    throw ParseError(path.string(), 0, "architecture",
                     "'" + family + "' is no detector family (ssd, rpn or det3d)");
  }
  return family;
}

struct Detector::Impl {
  fs::path model_dir;
  std::string family, input;
  std::string weights_fnv1a64;
  std::vector<std::string> classes;
  DetectorNeeds needs;
  DetectorOptions options;
  std::optional<ScoreCalibration> calibration;  // DetectorOptions::calibration's, once read

  virtual ~Impl() = default;
  virtual std::optional<StereoOptions> Stereo() const = 0;
  virtual std::unique_ptr<PreparedBatch> Prepare(const std::vector<StereoFrame>& frames) const = 0;
  virtual void Run(PreparedBatch& batch) = 0;

  // "frame 000123: models/ssd-rgbh (ssd rgbh-learned) needs the right image; the frame has none".
  void Require(bool present, const StereoFrame& frame, const char* what) const {
    STEREODET_CHECK(present) << "frame " << (frame.id.empty() ? "(no id)" : frame.id) << ": "
                             << model_dir.string() << " (" << family << " " << input << ") needs "
                             << what << "; the frame has none";
  }
  void CheckFrame(const StereoFrame& frame) const {
    // What the pair would give, given: heights (RGB-H from a `stereo` folder) stand for the pair
    // and its calibration; a stereo 3D model's points for the pair (it still needs the image's
    // size and the calibration).
    const bool points_for_pair = family == "det3d" && !needs.points && frame.points.has_value();
    const bool pair = frame.height_code.empty() && !points_for_pair;
    if (needs.left_image && !points_for_pair) Require(!frame.left.empty(), frame, "the left image");
    if (needs.right_image && pair) Require(!frame.right.empty(), frame, "the right image");
    if (needs.calibration && (pair || points_for_pair)) {
      Require(frame.calib.has_value(), frame, "a calibration");
    }
    if (needs.points) Require(frame.points.has_value(), frame, "the LiDAR points");
    for (const cv::Mat* image : {&frame.left, &frame.right}) {
      STEREODET_CHECK(image->empty() || image->type() == CV_8UC3)
          << "frame " << frame.id << ": images must be 8-bit BGR (CV_8UC3)";
    }
  }
  // Prepares every frame in parallel (options.threads), `prepare(i, result)` filling frame i.
  template <typename Batch, typename Fn>
  std::unique_ptr<Batch> PrepareEach(const std::vector<StereoFrame>& frames, Fn prepare) const {
    for (const StereoFrame& frame : frames) CheckFrame(frame);
    auto batch = std::make_unique<Batch>();
    batch->owner = this;
    batch->results.resize(frames.size());
    batch->Resize(frames.size());
    ParallelFor(
        frames.size(),
        [&](size_t i) {
          batch->results[i].id = frames[i].id;
          prepare(i, *batch);
        },
        options.threads);
    return batch;
  }
};

namespace {

// The stereo geometry of a frame (its calibration: CheckFrame made sure it has one).
StereoGeometry GeometryOf(const StereoFrame& frame) {
  return StereoGeometry::FromCalibration(*frame.calib);
}

void CheckPair(const StereoFrame& frame, const DisparityOptions& disparity) {
  const fs::path left(frame.id.empty() ? "left image" : frame.id + " (left image)");
  const fs::path right(frame.id.empty() ? "right image" : frame.id + " (right image)");
  CheckStereoPairSize(frame.left, frame.right, left, right);
  CheckImageFitsMatcher(disparity, frame.left.size(), left);
}

// --- the image families (ssd, rpn) --------------------------------------------------------------

// Their prepared batch: the network inputs and each frame's image size.
struct ImageBatch : Detector::PreparedBatch {
  std::vector<PlanarImage> inputs;
  std::vector<cv::Size> sizes;
  void Resize(size_t n) {
    inputs.resize(n);
    sizes.resize(n);
  }
};

// A 2D network's boxes (in input_width x input_height px) as KITTI objects in each frame's image
// px; the batch's network time `network_s` is shared out over its frames.
void DecodeImageBatch(ImageBatch& batch, const std::vector<std::vector<ScoredBox>>& boxes,
                      const std::vector<std::string>& classes, int input_width, int input_height,
                      double network_s) {
  const double network_s_per_frame = network_s / std::max<size_t>(1, batch.inputs.size());
  for (size_t i = 0; i < batch.inputs.size(); ++i) {
    const Timer timer;
    const cv::Size size = batch.sizes[i];
    const double sx = static_cast<double>(size.width) / input_width;
    const double sy = static_cast<double>(size.height) / input_height;
    batch.results[i].objects =
        ToKittiDetections(boxes[i], classes, sx, sy, size.width, size.height);
    batch.results[i].times.network_s = network_s_per_frame;
    batch.results[i].times.decode_s = timer.ElapsedSeconds();
  }
}

// --- ssd ---------------------------------------------------------------------------------------

struct SsdImpl : Detector::Impl {
  SsdModel model;
  bool height = false;
  StereoOptions stereo;  // with the blur of the network's image

  explicit SsdImpl(SsdModel m) : model(std::move(m)) {}

  std::optional<StereoOptions> Stereo() const override {
    if (!height) return std::nullopt;
    return stereo;
  }

  std::unique_ptr<Detector::PreparedBatch> Prepare(
      const std::vector<StereoFrame>& frames) const override {
    const SsdConfig& config = model.config();
    return PrepareEach<ImageBatch>(frames, [&](size_t i, ImageBatch& batch) {
      const StereoFrame& frame = frames[i];
      DetectStageTimes& times = batch.results[i].times;
      batch.sizes[i] = frame.left.size();
      cv::Mat network_image = frame.left, height_code;
      Timer timer;
      if (height && !frame.height_code.empty()) {
        // Heights given (a `stereo` folder's, at the match size): as matching would give them.
        const cv::Size match = stereo.disparity.MatchSize(frame.left.size());
        STEREODET_CHECK_IO(frame.height_code.size() == match &&
                           frame.height_code.type() == CV_16UC1)
            << "frame " << frame.id << ": the heights given are " << frame.height_code.cols << "x"
            << frame.height_code.rows << " px at the match scale, " << match.width << "x"
            << match.height << " (16-bit) for a left image of " << frame.left.cols << "x"
            << frame.left.rows;
        height_code = frame.height_code;
        if (options.blur_sigma_px > 0.0) {
          timer.Restart();
          network_image = GaussianBlurImage(frame.left, options.blur_sigma_px);
          times.encode_s += timer.ElapsedSeconds();
        }
      } else if (height) {
        CheckPair(frame, stereo.disparity);
        StereoEncoder encoder(stereo);  // one per frame: not thread-safe, cheap to make
        StereoOutputs outputs;
        outputs.rgbh = false;
        outputs.full_resolution = false;  // match-scale codes go to the network directly
        const StereoEncoding encoding =
            encoder.Encode(frame.left, frame.right, GeometryOf(frame), outputs);
        network_image = encoding.network_image;  // blurred when asked; stereo saw it sharp
        height_code = encoding.height_code;
        times.stereo_s += timer.ElapsedSeconds();
      } else if (options.blur_sigma_px > 0.0) {
        network_image = GaussianBlurImage(frame.left, options.blur_sigma_px);
        times.encode_s += timer.ElapsedSeconds();
      }
      timer.Restart();
      batch.inputs[i] = PrepareNetworkInput(network_image, height_code, config);
      times.encode_s += timer.ElapsedSeconds();
    });
  }

  void Run(Detector::PreparedBatch& prepared) override {
    ImageBatch& batch = static_cast<ImageBatch&>(prepared);
    const SsdConfig& config = model.config();
    const Timer timer;
    const std::vector<std::vector<ScoredBox>> boxes = model.Detect(batch.inputs, options.ssd);
    DecodeImageBatch(batch, boxes, config.classes, config.InputWidth(), config.InputHeight(),
                     timer.ElapsedSeconds());
  }
};

// --- rpn ---------------------------------------------------------------------------------------

struct RpnImpl : Detector::Impl {
  RpnModel model;
  bool geometry = false;
  StereoOptions stereo;  // the model's, with the blur of the network's image

  explicit RpnImpl(RpnModel m) : model(std::move(m)) {}

  std::optional<StereoOptions> Stereo() const override {
    if (!geometry) return std::nullopt;
    return stereo;
  }

  std::unique_ptr<Detector::PreparedBatch> Prepare(
      const std::vector<StereoFrame>& frames) const override {
    const RpnConfig& config = model.config();
    return PrepareEach<ImageBatch>(frames, [&](size_t i, ImageBatch& batch) {
      const StereoFrame& frame = frames[i];
      DetectStageTimes& times = batch.results[i].times;
      Timer timer;
      if (geometry) {
        CheckPair(frame, stereo.disparity);
        StereoEncoder encoder(stereo);  // one per frame: not thread-safe, cheap to make
        StereoOutputs outputs;
        outputs.rgbh = false;
        outputs.depth = true;
        const StereoEncoding encoding =
            encoder.Encode(frame.left, frame.right, GeometryOf(frame), outputs);
        times.stereo_s += timer.ElapsedSeconds();  // blurs the network's image only
        timer.Restart();
        batch.sizes[i] = encoding.network_image.size();
        batch.inputs[i] = PrepareRpnInput(encoding.network_image, encoding.depth_code,
                                          encoding.height_code, config, stereo.depth);
        times.encode_s += timer.ElapsedSeconds();
        return;
      }
      batch.sizes[i] = frame.left.size();
      cv::Mat image = frame.left;
      if (options.blur_sigma_px > 0.0) image = GaussianBlurImage(image, options.blur_sigma_px);
      batch.inputs[i] = PrepareRpnInput(image, {}, {}, config);
      times.encode_s += timer.ElapsedSeconds();
    });
  }

  void Run(Detector::PreparedBatch& prepared) override {
    ImageBatch& batch = static_cast<ImageBatch&>(prepared);
    const RpnConfig& config = model.config();
    const Timer timer;
    const std::vector<std::vector<ScoredBox>> boxes = model.Detect(batch.inputs, options.rpn);
    DecodeImageBatch(batch, boxes, config.classes, config.input_width, config.input_height,
                     timer.ElapsedSeconds());
  }
};

// --- det3d -------------------------------------------------------------------------------------

struct Det3dBatch : Detector::PreparedBatch {
  std::vector<Det3dFrame> frames;
  std::vector<Det3dSample> samples;
  void Resize(size_t n) {
    frames.resize(n);
    samples.resize(n);
  }
};

struct Det3dImpl : Detector::Impl {
  Det3dModel model;
  StereoOptions stereo;  // a stereo model's point cloud, when the frame brings none

  explicit Det3dImpl(Det3dModel m) : model(std::move(m)) {}

  std::optional<StereoOptions> Stereo() const override {
    if (model.config().input != PointSource::kStereo) return std::nullopt;
    return stereo;
  }

  std::unique_ptr<Detector::PreparedBatch> Prepare(
      const std::vector<StereoFrame>& frames) const override {
    const Det3dConfig& config = model.config();
    return PrepareEach<Det3dBatch>(frames, [&](size_t i, Det3dBatch& batch) {
      const StereoFrame& frame = frames[i];
      DetectStageTimes& times = batch.results[i].times;
      const cv::Size size = frame.left.empty() ? frame.image_size : frame.left.size();
      STEREODET_CHECK(size.width > 0 && size.height > 0)
          << "frame " << frame.id << ": " << model_dir.string()
          << " (det3d) needs the left image or its size (StereoFrame::image_size)";
      Timer timer;
      std::vector<VeloPoint> computed;
      if (!frame.points) {
        // Only a stereo model gets here (a LiDAR one needs the points: CheckFrame).
        Require(!frame.left.empty() && !frame.right.empty(), frame,
                "its stereo points or the stereo pair");
        CheckPair(frame, stereo.disparity);
        StereoEncoder encoder(stereo);
        computed = encoder
                       .Encode(frame.left, frame.right, GeometryOf(frame),
                               {.rgbh = false, .depth = false, .points = true})
                       .points;
        times.stereo_s += timer.ElapsedSeconds();
        timer.Restart();
      }
      Det3dFrame& f = batch.frames[i];
      f.id = frame.id;
      f.calib = *frame.calib;
      f.image_width = size.width;
      f.image_height = size.height;
      f.points = FilterDet3dPoints(frame.points ? *frame.points : computed, f.calib, size.width,
                                   size.height, config.input, config.grid, options.det3d_points);
      batch.samples[i] = MakeDet3dSample(f, config, model.anchors(), false);
      times.encode_s += timer.ElapsedSeconds();
    });
  }

  void Run(Detector::PreparedBatch& prepared) override {
    Det3dBatch& batch = static_cast<Det3dBatch&>(prepared);
    const Det3dConfig& config = model.config();
    Timer timer;
    const std::vector<std::vector<ScoredLidarBox>> boxes =
        model.Detect(batch.samples, options.det3d);
    const double network_s = timer.ElapsedSeconds() / std::max<size_t>(1, batch.samples.size());
    for (size_t i = 0; i < batch.samples.size(); ++i) {
      timer.Restart();
      const Det3dFrame& f = batch.frames[i];
      std::vector<Object>& objects = batch.results[i].objects;
      for (const ScoredLidarBox& b : boxes[i]) {
        std::optional<Object> o =
            ToKitti3DDetection(b, config.classes, f.calib, f.image_width, f.image_height);
        if (o) objects.push_back(*o);
      }
      batch.results[i].times.network_s = network_s;
      batch.results[i].times.decode_s = timer.ElapsedSeconds();
    }
  }
};

}  // namespace

Detector::Detector(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Detector::~Detector() = default;
Detector::Detector(Detector&&) noexcept = default;
Detector& Detector::operator=(Detector&&) noexcept = default;

Detector Detector::Open(const fs::path& model_dir, const DetectorOptions& options) {
  options.Check();
  const std::string family = ModelFamily(model_dir);
  const ComputeDevice device = ResolveComputeDevice(options.device);
  SetTorchThreads(options.threads);
  std::unique_ptr<Impl> impl;
  if (family == "ssd") {
    auto ssd = std::make_unique<SsdImpl>(SsdModel::Load(model_dir, device));
    const SsdConfig& config = ssd->model.config();
    ssd->input = InputEncodingName(config.encoding);
    ssd->classes = config.classes;
    ssd->height = UsesHeight(config.encoding);
    ssd->stereo = options.stereo.value_or(ssd->model.stereo());
    ssd->stereo.blur.sigma_px = options.blur_sigma_px;
    ssd->stereo.blur.mode = BlurMode::kNetworkImage;
    ssd->needs = {.left_image = true, .right_image = ssd->height, .calibration = ssd->height};
    impl = std::move(ssd);
  } else if (family == "rpn") {
    auto rpn = std::make_unique<RpnImpl>(RpnModel::Load(model_dir, device));
    const RpnConfig& config = rpn->model.config();
    rpn->input = RpnInputName(config.input);
    rpn->classes = config.classes;
    rpn->geometry = config.input == RpnInput::kRgbd;
    rpn->stereo = rpn->model.stereo();
    rpn->stereo.blur.sigma_px = options.blur_sigma_px;
    rpn->stereo.blur.mode = BlurMode::kNetworkImage;
    rpn->needs = {.left_image = true, .right_image = rpn->geometry, .calibration = rpn->geometry};
    impl = std::move(rpn);
  } else {
    auto det3d = std::make_unique<Det3dImpl>(Det3dModel::Load(model_dir, device));
    const Det3dConfig& config = det3d->model.config();
    det3d->input = PointSourceName(config.input);
    det3d->classes = config.classes;
    det3d->stereo = options.stereo.value_or(StereoOptions());
    // A stereo model reads the pair, unless the frame carries its points (CheckFrame).
    const bool stereo = config.input == PointSource::kStereo;
    det3d->needs = {
        .left_image = stereo, .right_image = stereo, .calibration = true, .points = !stereo};
    impl = std::move(det3d);
  }
  impl->model_dir = model_dir;
  impl->family = family;
  impl->options = options;
  if (!options.calibration.empty()) impl->calibration = ReadScoreCalibration(options.calibration);
  const fs::path config = model_dir / kModelConfigFile;
  impl->weights_fnv1a64 = ReadWeightsRecord(ReadFile(config), config.string()).fnv1a64;
  if (impl->weights_fnv1a64.empty()) {
    impl->weights_fnv1a64 = HashHex(Fnv1a64(ReadFile(model_dir / kModelWeightsFile)));
  }
  return Detector(std::move(impl));
}

const fs::path& Detector::model_dir() const { return impl_->model_dir; }
const std::string& Detector::family() const { return impl_->family; }
const std::string& Detector::input() const { return impl_->input; }
const std::vector<std::string>& Detector::classes() const { return impl_->classes; }
const DetectorNeeds& Detector::needs() const { return impl_->needs; }
const DetectorOptions& Detector::options() const { return impl_->options; }
std::optional<StereoOptions> Detector::stereo() const { return impl_->Stereo(); }
const std::string& Detector::weights_fnv1a64() const { return impl_->weights_fnv1a64; }

std::unique_ptr<Detector::PreparedBatch> Detector::Prepare(
    const std::vector<StereoFrame>& frames) const {
  return impl_->Prepare(frames);
}

std::vector<DetectResult> Detector::Run(std::unique_ptr<PreparedBatch> batch) {
  STEREODET_CHECK(batch != nullptr && batch->owner == impl_.get())
      << "Detector::Run: a batch that this detector's Prepare did not make";
  if (batch->results.empty()) return {};
  try {
    impl_->Run(*batch);
  } catch (const NonFiniteOutputError& e) {
    // The model names no frame; the batch does.
    const std::string& id = batch->results.at(e.batch_index()).id;
    STEREODET_THROW_IO() << "frame " << (id.empty() ? "(no id)" : id) << ": "
                         << impl_->model_dir.string() << " (" << impl_->family << " "
                         << impl_->input << "): the network's " << e.output()
                         << " are not finite (NaN or inf); its weights overflow on this input "
                            "(a training that diverged?): retrain the model";
  }
  if (impl_->calibration) {
    for (DetectResult& r : batch->results) impl_->calibration->Apply(&r.objects);
  }
  return std::move(batch->results);
}

std::vector<DetectResult> Detector::DetectBatch(const std::vector<StereoFrame>& frames) {
  return Run(Prepare(frames));
}

DetectResult Detector::Detect(const StereoFrame& frame) {
  std::vector<DetectResult> results = DetectBatch({frame});
  return std::move(results.front());
}

Detector OpenDetectorOfFamily(const fs::path& model_dir, const DetectorOptions& options,
                              const std::string& family) {
  Detector detector = Detector::Open(model_dir, options);
  STEREODET_CHECK(detector.family() == family)
      << model_dir.string() << " holds a " << detector.family() << " model, not "
      << (family == "det3d" ? "a " : "an ") << family << " one: use `detect " << detector.family()
      << "` or `detect --model`";
  return detector;
}

}  // namespace stereodet
