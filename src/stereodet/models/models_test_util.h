// Test support for the models tests (include from *_test.cc only).
#ifndef STEREODET_MODELS_MODELS_TEST_UTIL_H_
#define STEREODET_MODELS_MODELS_TEST_UTIL_H_

#include <filesystem>
#include <string>

#include "stereodet/util/test_paths.h"

namespace stereodet {

// An empty folder `name` under the build tree's models_test_tmp/ (removed first if it exists).
// The models tests run as one program (one CTest test), so fixed names do not race.
inline std::filesystem::path ModelsTestDir(const std::string& name) {
  const std::filesystem::path dir = TestBinaryDir() / "models_test_tmp" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace stereodet

#endif  // STEREODET_MODELS_MODELS_TEST_UTIL_H_
