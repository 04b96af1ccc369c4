// libFuzzer target for the split-file parser (ParseSplit).
//
// Any input must either parse or throw ParseError naming a line >= 1 and the field "frame id";
// the sanitizers catch memory errors and undefined behaviour. What parses must round-trip: the ids
// written one a line parse back to the same ids.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/kitti/dataset.h"
#include "stereodet/util/check.h"

namespace {

void Fail(const char* what) {
  std::fprintf(stderr, "split_fuzzer: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stereodet;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> ids;
  try {
    ids = ParseSplit(text, "fuzz.txt");
  } catch (const ParseError& e) {
    if (e.line() < 1 || e.field() != "frame id") Fail("ParseError without line or field");
    if (e.message().size() > 200) Fail("the message echoes too much of the input");
    return 0;
  }
  std::string written;
  for (const std::string& id : ids) {
    if (id.empty()) Fail("an empty id");
    written += id + "\n";
  }
  if (ParseSplit(written, "written.txt") != ids) Fail("parse(write(ids)) != ids");
  return 0;
}
