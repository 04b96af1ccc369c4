#include "stereodet/models/device.h"

#include <torch/cuda.h>
#include <torch/torch.h>

#include "stereodet/util/check.h"

namespace stereodet {

const char* ComputeDeviceName(ComputeDevice device) {
  return device == ComputeDevice::kCuda ? "cuda" : "cpu";
}

std::optional<ComputeDevice> ParseComputeDevice(std::string_view text) {
  if (text == "cpu") return ComputeDevice::kCpu;
  if (text == "cuda") return ComputeDevice::kCuda;
  return std::nullopt;
}

bool CudaAvailable() { return torch::cuda::is_available(); }

ComputeDevice ResolveComputeDevice(std::string_view text) {
  const std::optional<ComputeDevice> device = ParseComputeDevice(text);
  STEREODET_CHECK(device.has_value()) << "unknown device '" << text << "' (expected cpu or cuda)";
  if (*device == ComputeDevice::kCuda) {
    STEREODET_CHECK_IO(CudaAvailable())
        << "--device cuda: no CUDA device is available (this LibTorch was built without CUDA, "
           "or no GPU is visible); use --device cpu, or build against a CUDA LibTorch "
           "(-DTorch_DIR=...)";
  }
  return *device;
}

void SetTorchThreads(int num_threads) {
  STEREODET_CHECK(num_threads >= 0) << "threads must be >= 0, got " << num_threads;
  if (num_threads > 0) torch::set_num_threads(num_threads);
}

std::vector<float> StackPlanar(const std::vector<PlanarImage>& inputs, int channels, int height,
                               int width) {
  const size_t size = static_cast<size_t>(channels) * height * width;
  std::vector<float> stacked;
  stacked.reserve(inputs.size() * size);
  for (size_t i = 0; i < inputs.size(); ++i) {
    const PlanarImage& input = inputs[i];
    STEREODET_CHECK(input.channels == channels && input.rows == height && input.cols == width &&
                    input.data.size() == size)
        << "input " << i << " must have " << channels << " planes of " << width << "x" << height
        << " px, got " << input.channels << " of " << input.cols << "x" << input.rows;
    stacked.insert(stacked.end(), input.data.begin(), input.data.end());
  }
  return stacked;
}

}  // namespace stereodet
