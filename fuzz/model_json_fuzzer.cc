// libFuzzer target for a model folder's model.json (SsdConfigFromJson, ReadWeightsRecord).
//
// Any input must either parse or throw ParseError; the sanitizers catch undefined behaviour (a
// float such as 1e300 where an integer belongs). What parses round-trips through SsdConfigToJson.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "stereodet/models/ssd/ssd_model.h"
#include "stereodet/util/check.h"

namespace {

void Fail(const char* what) {
  std::fprintf(stderr, "model_json_fuzzer: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stereodet;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    (void)ReadWeightsRecord(text, "model.json");
  } catch (const ParseError&) {
  }
  SsdConfig config;
  try {
    config = SsdConfigFromJson(text, "model.json");
  } catch (const ParseError&) {
    return 0;
  }
  const std::string written = SsdConfigToJson(config);
  if (SsdConfigToJson(SsdConfigFromJson(written, "written.json")) != written) {
    Fail("read(write(config)) != config");
  }
  return 0;
}
