#include "stereodet/models/device.h"

#include <torch/cuda.h>

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

}  // namespace stereodet
