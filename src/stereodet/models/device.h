// The compute device of the LibTorch models: `--device cpu|cuda` for `train` and `detect`. Nothing
// in the models assumes the CPU: networks, batches and targets go to the chosen device, results
// come back to the host. CI and the committed models use the CPU; a CUDA build of LibTorch (CMake
// takes its prefix) runs the same code on a GPU.
#ifndef STEREODET_MODELS_DEVICE_H_
#define STEREODET_MODELS_DEVICE_H_

#include <optional>
#include <string_view>
#include <vector>

#include "stereodet/stereo/rgbh.h"

namespace stereodet {

enum class ComputeDevice { kCpu, kCuda };

const char* ComputeDeviceName(ComputeDevice device);  // "cpu", "cuda"
// "cpu" or "cuda" (also "cuda:N" is not accepted: one GPU, the current one).
std::optional<ComputeDevice> ParseComputeDevice(std::string_view text);
// Parses `text` and checks that the device can be used. Throws std::invalid_argument for an unknown
// name, std::runtime_error for cuda when this LibTorch has no CUDA support or sees no GPU.
ComputeDevice ResolveComputeDevice(std::string_view text);
// True when LibTorch was built with CUDA and sees at least one GPU.
bool CudaAvailable();

// Threads LibTorch's operators use (0 = leave LibTorch's default, all cores). Process-wide.
void SetTorchThreads(int num_threads);

// Concatenates `inputs` (each `channels` planes of height x width) into one
// [image][channel][row][column] array: a batch as the image networks take it. Throws
// std::invalid_argument for an input of another shape.
std::vector<float> StackPlanar(const std::vector<PlanarImage>& inputs, int channels, int height,
                               int width);

}  // namespace stereodet

#endif  // STEREODET_MODELS_DEVICE_H_
