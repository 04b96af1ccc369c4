// model.json of every family without LibTorch (models_core): the configs' text, their refusals, and
// the model_json fuzzer's corpus replayed in every build (the sanitizer build included).
#include "stereodet/models/model_json.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "stereodet/models/config_test_util.h"
#include "stereodet/models/model_json_internal.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/fuzz_corpus.h"

namespace stereodet {
namespace {

using ::testing::HasSubstr;

// One rule for every family's class names; each family's Check() applies it.
TEST(ModelJsonTest, ClassNamesAreOneToTwoHundredFiftySixWordsWithoutCommas) {
  EXPECT_NO_THROW(internal::CheckClassNames({"Car"}));
  EXPECT_NO_THROW(internal::CheckClassNames(std::vector<std::string>(256, "Car")));
  EXPECT_THROW(internal::CheckClassNames({}), std::invalid_argument);
  EXPECT_THROW(internal::CheckClassNames(std::vector<std::string>(257, "Car")),
               std::invalid_argument);
  for (const char* bad : {"", "Race car", "Car,Van", "Car\t", "\nCar"}) {
    SCOPED_TRACE(bad);
    EXPECT_THROW(internal::CheckClassNames({"Car", bad}), std::invalid_argument);
  }
  SsdConfig ssd = TinySsdConfig();
  RpnConfig rpn = TinyRpnConfig();
  Det3dConfig det3d = TinyDet3dConfig();
  ssd.classes = rpn.classes = det3d.classes = {"Car", "Van,Truck"};
  EXPECT_THROW(ssd.Check(), std::invalid_argument);
  EXPECT_THROW(rpn.Check(), std::invalid_argument);
  EXPECT_THROW(det3d.Check(), std::invalid_argument);
}

TEST(ModelJsonTest, SsdConfigJsonRoundTrip) {
  SsdConfig config = TinySsdConfig(InputEncoding::kRgbhFixed);
  config.classes = {"Car"};
  config.boxes.aspect_ratios = {0.5, 2.5};
  const SsdConfig back = SsdConfigFromJson(SsdConfigToJson(config), "test");
  EXPECT_EQ(back.encoding, config.encoding);
  EXPECT_EQ(back.classes, config.classes);
  EXPECT_EQ(back.boxes.aspect_ratios, config.boxes.aspect_ratios);
  EXPECT_EQ(back.boxes.min_size_fraction, config.boxes.min_size_fraction);
  EXPECT_EQ(back.base_channels, config.base_channels);
  EXPECT_THROW(SsdConfigFromJson("{\"version\": 1}", "model.json"), ParseError);
  EXPECT_THROW(SsdConfigFromJson("not json", "model.json"), ParseError);
}

TEST(ModelJsonTest, SsdConfigWithAnUnknownEncodingNamesTheField) {
  std::string json = SsdConfigToJson(TinySsdConfig(InputEncoding::kRgb));
  const size_t at = json.find("\"rgb\"");
  ASSERT_NE(at, std::string::npos) << json;
  json.replace(at, 5, "\"rgbd\"");
  try {
    SsdConfigFromJson(json, "model.json");
    FAIL() << "an unknown encoding was accepted";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), "model.json");
    EXPECT_EQ(e.field(), "encoding");
    EXPECT_NE(e.message().find("unknown input encoding 'rgbd'"), std::string::npos) << e.what();
  }
}

// A model.json with absurd sizes is refused at once, naming the field (it ran out of memory after a
// long wait before).
TEST(ModelJsonTest, SsdConfigWithAbsurdSizesIsRefusedNamingThem) {
  const std::string json = SsdConfigToJson(TinySsdConfig(InputEncoding::kRgb));
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"\"input_width\": 64", "\"input_width\": 1000000"},
           {"\"input_height\": 48", "\"input_height\": 70000"}}) {
    std::string bad = json;
    const size_t at = bad.find(from);
    ASSERT_NE(at, std::string::npos) << json;
    bad.replace(at, from.size(), to);
    try {
      SsdConfigFromJson(bad, "model.json");
      FAIL() << to;
    } catch (const ParseError& e) {
      EXPECT_NE(e.message().find("input size must be in [16, 4096] px a side"), std::string::npos)
          << e.what();
    }
  }
  SsdConfig many = TinySsdConfig(InputEncoding::kRgb);
  many.classes.assign(300, "Car");
  EXPECT_THROW(many.Check(), std::invalid_argument);
}

// Parses `text` with `read` and round-trips what parses through `write`; 1 when it parsed, 0 when
// it threw ParseError naming `source`.
template <typename Read, typename Write>
int ParsesAndRoundTrips(const std::string& text, const std::string& source, Read read,
                        Write write) {
  try {
    const std::string written = write(read(text, source));
    EXPECT_EQ(write(read(written, "written")), written);
    return 1;
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), source);
  } catch (const std::exception& e) {
    ADD_FAILURE() << "unexpected exception: " << e.what();
  }
  return 0;
}

// The model_json fuzzer's corpus (fuzz/model_json_fuzzer.cc), replayed for every family: each
// model.json parses or throws ParseError naming the file (1e300 or 99999999999 where an int belongs
// included: no undefined behaviour), and what parses round-trips.
TEST(ModelJsonTest, FuzzCorpusParsesOrThrowsParseError) {
  const std::vector<std::filesystem::path> files = FuzzCorpusFiles("model_json");
  ASSERT_GE(files.size(), 5u) << "the model_json corpus is missing";
  int parsed = 0, rejected = 0, rpn = 0, det3d = 0, stereo_rejected = 0;
  for (const std::filesystem::path& path : files) {
    SCOPED_TRACE(path.filename().string());
    const std::string text = ReadFile(path);
    // The records parse or throw ParseError naming the file, nothing else (a stereo setting out of
    // range threw std::invalid_argument: rpn_stereo_out_of_range.json, from the fuzzer).
    for (auto read :
         {+[](const std::string&s, const std::string&f) { ReadWeightsRecord(s, f); },
          +[](const std::string&s, const std::string&f) { ReadStereoRecord(s, f); },
          +[](const std::string&s, const std::string&f) { ReadRpnStereoRecord(s, f); }}) {
      try {
        read(text, path.string());
      } catch (const ParseError& e) {
        EXPECT_EQ(e.file(), path.string());
        stereo_rejected += e.field() == "stereo";
      } catch (const std::exception& e) {
        ADD_FAILURE() << "not a ParseError: " << e.what();
      }
    }
    const int ssd = ParsesAndRoundTrips(text, path.string(), SsdConfigFromJson,
                                        [](const SsdConfig& c) { return SsdConfigToJson(c); });
    parsed += ssd;
    rejected += 1 - ssd;
    rpn += ParsesAndRoundTrips(text, path.string(), RpnConfigFromJson,
                               [](const RpnConfig& c) { return RpnConfigToJson(c); });
    det3d += ParsesAndRoundTrips(text, path.string(), Det3dConfigFromJson,
                                 [](const Det3dConfig& c) { return Det3dConfigToJson(c); });
  }
  EXPECT_GT(parsed, 0);
  EXPECT_GT(rejected, 0);
  EXPECT_GT(rpn, 0);              // rpn_rgbd.json
  EXPECT_GT(det3d, 0);            // det3d_lidar.json
  EXPECT_GT(stereo_rejected, 0);  // rpn_stereo_out_of_range.json
  try {
    SsdConfigFromJson(
        ReadFile(FuzzCorpusFiles("model_json").at(0).parent_path() / "float_width.json"),
        "model.json");
    ADD_FAILURE() << "no error";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.field(), "input_width");
    EXPECT_THAT(e.message(), HasSubstr("expected an integer"));
  }
}

}  // namespace
}  // namespace stereodet
