// Test support (include from *_test.cc only): a temporary folder unique to the running test.
//
// ctest runs the tests of one binary as separate processes in parallel, so a fixed folder name
// shared by several tests makes them race, and so do two builds on one host. The folder is named
// after the test suite, the test, an optional suffix (for a test that needs two) and the process
// id, created empty, and removed with everything in it when the object dies.
#ifndef STEREODET_UTIL_TEST_TEMP_DIR_H_
#define STEREODET_UTIL_TEST_TEMP_DIR_H_

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>

namespace stereodet {

class TestTempDir {
 public:
  explicit TestTempDir(std::string_view suffix = "") {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = "stereodet_";
    if (info != nullptr) name.append(info->test_suite_name()).append("_").append(info->name());
    if (!suffix.empty()) name.append("_").append(suffix);
    name.append("_").append(std::to_string(::getpid()));
    for (char& c : name) {
      if (c == '/') c = '_';  // parameterized test names contain '/'
    }
    path_ = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TestTempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TestTempDir(const TestTempDir&) = delete;
  TestTempDir& operator=(const TestTempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::filesystem::path& child) const {
    return path_ / child;
  }

 private:
  std::filesystem::path path_;
};

}  // namespace stereodet

#endif  // STEREODET_UTIL_TEST_TEMP_DIR_H_
