#include "stereodet/kitti/label_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>

#include "stereodet/kitti/text_number.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/strings.h"

namespace stereodet {

namespace {

using kitti_internal::AppendRoundTrip;
using kitti_internal::NumberStatus;
using kitti_internal::QuoteToken;
using kitti_internal::ReadFiniteDouble;

constexpr int kLabelFields = 15;
constexpr int kDetectionFields = 16;

// Field names in file order, as they appear in error messages.
constexpr std::array<const char*, kDetectionFields> kFieldNames = {
    "type",       "truncated",   "occluded",     "alpha",        "bbox.left",    "bbox.top",
    "bbox.right", "bbox.bottom", "dimensions.h", "dimensions.w", "dimensions.l", "location.x",
    "location.y", "location.z",  "rotation_y",   "score"};

// KITTI's "not estimated" / DontCare value of each numeric field (index as kFieldNames), or 0 when
// the field has none. KITTI writes these as integers ("-1", "-10", "-1000"), so the writer does
// too.
constexpr std::array<double, kDetectionFields> kSentinels = {
    0, -1, 0, -10, 0, 0, 0, 0, -1, -1, -1, -1000, -1000, -1000, -10, 0};

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

// Whether `type` is a class token this parser accepts (kMaxObjectTypeLength, printable ASCII).
bool IsValidType(std::string_view type) {
  if (type.empty() || type.size() > kMaxObjectTypeLength) return false;
  for (char c : type) {
    if (c < 0x21 || c > 0x7e) return false;  // a char is signed: bytes >= 0x80 are < 0 here
  }
  return true;
}

// Why `type` is not a valid class token, for the error message; requires !IsValidType(type).
std::string TypeProblem(std::string_view type) {
  const std::string quoted = QuoteToken(type);
  if (type.size() > kMaxObjectTypeLength) {
    return quoted + " (" + std::to_string(type.size()) + " bytes) is longer than " +
           std::to_string(kMaxObjectTypeLength) + " characters: not a class name";
  }
  size_t i = 0;
  while (i < type.size() && type[i] >= 0x21 && type[i] <= 0x7e) ++i;
  return quoted + " holds a byte that is not printable ASCII (at offset " + std::to_string(i) +
         "): a class name is printable ASCII (Car, Pedestrian, DontCare, ...)";
}

// The numbers of KITTI's files are short decimals ("-1.57", "712.40", "0", "-1000"): read as
// m / 10^k with m < 10^15 and k <= 15, both exact doubles, the quotient is the decimal's correctly
// rounded value (IEEE division rounds to nearest, and m / 10^k is never halfway between two
// doubles), which is what std::from_chars returns, at a fraction of its cost. Reads
// [+-]digits[.digits] with at most 15 digits in all from *p on, and moves *p past it; returns false
// for anything else, which then takes ReadFiniteDouble (and its error messages).
// Inlined into the line parser: it reads 13 to 14 numbers a line, 600k for a KITTI-val-sized set.
[[gnu::always_inline]] inline bool ScanShortDecimal(const char** p_inout, const char* end,
                                                    double* value) {
  constexpr int kMaxDigits = 15;
  static constexpr double kPow10[kMaxDigits + 1] = {1e0, 1e1, 1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                                    1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15};
  const char* p = *p_inout;
  bool negative = false;
  if (p < end && (*p == '-' || *p == '+')) negative = *p++ == '-';
  // The digits are counted once scanned: a longer run (which wraps the unsigned mantissa) is
  // refused below, before the mantissa is used.
  uint64_t mantissa = 0;
  const char* const integer_begin = p;
  for (unsigned digit; p < end && (digit = static_cast<unsigned>(*p - '0')) < 10; ++p) {
    mantissa = mantissa * 10 + digit;
  }
  const ptrdiff_t integer_digits = p - integer_begin;
  if (integer_digits == 0) return false;
  ptrdiff_t decimals = 0;
  if (p < end && *p == '.') {
    ++p;
    const char* const decimals_begin = p;
    for (unsigned digit; p < end && (digit = static_cast<unsigned>(*p - '0')) < 10; ++p) {
      mantissa = mantissa * 10 + digit;
    }
    decimals = p - decimals_begin;
    if (decimals == 0) return false;
  }
  if (integer_digits + decimals > kMaxDigits) return false;
  const double magnitude = static_cast<double>(mantissa) / kPow10[decimals];
  *value = negative ? -magnitude : magnitude;
  *p_inout = p;
  return true;
}

// ScanShortDecimal over a whole token.
bool ReadShortDecimal(std::string_view token, double* value) {
  const char* p = token.data();
  const char* const end = p + token.size();
  return ScanShortDecimal(&p, end, value) && p == end;
}

// Splits one line (no '\n') into at most `max_tokens` tokens; returns the true token count, which
// may exceed max_tokens (the extra tokens are counted, not stored).
int Tokenize(std::string_view line, std::string_view* tokens, int max_tokens) {
  int count = 0;
  const char* p = line.data();
  const char* end = p + line.size();
  while (true) {
    while (p < end && IsBlank(*p)) ++p;
    if (p == end) return count;
    const char* start = p;
    while (p < end && !IsBlank(*p)) ++p;
    if (count < max_tokens) tokens[count] = std::string_view(start, static_cast<size_t>(p - start));
    ++count;
  }
}

// A bad line: the parser records it and moves on (lenient) or throws (strict).
struct LineError {
  int field = -1;  // index into kFieldNames, or -1 for the field count
  std::string message;
};

const char* FieldName(int field) { return field >= 0 ? kFieldNames[field] : "field count"; }

std::string ExpectedCount(ObjectFileKind kind) {
  switch (kind) {
    case ObjectFileKind::kLabel:
      return "15 (a label line)";
    case ObjectFileKind::kDetection:
      return "16 (a detection line, score last)";
    case ObjectFileKind::kAny:
      return "15 (label) or 16 (detection, score last)";
  }
  return "15";
}

// The numeric fields of a parsed line (values[1..] in KITTI's order, occluded apart) into
// `object`; the score only when the line has all 16 fields. Both parsing paths use it, so a line
// reads the same on either.
void AssignFields(const double* values, int occluded, int count, Object* object) {
  object->truncated = values[1];
  object->occluded = occluded;
  object->alpha = values[3];
  object->box = Box2D{values[4], values[5], values[6], values[7]};
  object->box3d.h = values[8];
  object->box3d.w = values[9];
  object->box3d.l = values[10];
  object->box3d.location = Eigen::Vector3d(values[11], values[12], values[13]);
  object->box3d.rotation_y = values[14];
  if (count == kDetectionFields) {
    object->score = values[15];
  } else {
    object->score.reset();
  }
}

// A line as KITTI's files write them, in one pass: the type, then 14 (label) or 15 (detection)
// numbers, short decimals (ScanShortDecimal) or else any finite number (ReadFiniteDouble), with
// occluded a short integer and dimensions >= 0 or -1. Returns false for any other line, without
// touching `error`; ParseLine then parses it (and reports what is wrong) from scratch, so a line
// reads the same on both paths.
bool ParseUsualLine(std::string_view line, ObjectFileKind kind, Object* object) {
  const char* p = line.data();
  const char* const end = p + line.size();
  auto skip_blanks = [&] {
    while (p < end && IsBlank(*p)) ++p;
  };
  auto at_token_end = [&] { return p == end || IsBlank(*p); };
  skip_blanks();
  const char* const type_begin = p;
  while (p < end && !IsBlank(*p)) ++p;
  if (p == type_begin) return false;
  const std::string_view type(type_begin, static_cast<size_t>(p - type_begin));
  if (!IsValidType(type)) return false;
  double values[kDetectionFields];
  int occluded = 0;
  int count = 1;
  for (; count < kDetectionFields; ++count) {
    skip_blanks();
    if (p == end) break;
    if (count == 2) {
      // occluded: [+-]digits, at most 9 of them (an int)
      bool negative = false;
      if (*p == '-' || *p == '+') negative = *p++ == '-';
      int digits = 0, value = 0;
      for (; p < end && *p >= '0' && *p <= '9' && digits < 9; ++p, ++digits) {
        value = value * 10 + (*p - '0');
      }
      if (digits == 0 || !at_token_end()) return false;
      occluded = negative ? -value : value;
      continue;
    }
    const char* const token_begin = p;
    if (ScanShortDecimal(&p, end, &values[count]) && at_token_end()) continue;
    // Another form (a full-precision score, an exponent): the general reader, on this token only.
    p = token_begin;
    while (p < end && !IsBlank(*p)) ++p;
    const std::string_view token(token_begin, static_cast<size_t>(p - token_begin));
    if (ReadFiniteDouble(token, &values[count]) != NumberStatus::kOk) return false;
  }
  skip_blanks();
  if (p != end) return false;  // a 17th field
  if (kind == ObjectFileKind::kLabel       ? count != kLabelFields
      : kind == ObjectFileKind::kDetection ? count != kDetectionFields
                                           : (count != kLabelFields && count != kDetectionFields)) {
    return false;
  }
  for (int i = 8; i <= 10; ++i) {
    if (values[i] < 0 && values[i] != -1.0) return false;
  }
  object->type.assign(type.data(), type.size());
  AssignFields(values, occluded, count, object);
  return true;
}

// Parses one non-blank line into `object`. Returns false and fills `error` for a bad line.
bool ParseLine(std::string_view line, ObjectFileKind kind, Object* object, LineError* error) {
  if (ParseUsualLine(line, kind, object)) return true;
  std::array<std::string_view, kDetectionFields> tokens;
  const int count = Tokenize(line, tokens.data(), kDetectionFields);
  const bool count_ok = kind == ObjectFileKind::kLabel ? count == kLabelFields
                        : kind == ObjectFileKind::kDetection
                            ? count == kDetectionFields
                            : (count == kLabelFields || count == kDetectionFields);
  if (!count_ok) {
    // Name the first missing field, or the first unexpected one, so the user sees where it went
    // wrong.
    const int wanted = kind == ObjectFileKind::kDetection ? kDetectionFields : kLabelFields;
    error->field = count < wanted ? count : (count == kDetectionFields ? kDetectionFields - 1 : -1);
    error->message = (count < wanted ? "missing: the line has " : "unexpected: the line has ") +
                     std::to_string(count) + " fields, expected " + ExpectedCount(kind);
    if (kind == ObjectFileKind::kDetection && count == kLabelFields) {
      error->message +=
          "; a label line: to evaluate labels as detections, give them a score "
          "(`eval --score 1`)";
    }
    return false;
  }

  if (!IsValidType(tokens[0])) {
    error->field = 0;
    error->message = TypeProblem(tokens[0]);
    return false;
  }
  object->type.assign(tokens[0].data(), tokens[0].size());
  double values[kDetectionFields];
  for (int i = 1; i < count; ++i) {
    if (i == 2) continue;  // occluded: an integer, read below
    if (ReadShortDecimal(tokens[i], &values[i])) continue;
    const NumberStatus status = ReadFiniteDouble(tokens[i], &values[i]);
    if (status != NumberStatus::kOk) {
      error->field = i;
      error->message = QuoteToken(tokens[i]) + " " + kitti_internal::NumberStatusMessage(status);
      return false;
    }
  }
  std::optional<int> occluded = kitti_internal::ReadInt(tokens[2]);
  if (!occluded && count == kDetectionFields && kind != ObjectFileKind::kLabel) {
    // A detection line: the devkit reads truncation and occlusion of detections as throw-away
    // doubles, and several tools write "-1.0000" there. Accept any finite number; an integral one
    // is kept, any other becomes -1 (unknown).
    double value = 0.0;
    if (ReadFiniteDouble(tokens[2], &value) == NumberStatus::kOk) {
      occluded = value == std::trunc(value) && std::abs(value) < 1e9 ? static_cast<int>(value) : -1;
    }
  }
  if (!occluded) {
    error->field = 2;
    error->message = QuoteToken(tokens[2]) + " is not an integer (0, 1, 2, 3, or -1 for DontCare)";
    return false;
  }
  for (int i = 8; i <= 10; ++i) {
    if (values[i] < 0 && values[i] != -1.0) {
      error->field = i;
      error->message = QuoteToken(tokens[i]) +
                       " is negative (dimensions are >= 0, or -1 for KITTI's \"not estimated\")";
      return false;
    }
  }
  AssignFields(values, *occluded, count, object);
  return true;
}

void AppendField(std::string* out, double value, int field) {
  STEREODET_CHECK(std::isfinite(value))
      << "cannot write a KITTI object: field " << kFieldNames[field] << " is " << value;
  out->push_back(' ');
  if (kSentinels[field] != 0 && value == kSentinels[field]) {
    out->append(std::to_string(static_cast<int>(value)));
    return;
  }
  AppendRoundTrip(out, value, std::chars_format::fixed, 2);
}

void AppendObject(std::string* out, const Object& object) {
  STEREODET_CHECK(IsValidType(object.type))
      << "cannot write a KITTI object: type " << QuoteToken(object.type)
      << " must be one word of printable ASCII, at most " << kMaxObjectTypeLength << " characters";
  out->append(object.type);
  AppendField(out, object.truncated, 1);
  out->push_back(' ');
  out->append(std::to_string(object.occluded));
  AppendField(out, object.alpha, 3);
  AppendField(out, object.box.left, 4);
  AppendField(out, object.box.top, 5);
  AppendField(out, object.box.right, 6);
  AppendField(out, object.box.bottom, 7);
  AppendField(out, object.box3d.h, 8);
  AppendField(out, object.box3d.w, 9);
  AppendField(out, object.box3d.l, 10);
  AppendField(out, object.box3d.location.x(), 11);
  AppendField(out, object.box3d.location.y(), 12);
  AppendField(out, object.box3d.location.z(), 13);
  AppendField(out, object.box3d.rotation_y, 14);
  if (object.score) AppendField(out, *object.score, 15);
}

}  // namespace

const char* ObjectFieldName(int index) {
  STEREODET_CHECK(index >= 0 && index < kDetectionFields) << "no KITTI object field " << index;
  return kFieldNames[index];
}

ObjectFile ParseObjects(std::string_view text, const std::string& source,
                        const ObjectParseOptions& options) {
  // A UTF-8 byte-order mark (Windows editors write one) is no part of the first line's type.
  text = StripUtf8Bom(text);
  ObjectFile file;
  // One object per line at most: counting the newlines reserves about the right size, where a
  // guess from the byte count left a third of every frame's objects unused. Counted by memchr (a
  // vectorized scan; std::count went byte by byte, 2 instructions a byte).
  size_t lines = 1;
  for (const char *p = text.data(), *const end = p + text.size();
       p < end && (p = static_cast<const char*>(
                       std::memchr(p, '\n', static_cast<size_t>(end - p)))) != nullptr;
       ++p) {
    ++lines;
  }
  file.objects.reserve(lines);
  LineError error;
  int line_number = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    ++line_number;
    const std::string_view line = kitti_internal::NextLine(text, &pos);

    size_t first = 0;
    while (first < line.size() && IsBlank(line[first])) ++first;
    if (first == line.size()) continue;  // blank line

    // Parse in place: no copy of the object (its type string) per line.
    if (ParseLine(line, options.kind, &file.objects.emplace_back(), &error)) continue;
    file.objects.pop_back();
    ParseError parse_error(source, line_number, FieldName(error.field), error.message);
    if (!options.lenient) throw parse_error;
    ++file.skipped_lines;
    file.problems.emplace_back(parse_error.what());
  }
  return file;
}

ObjectFile ReadObjects(const std::filesystem::path& path, const ObjectParseOptions& options) {
  return ParseObjects(ReadFile(path), path.string(), options);
}

std::string FormatObject(const Object& object) {
  std::string line;
  line.reserve(128);
  AppendObject(&line, object);
  return line;
}

std::string FormatObjects(const std::vector<Object>& objects) {
  std::string text;
  text.reserve(objects.size() * 100);
  for (const Object& object : objects) {
    AppendObject(&text, object);
    text.push_back('\n');
  }
  return text;
}

void WriteObjects(const std::filesystem::path& path, const std::vector<Object>& objects) {
  WriteFileAtomically(path, FormatObjects(objects));
}

}  // namespace stereodet
