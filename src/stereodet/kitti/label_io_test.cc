#include "stereodet/kitti/label_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/util/check.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// Lines from KITTI's training/label_2 (000000.txt, 000001.txt, 000008.txt) and typical detections.
constexpr char kPedestrian[] =
    "Pedestrian 0.00 0 -0.20 712.40 143.00 810.73 307.92 1.89 0.48 1.20 1.84 1.47 8.41 0.01";
constexpr char kDontCare[] =
    "DontCare -1 -1 -10 503.89 169.71 590.61 190.13 -1 -1 -1 -1000 -1000 -1000 -10";
constexpr char kTruncatedCar[] =
    "Car 0.88 3 -0.69 0.00 192.37 402.31 374.00 1.60 1.57 3.23 -2.70 1.74 3.68 -1.29";
constexpr char kCyclist[] =
    "Cyclist 0.00 0 1.94 330.06 176.41 355.61 213.60 1.72 0.50 1.95 -12.63 1.88 34.09 1.56";
constexpr char kDetection[] =
    "Car -1 -1 -1.56 564.62 174.59 616.43 224.74 1.61 1.66 3.20 -0.69 1.69 25.01 -1.59 0.97";

ParseError ExpectParseError(const std::string& text, ObjectFileKind kind = ObjectFileKind::kLabel) {
  ObjectParseOptions options;
  options.kind = kind;
  try {
    ParseObjects(text, "label_2/000042.txt", options);
  } catch (const ParseError& e) {
    return e;
  }
  ADD_FAILURE() << "no ParseError for: " << text;
  return ParseError("", 0, "", "");
}

TEST(LabelIoTest, ParsesARealKittiLabelLine) {
  const ObjectFile file = ParseObjects(kPedestrian, "x");
  ASSERT_EQ(file.objects.size(), 1u);
  const Object& o = file.objects[0];
  EXPECT_EQ(o.type, "Pedestrian");
  EXPECT_EQ(o.truncated, 0.0);
  EXPECT_EQ(o.occluded, 0);
  EXPECT_EQ(o.alpha, -0.20);
  EXPECT_EQ(o.box, (Box2D{712.40, 143.00, 810.73, 307.92}));
  EXPECT_EQ(o.box3d.h, 1.89);
  EXPECT_EQ(o.box3d.w, 0.48);
  EXPECT_EQ(o.box3d.l, 1.20);
  EXPECT_EQ(o.box3d.location, Eigen::Vector3d(1.84, 1.47, 8.41));
  EXPECT_EQ(o.box3d.rotation_y, 0.01);
  EXPECT_FALSE(o.score.has_value());
  EXPECT_EQ(file.skipped_lines, 0);
  EXPECT_TRUE(file.problems.empty());
}

TEST(LabelIoTest, ParsesDontCareSentinels) {
  const Object o = ParseObjects(kDontCare, "x").objects.at(0);
  EXPECT_TRUE(o.IsDontCare());
  EXPECT_EQ(o.truncated, -1.0);
  EXPECT_EQ(o.occluded, -1);
  EXPECT_EQ(o.alpha, -10.0);
  EXPECT_FALSE(o.Has3D());
  EXPECT_EQ(o.box3d.location, Eigen::Vector3d(-1000, -1000, -1000));
  EXPECT_EQ(o.box3d.rotation_y, -10.0);
}

TEST(LabelIoTest, RealKittiLinesRoundTripByteForByte) {
  for (const char* line : {kPedestrian, kDontCare, kTruncatedCar, kCyclist, kDetection}) {
    ObjectParseOptions options;
    options.kind = ObjectFileKind::kAny;
    const ObjectFile file = ParseObjects(line, "x", options);
    ASSERT_EQ(file.objects.size(), 1u) << line;
    EXPECT_EQ(FormatObject(file.objects[0]), line);
  }
  // A whole file: lines end in '\n', and the text comes back unchanged.
  const std::string text =
      std::string(kTruncatedCar) + "\n" + kPedestrian + "\n" + kDontCare + "\n";
  EXPECT_EQ(FormatObjects(ParseObjects(text, "x").objects), text);
}

TEST(LabelIoTest, DetectionsHaveAScoreLast) {
  ObjectParseOptions options;
  options.kind = ObjectFileKind::kDetection;
  const ObjectFile file = ParseObjects(kDetection, "x", options);
  ASSERT_EQ(file.objects.size(), 1u);
  ASSERT_TRUE(file.objects[0].score.has_value());
  EXPECT_EQ(*file.objects[0].score, 0.97);
  // A label line in a detection file lacks the score.
  const ParseError e = ExpectParseError(kPedestrian, ObjectFileKind::kDetection);
  EXPECT_EQ(e.field(), "score");
  EXPECT_THAT(e.message(), HasSubstr("15 fields"));
}

TEST(LabelIoTest, AnyKindAcceptsBothPerLine) {
  ObjectParseOptions options;
  options.kind = ObjectFileKind::kAny;
  const std::string text = std::string(kPedestrian) + "\n" + kDetection + "\n";
  const ObjectFile file = ParseObjects(text, "x", options);
  ASSERT_EQ(file.objects.size(), 2u);
  EXPECT_FALSE(file.objects[0].score.has_value());
  EXPECT_TRUE(file.objects[1].score.has_value());
}

TEST(LabelIoTest, UnknownClassNamesAreKept) {
  const std::string line =
      "Tram_42 0.00 1 0.50 10.00 20.00 30.00 60.00 3.00 2.50 15.00 4.00 1.60 30.00 0.40";
  const ObjectFile file = ParseObjects(line, "x");
  ASSERT_EQ(file.objects.size(), 1u);
  EXPECT_EQ(file.objects[0].type, "Tram_42");
  EXPECT_EQ(FormatObject(file.objects[0]), line);
}

TEST(LabelIoTest, BlankLinesCrlfAndTabsAreAccepted) {
  const std::string text =
      std::string("\n  \n") + kPedestrian + "\r\n\t\n" + kCyclist;  // no final \n
  const ObjectFile file = ParseObjects(text, "x");
  ASSERT_EQ(file.objects.size(), 2u);
  EXPECT_EQ(file.objects[1].type, "Cyclist");
  const std::string tabbed = "Car\t0.00\t0\t1.00\t1\t2\t3\t4\t1.5\t1.6\t3.9\t1\t1.6\t20\t0.5\t0.9";
  ObjectParseOptions options;
  options.kind = ObjectFileKind::kAny;
  EXPECT_EQ(ParseObjects(tabbed, "x", options).objects.size(), 1u);
}

TEST(LabelIoTest, EmptyTextGivesNoObjects) {
  EXPECT_TRUE(ParseObjects("", "x").objects.empty());
  EXPECT_TRUE(ParseObjects("\n\n \r\n", "x").objects.empty());
}

TEST(LabelIoTest, ALeadingUtf8ByteOrderMarkIsIgnored) {
  // A Windows editor writes EF BB BF first; the first object must still be a Pedestrian, not an
  // unknown class "\xef\xbb\xbfPedestrian".
  const std::string text = std::string("\xEF\xBB\xBF") + kPedestrian + "\n" + kCyclist + "\n";
  const ObjectFile file = ParseObjects(text, "x");
  ASSERT_EQ(file.objects.size(), 2u);
  EXPECT_EQ(file.objects[0].type, "Pedestrian");
  EXPECT_EQ(file.objects, ParseObjects(std::string(kPedestrian) + "\n" + kCyclist, "x").objects);
  // Only at the very start: a mark on the second line stays in that line's type, and is refused.
  const ParseError e = ExpectParseError(std::string(kCyclist) + "\n\xEF\xBB\xBF" + kPedestrian);
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.field(), "type");
  EXPECT_THAT(e.what(), HasSubstr("'\\xef\\xbb\\xbfPedestrian'"));
}

// --- Error cases: each names the file, the 1-based line and the field. ---

TEST(LabelIoErrorTest, AHugeClassNameIsRefusedShortened) {
  const std::string name(10 * 1000 * 1000, 'a');
  const ParseError e = ExpectParseError(std::string(kCyclist) + "\n" + name +
                                        " 0.00 0 1 1 2 3 4 1.5 1.6 3.9 1 1.6 20 0.5");
  EXPECT_EQ(e.file(), "label_2/000042.txt");
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.field(), "type");
  EXPECT_THAT(e.what(), HasSubstr("'" + std::string(40, 'a') + "...'"));
  EXPECT_THAT(e.what(), HasSubstr("10000000 bytes"));
  EXPECT_LT(std::strlen(e.what()), 300u);  // not echoed in full
  // The longest accepted name, and one byte more.
  const std::string numbers = " 0.00 0 1 1 2 3 4 1.5 1.6 3.9 1 1.6 20 0.5";
  const std::string longest(kMaxObjectTypeLength, 'T');
  EXPECT_EQ(ParseObjects(longest + numbers, "x").objects.at(0).type, longest);
  EXPECT_EQ(ExpectParseError(longest + "T" + numbers).field(), "type");
}

TEST(LabelIoErrorTest, ANulOrNonAsciiByteInAClassNameIsRefusedEscaped) {
  const std::string numbers = " 0.00 0 1 1 2 3 4 1.5 1.6 3.9 1 1.6 20 0.5";
  const ParseError nul = ExpectParseError(std::string("Car\0x", 5) + numbers);
  EXPECT_EQ(nul.line(), 1);
  EXPECT_EQ(nul.field(), "type");
  EXPECT_THAT(nul.what(), HasSubstr("'Car\\x00x'"));
  EXPECT_THAT(nul.what(), HasSubstr("offset 3"));
  EXPECT_EQ(std::string(nul.what()).find('\0'), std::string::npos);
  const ParseError utf8 = ExpectParseError("Fu\xC3\x9Fg\xC3\xA4nger" + numbers);
  EXPECT_THAT(utf8.what(), HasSubstr("'Fu\\xc3\\x9fg\\xc3\\xa4nger'"));
  const ParseError bell = ExpectParseError("Car\x07" + numbers, ObjectFileKind::kAny);
  EXPECT_EQ(bell.field(), "type");
  // Lenient mode skips such a line and keeps the others.
  ObjectParseOptions lenient;
  lenient.lenient = true;
  const ObjectFile file =
      ParseObjects(std::string("Car\0", 4) + numbers + "\n" + kCyclist, "x", lenient);
  ASSERT_EQ(file.objects.size(), 1u);
  EXPECT_EQ(file.objects[0].type, "Cyclist");
  EXPECT_EQ(file.skipped_lines, 1);
  // And the writer refuses what the parser would refuse, so every file it writes reads back.
  Object object = ParseObjects(kCyclist, "x").objects.at(0);
  for (const std::string& bad : {std::string("Car\0", 4), std::string("Caf\xC3\xA9"),
                                 std::string(kMaxObjectTypeLength + 1, 'a'), std::string()}) {
    object.type = bad;
    EXPECT_THROW(FormatObject(object), std::invalid_argument);
  }
}

TEST(LabelIoErrorTest, WrongFieldCountNamesTheMissingField) {
  const ParseError e = ExpectParseError(std::string(kCyclist) + "\nCar 0.00 0 1.00 1 2 3 4\n");
  EXPECT_EQ(e.file(), "label_2/000042.txt");
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.field(), "dimensions.h");
  EXPECT_THAT(e.message(), HasSubstr("8 fields"));
  EXPECT_THAT(std::string(e.what()), HasSubstr("label_2/000042.txt:2: field dimensions.h:"));
}

TEST(LabelIoErrorTest, ScoreInALabelFileAndTooManyFields) {
  const ParseError sixteen = ExpectParseError(kDetection);
  EXPECT_EQ(sixteen.field(), "score");
  EXPECT_THAT(sixteen.message(), HasSubstr("unexpected"));
  const ParseError seventeen =
      ExpectParseError(std::string(kDetection) + " 7", ObjectFileKind::kAny);
  EXPECT_EQ(seventeen.field(), "field count");
  EXPECT_THAT(seventeen.message(), HasSubstr("17 fields"));
}

TEST(LabelIoErrorTest, TextWhereANumberBelongs) {
  struct Case {
    std::string line;
    std::string field;
  };
  const std::vector<Case> cases = {
      {"Car zero 0 1 1 2 3 4 1.5 1.6 3.9 1 1.6 20 0.5", "truncated"},
      {"Car 0 0 1 1 2 3 4 1.5 1.6 3.9 1 1.6 20 0.5x", "rotation_y"},
      {"Car 0 0 1 1 2 3 4 1.5 1.6 3.9 1,5 1.6 20 0.5", "location.x"},
      {"Car 0 0 1 1 2 3 4 1.5 1.6 3.9 1 1.6 20 0.5", ""},  // valid: control
      {"Car 0 0 1 1 top 3 4 1.5 1.6 3.9 1 1.6 20 0.5", "bbox.top"},
      {"Car 0 0 1 1 2 3 4 1.5 1.6 3.9 1 - 20 0.5", "location.y"},
      {"Car 0 0 1 1 2 3 4 1.5 1.6 3.9 1 1.6 +-20 0.5", "location.z"},
      {"Car 0 0 0x1 1 2 3 4 1.5 1.6 3.9 1 1.6 20 0.5", "alpha"},
  };
  for (const Case& c : cases) {
    if (c.field.empty()) {
      EXPECT_NO_THROW(ParseObjects(c.line, "x")) << c.line;
      continue;
    }
    const ParseError e = ExpectParseError(c.line);
    EXPECT_EQ(e.field(), c.field) << c.line;
    EXPECT_EQ(e.line(), 1);
    EXPECT_THAT(e.message(), HasSubstr("is not a number")) << c.line;
  }
}

TEST(LabelIoErrorTest, NanAndInfinityAreRejected) {
  for (const std::string bad : {"nan", "NaN", "inf", "-inf", "infinity"}) {
    const std::string line = "Car 0 0 1 1 2 3 4 " + bad + " 1.6 3.9 1 1.6 20 0.5";
    const ParseError e = ExpectParseError(line);
    EXPECT_EQ(e.field(), "dimensions.h") << bad;
    EXPECT_THAT(e.message(), HasSubstr("not a finite number")) << bad;
  }
  for (const std::string bad : {"1e999", "-1e400", "1e-400"}) {
    const ParseError e = ExpectParseError("Car 0 0 1 1 2 3 4 1.5 1.6 3.9 " + bad + " 1.6 20 0.5");
    EXPECT_EQ(e.field(), "location.x") << bad;
    EXPECT_THAT(e.message(), HasSubstr("out of the range of a double")) << bad;
  }
  // Subnormal numbers are numbers.
  EXPECT_NO_THROW(ParseObjects("Car 0 0 1 1 2 3 4 1.5 1.6 3.9 5e-324 1.6 20 1e-310", "x"));
  const ParseError score =
      ExpectParseError(std::string(kPedestrian) + " nan", ObjectFileKind::kDetection);
  EXPECT_EQ(score.field(), "score");
}

TEST(LabelIoErrorTest, NegativeDimensionsOtherThanMinusOneAreRejected) {
  const ParseError h = ExpectParseError("Car 0 0 1 1 2 3 4 -1.5 1.6 3.9 1 1.6 20 0.5");
  EXPECT_EQ(h.field(), "dimensions.h");
  const ParseError w = ExpectParseError("Car 0 0 1 1 2 3 4 1.5 -0.01 3.9 1 1.6 20 0.5");
  EXPECT_EQ(w.field(), "dimensions.w");
  const ParseError l = ExpectParseError("Car 0 0 1 1 2 3 4 1.5 1.6 -2 1 1.6 20 0.5");
  EXPECT_EQ(l.field(), "dimensions.l");
  EXPECT_THAT(l.message(), HasSubstr("negative"));
  // KITTI's -1 "not estimated" (also written -1.00) and zero are fine; negative coordinates too.
  EXPECT_NO_THROW(ParseObjects("Car 0 0 1 1 2 3 4 -1 -1.00 -1 -5 -1.6 -20 -0.5", "x"));
  EXPECT_NO_THROW(ParseObjects("Car 0 0 1 1 2 3 4 0 0 0 1 1.6 20 0.5", "x"));
}

TEST(LabelIoErrorTest, OccludedMustBeAnInteger) {
  for (const std::string bad : {"0.0", "1.5", "x", "99999999999"}) {
    const ParseError e = ExpectParseError("Car 0 " + bad + " 1 1 2 3 4 1.5 1.6 3.9 1 1.6 20 0.5");
    EXPECT_EQ(e.field(), "occluded") << bad;
    EXPECT_THAT(e.message(), HasSubstr("not an integer"));
  }
}

// The devkit reads a detection's truncation and occlusion as throw-away doubles; tools write them
// as floats ("-1.0000"). Detections accept them, labels stay strict.
TEST(LabelIoTest, DetectionLinesAcceptFloatsInEveryField) {
  const std::string line =
      "Car -1.0000 -1.0000 -1.5600 564.6200 174.5900 616.4300 224.7400 1.6100 1.6600 3.2000 "
      "-0.6900 1.6900 25.0100 -1.5900 0.9700";
  for (const ObjectFileKind kind : {ObjectFileKind::kDetection, ObjectFileKind::kAny}) {
    ObjectParseOptions options;
    options.kind = kind;
    const ObjectFile file = ParseObjects(line, "det/000000.txt", options);
    ASSERT_EQ(file.objects.size(), 1u);
    const Object& o = file.objects[0];
    EXPECT_EQ(o.truncated, -1.0);
    EXPECT_EQ(o.occluded, -1);
    EXPECT_EQ(o.box.left, 564.62);
    EXPECT_EQ(*o.score, 0.97);
  }
  ObjectParseOptions detection;
  detection.kind = ObjectFileKind::kDetection;
  auto occluded = [&](const std::string& token) {
    return ParseObjects("Car 0 " + token + " 1 1 2 3 4 1.5 1.6 3.9 1 1.6 20 0.5 0.9", "x",
                        detection)
        .objects.at(0)
        .occluded;
  };
  EXPECT_EQ(occluded("2.0"), 2);
  EXPECT_EQ(occluded("1.5"), -1);  // not integral: unknown
  EXPECT_EQ(occluded("1e30"), -1);
  // Text and non-finite numbers are still errors in a detection line.
  for (const std::string bad : {"x", "nan", "inf"}) {
    const ParseError e = ExpectParseError(
        "Car 0 " + bad + " 1 1 2 3 4 1.5 1.6 3.9 1 1.6 20 0.5 0.9", ObjectFileKind::kDetection);
    EXPECT_EQ(e.field(), "occluded") << bad;
  }
  // A label line (15 fields, also in a kAny file) keeps the integer rule.
  EXPECT_EQ(
      ExpectParseError("Car 0 -1.0000 1 1 2 3 4 1.5 1.6 3.9 1 1.6 20 0.5", ObjectFileKind::kAny)
          .field(),
      "occluded");
}

TEST(LabelIoErrorTest, ErrorMessagesQuoteBinaryGarbageSafely) {
  const std::string line =
      std::string("Car \x01\xff\x7f") + " 0 1 1 2 3 4 1.5 1.6 3.9 1 1.6 20 0.5";
  const ParseError e = ExpectParseError(line);
  EXPECT_EQ(e.field(), "truncated");
  EXPECT_THAT(e.message(), HasSubstr("'\\x01\\xff\\x7f'"));
}

TEST(LabelIoErrorTest, LenientModeSkipsAndCountsBadLines) {
  const std::string text = std::string(kPedestrian) + "\n" +        // 1 ok
                           "Car 0 0 1 1 2 3 4 nan 1 1 1 1 1 1\n" +  // 2 bad
                           "\n" +                                   // 3 blank
                           kDontCare + "\n" +                       // 4 ok
                           "Car 0 0 1\n";                           // 5 bad
  ObjectParseOptions options;
  options.lenient = true;
  const ObjectFile file = ParseObjects(text, "det/000007.txt", options);
  ASSERT_EQ(file.objects.size(), 2u);
  EXPECT_EQ(file.objects[0].type, "Pedestrian");
  EXPECT_EQ(file.objects[1].type, "DontCare");
  EXPECT_EQ(file.skipped_lines, 2);
  ASSERT_EQ(file.problems.size(), 2u);
  EXPECT_THAT(file.problems[0], HasSubstr("det/000007.txt:2: field dimensions.h:"));
  EXPECT_THAT(file.problems[1], HasSubstr("det/000007.txt:5: field bbox.left:"));
  // Strict mode stops at line 2.
  const ParseError e = ExpectParseError(text);
  EXPECT_EQ(e.line(), 2);
}

TEST(LabelIoTest, FieldNames) {
  EXPECT_STREQ(ObjectFieldName(0), "type");
  EXPECT_STREQ(ObjectFieldName(8), "dimensions.h");
  EXPECT_STREQ(ObjectFieldName(11), "location.x");
  EXPECT_STREQ(ObjectFieldName(15), "score");
  EXPECT_THROW(ObjectFieldName(16), std::invalid_argument);
}

// --- Writing. ---

Object RandomObject(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> pick(0, 5);
  auto number = [&]() {
    switch (pick(rng)) {
      case 0:
        return std::round(u(rng) * 10000.0) / 100.0;  // KITTI-style, two decimals
      case 1:
        return u(rng) * std::pow(10.0, pick(rng) * 3 - 6);  // full precision, any scale
      case 2:
        return 0.0;
      case 3:
        return -0.0;
      case 4:
        return u(rng) * 1e17;  // beyond two-decimal formatting
      default:
        return u(rng) * 100.0;
    }
  };
  auto dimension = [&]() {
    const double d = std::abs(number());
    return pick(rng) == 0 ? -1.0 : d;
  };
  static const char* kTypes[] = {"Car",        "Van",
                                 "Pedestrian", "Person_sitting",
                                 "DontCare",   "An_unknown_class_with_a_long_name"};
  Object o;
  o.type = kTypes[pick(rng)];
  o.truncated = number();
  o.occluded = std::uniform_int_distribution<int>(-1, 3)(rng);
  o.alpha = number();
  o.box = {number(), number(), number(), number()};
  o.box3d.h = dimension();
  o.box3d.w = dimension();
  o.box3d.l = dimension();
  o.box3d.location = {number(), number(), number()};
  o.box3d.rotation_y = number();
  if (pick(rng) < 3) o.score = number();
  if (pick(rng) == 0) o.SetNot3DEstimated();
  return o;
}

TEST(LabelIoTest, ParseOfFormatIsIdentityOnRandomObjects) {
  std::mt19937_64 rng(7);
  std::vector<Object> objects;
  for (int i = 0; i < 3000; ++i) objects.push_back(RandomObject(rng));
  ObjectParseOptions options;
  options.kind = ObjectFileKind::kAny;
  const ObjectFile back = ParseObjects(FormatObjects(objects), "x", options);
  ASSERT_EQ(back.objects.size(), objects.size());
  for (size_t i = 0; i < objects.size(); ++i) {
    ASSERT_EQ(back.objects[i], objects[i]) << FormatObject(objects[i]);
    // Bit-exact, sign of zero included.
    EXPECT_EQ(std::signbit(back.objects[i].alpha), std::signbit(objects[i].alpha));
  }
}

// The parser reads short decimals ("-1.57") on a fast path of its own; every number must come out
// bit for bit as std::from_chars reads it, on both sides of the fast path's 15-digit limit, with
// leading zeros, signs and negative zero.
TEST(LabelIoTest, NumbersReadExactlyAsFromChars) {
  std::mt19937_64 rng(11);
  auto digits = [&](int n) {
    std::string s;
    for (int k = 0; k < n; ++k) s.push_back(static_cast<char>('0' + rng() % 10));
    return s;
  };
  auto token = [&](bool non_negative) {
    static const char* kSigns[] = {"", "-", "+"};
    std::string t = kSigns[non_negative ? (rng() % 2) * 2 : rng() % 3];
    t += digits(1 + static_cast<int>(rng() % 10));
    if (rng() % 4 != 0) {
      t += '.';
      t += digits(1 + static_cast<int>(rng() % 10));
    }
    return t;
  };
  auto from_chars = [](std::string_view t) {
    if (t.front() == '+') t.remove_prefix(1);
    double v = 0.0;
    const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    EXPECT_TRUE(ec == std::errc() && ptr == t.data() + t.size()) << t;
    return v;
  };
  std::vector<std::string> fixed = {"0",
                                    "-0",
                                    "-0.00",
                                    "+0.0",
                                    "007.50",
                                    "-1000",
                                    "-10",
                                    "999999999999999",
                                    "0.000000000000001",
                                    "123456789012.345",
                                    "1234567890123456",
                                    "-9999999999.999999"};
  for (int line = 0; line < 20000; ++line) {
    std::vector<std::string> tokens(16);
    for (int i = 1; i < 16; ++i) tokens[i] = token(i >= 8 && i <= 10);
    tokens[0] = "Car";
    // occluded: short integers on the one-pass reader, longer ones on the general one
    static const char* kOccluded[] = {"1", "+2", "-1", "007", "0", "123456789", "1234567890"};
    static const int kOccludedValue[] = {1, 2, -1, 7, 0, 123456789, 1234567890};
    const int occluded = static_cast<int>(rng() % 7);
    tokens[2] = kOccluded[occluded];
    if (line < static_cast<int>(fixed.size())) tokens[3] = fixed[line];
    // Label lines (15 fields, as labels and as either kind) and detection lines (16).
    const bool label = line % 2 == 1;
    if (label) tokens.pop_back();
    const ObjectFileKind kind = !label          ? ObjectFileKind::kDetection
                                : line % 4 == 1 ? ObjectFileKind::kLabel
                                                : ObjectFileKind::kAny;
    std::string text;
    static const char* kBlanks[] = {" ", "  ", "\t", " \r"};
    for (const std::string& t : tokens) text += t + kBlanks[rng() % 4];
    const ObjectFile file = ParseObjects(text, "x", {kind, false});
    ASSERT_EQ(file.objects.size(), 1u) << text;
    EXPECT_EQ(file.objects[0].type, "Car");
    EXPECT_EQ(file.objects[0].occluded, kOccludedValue[occluded]) << text;
    const Object& o = file.objects[0];
    const double got[16] = {0,
                            o.truncated,
                            0,
                            o.alpha,
                            o.box.left,
                            o.box.top,
                            o.box.right,
                            o.box.bottom,
                            o.box3d.h,
                            o.box3d.w,
                            o.box3d.l,
                            o.box3d.location.x(),
                            o.box3d.location.y(),
                            o.box3d.location.z(),
                            o.box3d.rotation_y,
                            o.score.value_or(0.0)};
    EXPECT_EQ(o.score.has_value(), !label);
    for (int i = 1; i < static_cast<int>(tokens.size()); ++i) {
      if (i == 2) continue;
      const double want = from_chars(tokens[i]);
      ASSERT_EQ(std::memcmp(&got[i], &want, sizeof(double)), 0)
          << "field " << i << " '" << tokens[i] << "': " << got[i] << " vs " << want;
    }
  }
}

TEST(LabelIoTest, FormatUsesTwoDecimalsOnlyWhenExact) {
  Object o;
  o.type = "Car";
  o.truncated = 0.5;
  o.alpha = 0.123456789;
  o.box = {1.0 / 3.0, 2.0, 3.25, 4.0};
  o.box3d.h = 1.5;
  o.box3d.w = 0.001;
  o.box3d.l = 4.0;
  o.box3d.location = {-1.0, 1e20, -1000.0};
  o.box3d.rotation_y = -10.0;
  o.score = 0.25;
  EXPECT_EQ(FormatObject(o),
            "Car 0.50 0 0.123456789 0.3333333333333333 2.00 3.25 4.00 1.50 0.001 4.00 -1.00 1e+20 "
            "-1000 -10 0.25");
}

TEST(LabelIoTest, FormatRejectsWhatCouldNotBeReadBack) {
  Object o;
  o.type = "Car";
  o.box3d.h = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(FormatObject(o), std::invalid_argument);
  o.box3d.h = 1.0;
  o.score = std::numeric_limits<double>::infinity();
  EXPECT_THROW(FormatObject(o), std::invalid_argument);
  o.score.reset();
  o.type = "Two words";
  EXPECT_THROW(FormatObject(o), std::invalid_argument);
  o.type = "";
  EXPECT_THROW(FormatObject(o), std::invalid_argument);
}

TEST(LabelIoTest, WriteAndReadFiles) {
  const TestTempDir temp;
  const fs::path dir = temp.path();
  std::mt19937_64 rng(11);
  std::vector<Object> objects;
  for (int i = 0; i < 20; ++i) {
    Object o = RandomObject(rng);
    o.score.reset();
    objects.push_back(o);
  }
  const fs::path path = dir / "label_2" / "000003.txt";
  WriteObjects(path, objects);
  EXPECT_EQ(ReadObjects(path).objects, objects);
  EXPECT_THROW(ReadObjects(dir / "missing.txt"), std::runtime_error);
  // Errors from files name the path.
  { std::ofstream(dir / "bad.txt") << kPedestrian << "\nCar 0 0\n"; }
  try {
    ReadObjects(dir / "bad.txt");
    ADD_FAILURE() << "no error";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), (dir / "bad.txt").string());
    EXPECT_EQ(e.line(), 2);
    EXPECT_EQ(e.field(), "alpha");
  }
}

}  // namespace
}  // namespace stereodet
