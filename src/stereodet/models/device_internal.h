// ComputeDevice as a torch::Device, for the .cc files that include LibTorch.
#ifndef STEREODET_MODELS_DEVICE_INTERNAL_H_
#define STEREODET_MODELS_DEVICE_INTERNAL_H_

#include <torch/torch.h>

#include <string>
#include <vector>

#include "stereodet/models/device.h"
#include "stereodet/models/network_output.h"

namespace stereodet::internal {

inline torch::Device TorchDevice(ComputeDevice device) {
  return device == ComputeDevice::kCuda ? torch::Device(torch::kCUDA) : torch::Device(torch::kCPU);
}

// Throws NonFiniteOutputError for the first row (dim 0) of `output` that holds a NaN or an
// infinity: row r belongs to the batch's input r, or to `input_of_row[r]` when that is given (the
// rows of several inputs together, as the second stage's regions of interest). `name` says which
// output it is. One reduction on the tensor's device, one small copy when something is wrong.
inline void CheckFiniteRows(const torch::Tensor& output, const std::string& name,
                            const std::vector<size_t>& input_of_row = {}) {
  if (output.numel() == 0) return;
  const torch::Tensor finite = torch::isfinite(output).reshape({output.size(0), -1}).all(1);
  if (finite.all().item<bool>()) return;
  const int64_t row = torch::logical_not(finite).nonzero()[0][0].item<int64_t>();
  throw NonFiniteOutputError(
      input_of_row.empty() ? static_cast<size_t>(row) : input_of_row.at(static_cast<size_t>(row)),
      name);
}

}  // namespace stereodet::internal

#endif  // STEREODET_MODELS_DEVICE_INTERNAL_H_
