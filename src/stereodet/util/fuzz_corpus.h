// Test support (include from *_test.cc only): the files of a libFuzzer corpus, fuzz/corpus/NAME/,
// which the tests beside each parser replay in every build (fuzz/CMakeLists.txt lists them).
#ifndef STEREODET_UTIL_FUZZ_CORPUS_H_
#define STEREODET_UTIL_FUZZ_CORPUS_H_

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "stereodet/util/test_paths.h"

namespace stereodet {

// The regular files of fuzz/corpus/`name`/ in name order (empty when the folder is missing).
inline std::vector<std::filesystem::path> FuzzCorpusFiles(const std::string& name) {
  const std::filesystem::path dir = ::stereodet::TestSourceDir() / "fuzz/corpus" / name;
  std::vector<std::filesystem::path> files;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace stereodet

#endif  // STEREODET_UTIL_FUZZ_CORPUS_H_
