// Test support (link from *_test.cc only): where the checkout and the build tree are.
//
// The paths are compiled into test_paths.cc alone, not into every test's command line, so that a
// second checkout (a git worktree) compiles the tests to the same objects and ccache can reuse
// them; only this one file differs between checkouts.
#ifndef STEREODET_UTIL_TEST_PATHS_H_
#define STEREODET_UTIL_TEST_PATHS_H_

#include <filesystem>

namespace stereodet {

// The source checkout's root (absolute), which holds tests/data and fuzz/corpus.
const std::filesystem::path& TestSourceDir();

// The CMake build tree's root (absolute), where tests may write scratch folders.
const std::filesystem::path& TestBinaryDir();

}  // namespace stereodet

#endif  // STEREODET_UTIL_TEST_PATHS_H_
