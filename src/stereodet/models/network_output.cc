#include "stereodet/models/network_output.h"

namespace stereodet {

NonFiniteOutputError::NonFiniteOutputError(size_t batch_index, const std::string& output)
    : std::runtime_error("the network's " + output + " for input " + std::to_string(batch_index) +
                         " of the batch are not finite (NaN or inf)"),
      batch_index_(batch_index),
      output_(output) {}

}  // namespace stereodet
