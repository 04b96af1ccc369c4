#include <nlohmann/json.hpp>
#include <sstream>

#include "stereodet/models/checkpoint_internal.h"
#include "stereodet/models/model_json.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/run_manifest.h"

namespace stereodet::internal {

std::string FirstConfigDifference(const std::string& recorded_text, const std::string& model_text) {
  const nlohmann::json recorded = nlohmann::json::parse(recorded_text, nullptr, false);
  const nlohmann::json model = nlohmann::json::parse(model_text);
  if (!recorded.is_object()) return "its recorded config is not a JSON object";
  for (const auto& [key, value] : model.items()) {
    const auto it = recorded.find(key);
    const std::string here = it == recorded.end() ? "nothing" : it->dump();
    if (here != value.dump()) return key + ": " + here + " here, " + value.dump() + " in the model";
  }
  return "";
}

std::string SerializeArchive(torch::serialize::OutputArchive& archive) {
  // Through a stream, not a file name: LibTorch names the archive's root folder after the file
  // it writes, and our temporary files' names hold the process id, so the same tensors would
  // give other bytes (and another model.json fingerprint) in every process.
  std::ostringstream bytes;
  archive.save_to(bytes);
  return std::move(bytes).str();
}

void SaveTrainingCheckpoint(const std::filesystem::path& path, const torch::nn::Module& module,
                            const torch::optim::Optimizer& optimizer, int epochs_done,
                            const CheckpointRecord& record) {
  torch::serialize::OutputArchive root, model, optim;
  module.save(model);
  optimizer.save(optim);
  root.write("model", model);
  root.write("optimizer", optim);
  root.write("epochs_done", torch::tensor(static_cast<int64_t>(epochs_done)));
  root.write("config", c10::IValue(record.config_json));
  root.write("parameters", torch::tensor(record.parameters));
  root.write("training_run", c10::IValue(record.training_run));
  WriteFileAtomically(path, SerializeArchive(root));
}

int LoadTrainingCheckpoint(const std::filesystem::path& path, torch::nn::Module& module,
                           torch::optim::Optimizer& optimizer, const torch::Device& device,
                           const CheckpointRecord& expected) {
  STEREODET_CHECK_IO(std::filesystem::is_regular_file(path))
      << "missing checkpoint " << path.string();
  try {
    torch::serialize::InputArchive root, model, optim;
    root.load_from(path.string(), device);
    // Its own record first: LibTorch's shape errors would name neither the file nor the setting.
    c10::IValue recorded_config, recorded_run;
    if (root.try_read("config", recorded_config)) {
      const std::string mismatch =
          FirstConfigDifference(recorded_config.toStringRef(), expected.config_json);
      STEREODET_CHECK_IO(mismatch.empty())
          << path.string() << " was written for another model: " << mismatch
          << "; it is not this model folder's checkpoint (copy a model folder whole, or train "
             "anew with --force)";
      torch::Tensor parameters;
      root.read("parameters", parameters);
      STEREODET_CHECK_IO(parameters.item<int64_t>() == expected.parameters)
          << path.string() << " holds " << parameters.item<int64_t>() << " parameters, the model "
          << expected.parameters;
    }
    if (!expected.training_run.empty()) {
      const std::string found =
          root.try_read("training_run", recorded_run) ? recorded_run.toStringRef() : "";
      STEREODET_CHECK_IO(found == expected.training_run)
          << path.string() << " is from another training run ("
          << (found.empty() ? "none recorded" : found) << ") than the folder's model.json ("
          << expected.training_run
          << "): a checkpoint copied from another model folder? Copy a model folder whole, or "
             "train anew with --force";
    }
    root.read("model", model);
    root.read("optimizer", optim);
    torch::Tensor epochs;
    root.read("epochs_done", epochs);
    module.load(model);
    optimizer.load(optim);
    return static_cast<int>(epochs.item<int64_t>());
  } catch (const c10::Error& e) {
    STEREODET_THROW_IO() << "cannot load checkpoint " << path.string() << ": "
                         << e.what_without_backtrace();
  }
  return 0;
}

int64_t CountParameters(const torch::nn::Module& module) {
  int64_t count = 0;
  for (const auto& p : module.parameters(/*recurse=*/true)) count += p.numel();
  return count;
}

void SaveModelFolder(const std::filesystem::path& model_dir, const torch::nn::Module& module,
                     const std::function<std::string(const std::string& fnv1a64)>& config_json) {
  std::filesystem::create_directories(model_dir);
  torch::serialize::OutputArchive archive;
  module.save(archive);
  const std::string bytes = SerializeArchive(archive);
  WriteFileAtomically(model_dir / kModelWeightsFile, bytes);
  WriteFileAtomically(model_dir / kModelConfigFile, config_json(HashHex(Fnv1a64(bytes))));
}

void LoadModelWeights(const std::filesystem::path& model_dir, const std::string& config_text,
                      torch::nn::Module& module, const torch::Device& device) {
  const std::filesystem::path path = model_dir / kModelWeightsFile;
  const std::string config_source = (model_dir / kModelConfigFile).string();
  const WeightsRecord record = ReadWeightsRecord(config_text, config_source);
  STEREODET_CHECK_IO(std::filesystem::is_regular_file(path))
      << "missing weights file " << path.string();
  // The bytes once, through ReadFile (a FIFO or a huge file is refused, not waited on): hashed,
  // then handed to LibTorch.
  const std::string bytes = ReadFile(path);
  if (!record.fnv1a64.empty()) {
    const std::string hash = HashHex(Fnv1a64(bytes));
    STEREODET_CHECK_IO(hash == record.fnv1a64)
        << path.string() << " does not belong to " << config_source << ": its hash is " << hash
        << ", model.json records " << record.fnv1a64
        << " (weights of another training?); copy the model folder whole";
  }
  try {
    torch::serialize::InputArchive archive;
    archive.load_from(bytes.data(), bytes.size(), device);
    module.load(archive);
  } catch (const c10::Error& e) {
    STEREODET_THROW_IO() << "cannot load weights " << path.string() << " for the model in "
                         << config_source << ": " << e.what_without_backtrace();
  }
  // A diverged training or an edited file: NaN or inf weights give empty or arbitrary detections
  // with no other sign, so they are refused here, for every family, naming the first tensor.
  torch::NoGradGuard no_grad;
  for (const auto& item : module.named_parameters(/*recurse=*/true)) {
    const bool finite = torch::isfinite(item.value()).all().item().toBool();
    STEREODET_CHECK_IO(finite)
        << path.string() << " holds non-finite weights (NaN or inf) in '" << item.key()
        << "': the training that wrote it diverged, or the file was changed; retrain the model";
  }
  for (const auto& item : module.named_buffers(/*recurse=*/true)) {
    if (!item.value().is_floating_point()) continue;
    const bool finite = torch::isfinite(item.value()).all().item().toBool();
    STEREODET_CHECK_IO(finite)
        << path.string() << " holds non-finite values (NaN or inf) in '" << item.key()
        << "': the training that wrote it diverged, or the file was changed; retrain the model";
  }
  if (record.parameters >= 0) {
    const int64_t count = CountParameters(module);
    STEREODET_CHECK_IO(count == record.parameters)
        << path.string() << " holds " << count << " parameters, " << config_source << " records "
        << record.parameters;
  }
}

}  // namespace stereodet::internal
