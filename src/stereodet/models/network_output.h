// What a model's Detect throws when its network's output for one input is not finite.
#ifndef STEREODET_MODELS_NETWORK_OUTPUT_H_
#define STEREODET_MODELS_NETWORK_OUTPUT_H_

#include <cstddef>
#include <stdexcept>
#include <string>

namespace stereodet {

// Thrown by SsdModel::Detect, RpnModel::Detect and Det3dModel::Detect when the network's output
// for one input of the batch holds a NaN or an infinity. Weights are checked when a model is
// opened, but finite weights can still overflow (a training that diverged short of inf, an input
// far outside the training's range), and decoding such an output gives empty or arbitrary boxes
// with no other sign. Detector::Run rethrows it as a std::runtime_error naming the model folder
// and the frame.
class NonFiniteOutputError : public std::runtime_error {
 public:
  // `batch_index`: the input's position in the batch given to Detect; `output`: which of the
  // network's outputs ("class scores", "objectness", ...).
  NonFiniteOutputError(size_t batch_index, const std::string& output);

  size_t batch_index() const { return batch_index_; }
  const std::string& output() const { return output_; }

 private:
  size_t batch_index_;
  std::string output_;
};

}  // namespace stereodet

#endif  // STEREODET_MODELS_NETWORK_OUTPUT_H_
