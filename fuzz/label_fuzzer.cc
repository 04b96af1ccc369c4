// libFuzzer target for the KITTI label/detection parser (ParseObjects).
//
// Any input must either parse or throw ParseError; nothing else may escape, and the sanitizers
// catch memory errors and undefined behaviour. What parses must also survive a round trip:
// parse(format(objects)) == objects, and lenient mode must keep exactly the lines strict mode
// accepts.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "stereodet/kitti/label_io.h"
#include "stereodet/util/check.h"

namespace {

void Fail(const char* what) {
  std::fprintf(stderr, "label_fuzzer: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stereodet;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  for (ObjectFileKind kind :
       {ObjectFileKind::kLabel, ObjectFileKind::kDetection, ObjectFileKind::kAny}) {
    ObjectParseOptions options;
    options.kind = kind;
    options.lenient = true;
    const ObjectFile lenient = ParseObjects(text, "fuzz.txt", options);  // must never throw
    if (lenient.skipped_lines != static_cast<int>(lenient.problems.size())) {
      Fail("skipped_lines != problems.size()");
    }

    options.lenient = false;
    bool strict_ok = true;
    try {
      const ObjectFile strict = ParseObjects(text, "fuzz.txt", options);
      if (!(strict.objects == lenient.objects)) Fail("strict and lenient disagree on a good file");
    } catch (const ParseError& e) {
      strict_ok = false;
      if (e.line() < 1 || e.field().empty()) Fail("ParseError without line or field");
    }
    if (strict_ok != (lenient.skipped_lines == 0)) Fail("strict threw but lenient skipped nothing");

    // Round trip what was accepted.
    const std::string formatted = FormatObjects(lenient.objects);
    options.kind = ObjectFileKind::kAny;
    const ObjectFile again = ParseObjects(formatted, "formatted.txt", options);  // must not throw
    if (!(again.objects == lenient.objects)) Fail("parse(format(objects)) != objects");
    if (FormatObjects(again.objects) != formatted) Fail("format is not stable");
  }
  return 0;
}
