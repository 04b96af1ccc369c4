// libFuzzer target for a model folder's model.json, every family: SsdConfigFromJson,
// RpnConfigFromJson, Det3dConfigFromJson, ReadWeightsRecord, ReadStereoRecord.
//
// Any input must either parse or throw ParseError; the sanitizers catch undefined behaviour (a
// float such as 1e300 where an integer belongs). What parses round-trips through the family's
// *ConfigToJson. Links models_core alone: the torch-free half of the models module.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "stereodet/models/det3d/det3d_config.h"
#include "stereodet/models/model_json.h"
#include "stereodet/models/rpn/rpn_config.h"
#include "stereodet/models/ssd/ssd_config.h"
#include "stereodet/util/check.h"

namespace {

void Fail(const char* what) {
  std::fprintf(stderr, "model_json_fuzzer: %s\n", what);
  std::abort();
}

// read(text) either throws ParseError or gives a config that write() turns into text that reads
// back to the same text.
template <typename Read, typename Write>
void CheckFamily(const std::string& text, Read read, Write write, const char* family) {
  std::string written;
  try {
    written = write(read(text, "model.json"));
  } catch (const stereodet::ParseError&) {
    return;
  }
  if (write(read(written, "written.json")) != written) {
    std::fprintf(stderr, "model_json_fuzzer: %s: ", family);
    Fail("read(write(config)) != config");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stereodet;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    (void)ReadWeightsRecord(text, "model.json");
  } catch (const ParseError&) {
  }
  try {
    (void)ReadStereoRecord(text, "model.json");
  } catch (const ParseError&) {
  }
  CheckFamily(
      text, SsdConfigFromJson, [](const SsdConfig& c) { return SsdConfigToJson(c); }, "ssd");
  CheckFamily(
      text, RpnConfigFromJson, [](const RpnConfig& c) { return RpnConfigToJson(c); }, "rpn");
  CheckFamily(
      text, Det3dConfigFromJson, [](const Det3dConfig& c) { return Det3dConfigToJson(c); },
      "det3d");
  return 0;
}
