#include "stereodet/util/test_paths.h"

namespace stereodet {

const std::filesystem::path& TestSourceDir() {
  static const std::filesystem::path dir(STEREODET_SOURCE_DIR);
  return dir;
}

const std::filesystem::path& TestBinaryDir() {
  static const std::filesystem::path dir(STEREODET_BINARY_DIR);
  return dir;
}

}  // namespace stereodet
