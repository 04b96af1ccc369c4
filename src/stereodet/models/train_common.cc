#include "stereodet/models/train_common.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>

#include "stereodet/models/model_json.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/output_folder.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/strings.h"

namespace stereodet {

double WarmupCosineLearningRate(double peak, int warmup_steps, double final_fraction, int64_t step,
                                int64_t total_steps) {
  const double warmup = warmup_steps > 0 ? std::min(1.0, (step + 1.0) / warmup_steps) : 1.0;
  const double progress =
      total_steps > 1 ? std::clamp(static_cast<double>(step) / (total_steps - 1), 0.0, 1.0) : 1.0;
  const double cosine = 0.5 * (1.0 + std::cos(M_PI * progress));
  return peak * warmup * (final_fraction + (1.0 - final_fraction) * cosine);
}

std::string NewTrainingRunId() {
  std::random_device device;
  const uint64_t random = (static_cast<uint64_t>(device()) << 32) ^ device();
  const auto now = std::chrono::system_clock::now().time_since_epoch().count();
  return HashHex(Fnv1a64(std::to_string(now), random));
}

std::string WarmupWarning(int warmup_steps, int64_t steps_per_epoch, int epochs) {
  const int64_t total_steps = steps_per_epoch * epochs;
  if (total_steps >= warmup_steps) return "";
  return fmt::format(
      "warning: this training has {} steps ({} epoch{} of {}), fewer than the learning-rate "
      "warm-up's {}; it never reaches the peak rate (more --epochs, more frames or a smaller "
      "--batch-size)\n",
      total_steps, epochs, epochs == 1 ? "" : "s", steps_per_epoch, warmup_steps);
}

bool PrepareModelFolder(const std::filesystem::path& out_dir, const std::string& tool, bool resume,
                        bool force) {
  namespace fs = std::filesystem;
  // A model folder is this training's only when this family's training made it: a detection
  // folder, a data set or another family's model is refused whatever --force says.
  CheckOutputFolderOwner(out_dir, tool, {tool});
  RemoveStaleTemporaries(out_dir);
  const fs::path checkpoint_path = out_dir / kCheckpointFile;
  const fs::path weights_path = out_dir / kModelWeightsFile;
  const bool resuming = resume && fs::exists(checkpoint_path);
  // Never train over a model silently: it is resumed (with its checkpoint) or replaced on request.
  const bool has_model = fs::exists(weights_path) || fs::exists(checkpoint_path);
  if (has_model && !resuming && !force) {
    STEREODET_THROW_ARG() << out_dir.string() << " holds a trained model ("
                          << (fs::exists(weights_path) ? kModelWeightsFile : kCheckpointFile) << ")"
                          << (resume ? " but no checkpoint.pt to resume from" : "")
                          << "; use --resume to continue its training, --force to train a new "
                             "model over it, or another --out";
  }
  CheckFolderWritable(out_dir);
  if (has_model && force) {
    for (const char* file :
         {kModelWeightsFile, kModelConfigFile, kCheckpointFile, kTrainLogFile, kRunManifestFile}) {
      fs::remove(out_dir / file);
    }
  }
  return resuming;
}

std::string UnfinishedTrainingWarning(const std::filesystem::path& model_dir) {
  const std::optional<RunManifest> manifest = ReadRunManifest(model_dir);
  if (!manifest) return "";
  const nlohmann::json settings = nlohmann::json::parse(manifest->settings_json, nullptr, false);
  if (!settings.is_object() || !settings.contains("epochs") || !settings.contains("epochs_done") ||
      !settings["epochs"].is_number_integer() || !settings["epochs_done"].is_number_integer()) {
    return "";
  }
  const int64_t epochs = settings["epochs"].get<int64_t>();
  const int64_t done = settings["epochs_done"].get<int64_t>();
  if (done >= epochs) return "";
  return fmt::format(
      "warning: {} was trained for {} of its {} epochs (its training stopped early; --resume "
      "finishes it); its detections are those of an unfinished model\n",
      model_dir.string(), done, epochs);
}

std::string KeptLogLines(const std::filesystem::path& path, const std::string& header,
                         int epochs_done) {
  std::string kept = header + "\n";
  if (!std::filesystem::exists(path)) return kept;
  std::istringstream in(ReadFile(path));
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    const std::vector<std::string_view> fields = Split(line, ',');
    if (fields.empty()) continue;
    const std::optional<long long> epoch = ParseInt(fields[0]);
    if (epoch && *epoch <= epochs_done) kept += line + "\n";
  }
  return kept;
}

}  // namespace stereodet
