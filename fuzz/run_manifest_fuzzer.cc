// libFuzzer target for the run manifest reader (RunManifestFromJson, run.json in every output
// folder).
//
// Any input must either parse or throw ParseError; what parses must be writable again and read
// back to the same manifest.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "stereodet/util/check.h"
#include "stereodet/util/run_manifest.h"

namespace {

void Fail(const char* what) {
  std::fprintf(stderr, "run_manifest_fuzzer: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stereodet;
  const std::string text(reinterpret_cast<const char*>(data), size);
  RunManifest manifest;
  try {
    manifest = RunManifestFromJson(text, "run.json");
  } catch (const ParseError&) {
    return 0;
  }
  const std::string written = RunManifestToJson(manifest);  // must not throw
  const RunManifest again = RunManifestFromJson(written, "written.json");
  if (again.tool != manifest.tool || again.version != manifest.version ||
      again.command_line != manifest.command_line || again.inputs != manifest.inputs ||
      again.frames != manifest.frames || again.settings_json != manifest.settings_json) {
    Fail("read(write(manifest)) != manifest");
  }
  if (RunManifestToJson(again) != written) Fail("writing is not stable");
  return 0;
}
