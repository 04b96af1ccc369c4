// ComputeDevice as a torch::Device, for the .cc files that include LibTorch.
#ifndef STEREODET_MODELS_DEVICE_INTERNAL_H_
#define STEREODET_MODELS_DEVICE_INTERNAL_H_

#include <torch/torch.h>

#include "stereodet/models/device.h"

namespace stereodet::internal {

inline torch::Device TorchDevice(ComputeDevice device) {
  return device == ComputeDevice::kCuda ? torch::Device(torch::kCUDA) : torch::Device(torch::kCPU);
}

}  // namespace stereodet::internal

#endif  // STEREODET_MODELS_DEVICE_INTERNAL_H_
