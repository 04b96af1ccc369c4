#include "stereodet/eval/coco.h"

#include <fmt/format.h>
#include <simdjson.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>
#include <unordered_map>
#include <utility>

#include "stereodet/eval/coco_internal.h"
#include "stereodet/eval/score_metrics_internal.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/malloc_tuning.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/timer.h"

namespace stereodet {

namespace {

using json = nlohmann::json;

// ---------------------------------------------------------------------------------------------
// Reading: one pass of nlohmann's SAX parser, no document tree (a tree of the 500,000 detections
// of a COCO-sized results file costs four times the parse and ten times the memory).

// The 1-based line of byte offset `byte` in `text` (nlohmann reports syntax errors by byte).
int LineOfByte(std::string_view text, size_t byte) {
  byte = std::min(byte, text.size());
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + byte, '\n'));
}

// The arrays of records a COCO file holds: the ground truth's three, or a results file itself.
enum class Section { kImages, kCategories, kAnnotations, kResults };

const char* SectionName(Section section) {
  switch (section) {
    case Section::kImages:
      return "images";
    case Section::kCategories:
      return "categories";
    case Section::kAnnotations:
      return "annotations";
    case Section::kResults:
      return "";
  }
  return "";
}

// The fields read from a record; other keys are skipped whatever they hold.
enum Slot { kId, kImageId, kCategoryId, kBbox, kArea, kScore, kIscrowd, kIgnore, kName, kNumSlots };
constexpr const char* kSlotNames[kNumSlots] = {"id",    "image_id", "category_id", "bbox", "area",
                                               "score", "iscrowd",  "ignore",      "name"};

int SlotOfKey(std::string_view key) {
  for (int s = 0; s < kNumSlots; ++s) {
    if (key == kSlotNames[s]) return s;
  }
  return -1;
}

// One field's JSON value, as far as the readers look at it.
struct RawValue {
  enum class Kind { kAbsent, kNull, kBool, kInteger, kUnsigned, kFloat, kString, kArray, kObject };
  Kind kind = Kind::kAbsent;
  bool boolean = false;
  int64_t integer = 0;          // kInteger
  uint64_t unsigned_value = 0;  // kUnsigned (a non-negative integer)
  double number = 0;            // any number, as a double
  std::string text;             // kString
  // kArray: its first 4 number elements, its size, and whether every element is a number.
  std::array<double, 4> numbers{};
  size_t size = 0;
  bool all_numbers = true;

  void SetNumber(Kind number_kind, double value) {
    kind = number_kind;
    number = value;
  }
};

// The value as a message quotes it: `"x"`, `[0,0,1]`, `an object`.
std::string Excerpt(const RawValue& v) {
  using Kind = RawValue::Kind;
  std::string text;
  switch (v.kind) {
    case Kind::kAbsent:
      return "nothing";
    case Kind::kNull:
      return "null";
    case Kind::kBool:
      return v.boolean ? "true" : "false";
    case Kind::kInteger:
      return fmt::format("{}", v.integer);
    case Kind::kUnsigned:
      return fmt::format("{}", v.unsigned_value);
    case Kind::kFloat:
      return fmt::format("{}", v.number);
    case Kind::kString:
      text = json(v.text).dump();
      break;
    case Kind::kArray:
      if (!v.all_numbers) return fmt::format("an array of {} elements, not all numbers", v.size);
      text = fmt::format(
          "[{}{}]",
          fmt::join(v.numbers.begin(), v.numbers.begin() + std::min<size_t>(v.size, 4), ","),
          v.size > 4 ? ",..." : "");
      break;
    case Kind::kObject:
      return "an object";
  }
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return text;
}

// The SAX handler: collects each record's fields, turns the record into an image id, a category,
// an annotation or a detection when it ends, and names the field of any error
// ("annotations[12].bbox").
class CocoReader {
 public:
  // Reads a ground truth into `gt`.
  CocoReader(std::string_view text, const std::string& source, CocoGroundTruth* gt)
      : text_(text), source_(source), gt_(gt) {
    // At least about 80 bytes an annotation: room for all without the growth's copies.
    ReserveOnHugePages(gt->annotations, text.size() / 80);
  }
  // Reads a results file into `dets`, checking its image ids against `images_of` (sorted).
  CocoReader(std::string_view text, const std::string& source, const CocoGroundTruth& images_of,
             std::vector<CocoDetection>* dets)
      : text_(text), source_(source), images_of_(&images_of), dets_(dets) {}

  void Read() {
    json::sax_parse(text_.begin(), text_.end(), this);
    if (gt_ != nullptr) {
      for (const Section s : {Section::kImages, Section::kCategories}) {
        if (!seen_[static_cast<int>(s)]) Fail(SectionName(s), "missing");
      }
    }
  }

  // nlohmann's SAX interface.
  bool null() {
    return Scalar([](RawValue& v) { v.kind = RawValue::Kind::kNull; });
  }
  bool boolean(bool value) {
    return Scalar([&](RawValue& v) {
      v.kind = RawValue::Kind::kBool;
      v.boolean = value;
    });
  }
  bool number_integer(int64_t value) {
    return Scalar([&](RawValue& v) {
      v.SetNumber(RawValue::Kind::kInteger, static_cast<double>(value));
      v.integer = value;
    });
  }
  bool number_unsigned(uint64_t value) {
    return Scalar([&](RawValue& v) {
      v.SetNumber(RawValue::Kind::kUnsigned, static_cast<double>(value));
      v.unsigned_value = value;
    });
  }
  bool number_float(double value, const std::string& /*token*/) {
    return Scalar([&](RawValue& v) { v.SetNumber(RawValue::Kind::kFloat, value); });
  }
  bool string(std::string& value) {
    return Scalar([&](RawValue& v) {
      v.kind = RawValue::Kind::kString;
      v.text.swap(value);
    });
  }
  bool binary(json::binary_t& /*value*/) {
    return Scalar([](RawValue& v) { v.kind = {}; });
  }
  bool start_object(size_t /*size*/) { return Open(/*object=*/true); }
  bool start_array(size_t /*size*/) { return Open(/*object=*/false); }
  bool end_object() { return Close(); }
  bool end_array() { return Close(); }
  bool key(std::string& name) {
    switch (frames_.back()) {
      case Frame::kTop:
        top_key_ = name;
        break;
      case Frame::kRecord:
        slot_ = SlotOfKey(name);  // a repeated key: its last value overwrites the first
        break;
      default:
        break;
    }
    return true;
  }
  bool parse_error(size_t position, const std::string& /*last_token*/,
                   const nlohmann::detail::exception& e) {
    throw ParseError(source_, LineOfByte(text_, position), "",
                     std::string("not valid JSON: ") + e.what());
  }

 private:
  // What an open array or object is.
  enum class Frame {
    kTop,         // the ground truth's object
    kSection,     // an array of records
    kRecord,      // one record's object
    kFieldArray,  // the array value of a record's field (a bbox)
    kSkip,        // anything else: read past
  };

  [[noreturn]] void Fail(const std::string& field, const std::string& message) const {
    throw ParseError(source_, 0, field, message);
  }
  std::string Element() const { return fmt::format("{}[{}]", SectionName(section_), index_); }
  std::string Field(int slot) const { return FieldOf(Element(), slot); }
  static std::string FieldOf(const std::string& element, int slot) {
    return element.empty() ? kSlotNames[slot] : element + "." + kSlotNames[slot];
  }

  // A scalar value: stored where it belongs, an error where a container was due.
  template <typename SetFn>
  bool Scalar(SetFn set) {
    if (frames_.empty()) RootIsNot();
    switch (frames_.back()) {
      case Frame::kTop: {
        RawValue v;
        set(v);
        if (IsSection(top_key_)) Fail(top_key_, "expected an array, got " + Excerpt(v));
        break;
      }
      case Frame::kSection: {
        RawValue v;
        set(v);
        Fail(Element(), "expected an object, got " + Excerpt(v));
      }
      case Frame::kRecord:
        if (slot_ >= 0) set(record_[slot_]);
        break;
      case Frame::kFieldArray: {
        RawValue v;
        set(v);
        RawValue& array = record_[slot_];
        const bool number = v.kind == RawValue::Kind::kInteger ||
                            v.kind == RawValue::Kind::kUnsigned || v.kind == RawValue::Kind::kFloat;
        if (number && array.size < 4) array.numbers[array.size] = v.number;
        array.all_numbers = array.all_numbers && number;
        ++array.size;
        break;
      }
      case Frame::kSkip:
        break;
    }
    return true;
  }

  bool IsSection(const std::string& key) const {
    return key == "images" || key == "categories" || key == "annotations";
  }

  [[noreturn]] void RootIsNot() const {
    Fail("", gt_ != nullptr ? "a COCO ground-truth file is a JSON object"
                            : "a COCO results file is a JSON array of {image_id, category_id, "
                              "bbox, score}");
  }

  bool Open(bool object) {
    if (frames_.empty()) {
      if (object != (gt_ != nullptr)) RootIsNot();
      if (object) {
        frames_.push_back(Frame::kTop);
      } else {
        section_ = Section::kResults;
        index_ = 0;
        frames_.push_back(Frame::kSection);
      }
      return true;
    }
    switch (frames_.back()) {
      case Frame::kTop:
        if (!IsSection(top_key_)) {
          frames_.push_back(Frame::kSkip);
        } else if (object) {
          Fail(top_key_, "expected an array, got an object");
        } else {
          section_ = top_key_ == "images"       ? Section::kImages
                     : top_key_ == "categories" ? Section::kCategories
                                                : Section::kAnnotations;
          index_ = 0;
          seen_[static_cast<int>(section_)] = true;
          frames_.push_back(Frame::kSection);
        }
        break;
      case Frame::kSection:
        if (!object) Fail(Element(), "expected an object, got an array");
        for (RawValue& v : record_) v.kind = RawValue::Kind::kAbsent;
        slot_ = -1;
        frames_.push_back(Frame::kRecord);
        break;
      case Frame::kRecord:
        if (slot_ < 0) {
          frames_.push_back(Frame::kSkip);
        } else if (object) {
          record_[slot_].kind = RawValue::Kind::kObject;
          frames_.push_back(Frame::kSkip);
        } else {
          RawValue& array = record_[slot_];
          array.kind = RawValue::Kind::kArray;
          array.size = 0;
          array.all_numbers = true;
          frames_.push_back(Frame::kFieldArray);
        }
        break;
      case Frame::kFieldArray:
        record_[slot_].all_numbers = false;
        ++record_[slot_].size;
        frames_.push_back(Frame::kSkip);
        break;
      case Frame::kSkip:
        frames_.push_back(Frame::kSkip);
        break;
    }
    return true;
  }

  bool Close() {
    const Frame closed = frames_.back();
    frames_.pop_back();
    if (closed == Frame::kRecord) {
      EndRecord();
      ++index_;
    }
    return true;
  }

  // The typed value of a record's field; absent ones fail unless optional.
  const RawValue& Required(int slot) const {
    if (record_[slot].kind == RawValue::Kind::kAbsent) Fail(Field(slot), "missing");
    return record_[slot];
  }
  int64_t Integer(int slot) const {
    const RawValue& v = Required(slot);
    if (v.kind == RawValue::Kind::kInteger) return v.integer;
    if (v.kind == RawValue::Kind::kUnsigned &&
        v.unsigned_value <= static_cast<uint64_t>(std::numeric_limits<int64_t>::max())) {
      return static_cast<int64_t>(v.unsigned_value);
    }
    Fail(Field(slot), "expected an integer id, got " + Excerpt(v));
  }
  double Number(int slot) const {
    const RawValue& v = Required(slot);
    if (v.kind != RawValue::Kind::kInteger && v.kind != RawValue::Kind::kUnsigned &&
        v.kind != RawValue::Kind::kFloat) {
      Fail(Field(slot), "expected a number, got " + Excerpt(v));
    }
    return v.number;
  }
  // An optional 0/1 flag ("iscrowd", "ignore"): an integer or a boolean, nonzero is set.
  bool Flag(int slot) const {
    const RawValue& v = record_[slot];
    switch (v.kind) {
      case RawValue::Kind::kAbsent:
        return false;
      case RawValue::Kind::kBool:
        return v.boolean;
      case RawValue::Kind::kInteger:
        return v.integer != 0;
      case RawValue::Kind::kUnsigned:
        return v.unsigned_value != 0;
      default:
        Fail(Field(slot), "expected an integer or a boolean, got " + Excerpt(v));
    }
  }
  CocoBox Box() const {
    const RawValue& v = Required(kBbox);
    if (v.kind != RawValue::Kind::kArray || v.size != 4 || !v.all_numbers) {
      Fail(Field(kBbox), "expected 4 numbers [x, y, width, height], got " + Excerpt(v));
    }
    return {v.numbers[0], v.numbers[1], v.numbers[2], v.numbers[3]};
  }

  void EndRecord() {
    switch (section_) {
      case Section::kImages:
        gt_->image_ids.push_back(Integer(kId));
        break;
      case Section::kCategories: {
        CocoCategory category;
        category.id = Integer(kId);
        const RawValue& name = record_[kName];
        if (name.kind != RawValue::Kind::kAbsent) {
          if (name.kind != RawValue::Kind::kString) {
            Fail(Field(kName), "expected a string, got " + Excerpt(name));
          }
          category.name = name.text;
        }
        gt_->categories.push_back(std::move(category));
        break;
      }
      case Section::kAnnotations: {
        CocoAnnotation a;
        a.id = Integer(kId);
        a.image_id = Integer(kImageId);
        a.category_id = Integer(kCategoryId);
        a.bbox = Box();
        a.area = Number(kArea);
        a.iscrowd = Flag(kIscrowd);
        a.ignore = Flag(kIgnore);
        const auto [it, inserted] = first_of_id_.emplace(a.id, index_);
        if (!inserted) {
          Fail(Field(kId), fmt::format("id {} is also annotations[{}]'s: annotation ids must be "
                                       "unique",
                                       a.id, it->second));
        }
        gt_->annotations.push_back(a);
        break;
      }
      case Section::kResults: {
        CocoDetection d;
        d.image_id = Integer(kImageId);
        d.category_id = Integer(kCategoryId);
        d.bbox = Box();
        d.score = Number(kScore);
        if (!std::binary_search(images_of_->image_ids.begin(), images_of_->image_ids.end(),
                                d.image_id)) {
          Fail(Field(kImageId),
               fmt::format("image {} is not in the ground truth {} (its \"images\"): the results "
                           "do not belong to this data set",
                           d.image_id, images_of_->source));
        }
        dets_->push_back(d);
        break;
      }
    }
  }

  std::string_view text_;
  const std::string& source_;
  CocoGroundTruth* gt_ = nullptr;
  const CocoGroundTruth* images_of_ = nullptr;
  std::vector<CocoDetection>* dets_ = nullptr;

  std::vector<Frame> frames_;
  std::string top_key_;  // the ground truth's key being read
  Section section_ = Section::kResults;
  size_t index_ = 0;  // of the record in its section
  std::array<bool, 4> seen_{};
  std::array<RawValue, kNumSlots> record_;
  int slot_ = -1;  // the record's field being read; -1: a key that is not read
  std::unordered_map<int64_t, size_t> first_of_id_;  // annotation id -> its first index
};

}  // namespace

CocoGroundTruth ParseCocoGroundTruth(std::string_view text, const std::string& source) {
  CocoGroundTruth gt;
  gt.source = source;
  CocoReader(text, source, &gt).Read();
  // pycocotools keys images and categories by id: a repeated one is the same image, and the last
  // category of an id is the one (COCO.createIndex).
  std::sort(gt.image_ids.begin(), gt.image_ids.end());
  gt.image_ids.erase(std::unique(gt.image_ids.begin(), gt.image_ids.end()), gt.image_ids.end());
  std::stable_sort(gt.categories.begin(), gt.categories.end(),
                   [](const CocoCategory& a, const CocoCategory& b) { return a.id < b.id; });
  std::vector<CocoCategory> unique;
  for (CocoCategory& c : gt.categories) {
    if (!unique.empty() && unique.back().id == c.id) {
      unique.back() = std::move(c);
    } else {
      unique.push_back(std::move(c));
    }
  }
  gt.categories = std::move(unique);
  return gt;
}

CocoGroundTruth ReadCocoGroundTruth(const std::filesystem::path& path) {
  return ParseCocoGroundTruth(ReadFile(path, kMaxReadFileBytes, "COCO ground truth"),
                              path.string());
}

namespace {

// simdjson's On-Demand parse of a results file, for the files nothing is wrong with: an array of
// objects, each with an integer image_id (one of gt's images) and category_id, a bbox of 4 numbers
// and a finite score, none of these given twice, and other keys holding a number, a string, a
// boolean or null. Returns false, with *dets in any state, for anything else (malformed JSON,
// other keys holding an array or an object, which On-Demand would skip without checking them):
// then CocoReader reads the file again and names what is wrong, or accepts what this path does
// not. Every value this path accepts it has parsed, so it accepts only valid JSON, and the values
// are CocoReader's (numbers are correctly rounded doubles in both, ids int64).
//
// On-Demand and not the DOM parser: on a COCO-sized file both spent most of their time touching
// fresh memory (the DOM's tape too), and On-Demand touches the least (docs/BENCHMARKS.md).
// `view` is the array's text with simdjson's padding after it; the detections are appended.
bool FastParseCocoArray(simdjson::ondemand::parser& parser, simdjson::padded_string_view view,
                        const CocoGroundTruth& gt, std::vector<CocoDetection>* dets) {
  namespace od = simdjson::ondemand;
  od::document doc;
  if (parser.iterate(view).get(doc)) return false;
  od::array array;
  if (doc.get_array().get(array)) return false;
  for (auto element : array) {
    od::object object;
    if (element.get_object().get(object)) return false;
    CocoDetection d;
    int seen = 0;  // bits: image_id, category_id, bbox, score
    for (auto field : object) {
      std::string_view key;
      if (field.unescaped_key().get(key)) return false;
      od::value value;
      if (field.value().get(value)) return false;
      int bit = 0;
      if (key == "image_id") {
        bit = 1;
        if (value.get_int64().get(d.image_id)) return false;
      } else if (key == "category_id") {
        bit = 2;
        if (value.get_int64().get(d.category_id)) return false;
      } else if (key == "bbox") {
        bit = 4;
        od::array box;
        if (value.get_array().get(box)) return false;
        std::array<double, 4> v{};
        size_t n = 0;
        for (auto number : box) {
          double x = 0;
          if (n >= 4 || number.get_double().get(x)) return false;
          v[n++] = x;
        }
        if (n != 4) return false;
        d.bbox = {v[0], v[1], v[2], v[3]};
      } else if (key == "score") {
        bit = 8;
        if (value.get_double().get(d.score) || !std::isfinite(d.score)) return false;
      } else {
        // Another key: parsed all the same, so that nothing unchecked is accepted.
        od::json_type type;
        if (value.type().get(type)) return false;
        double number = 0;
        std::string_view string;
        bool boolean = false;
        bool null = false;
        switch (type) {
          case od::json_type::number:
            if (value.get_double().get(number)) return false;
            break;
          case od::json_type::string:
            if (value.get_string().get(string)) return false;
            break;
          case od::json_type::boolean:
            if (value.get_bool().get(boolean)) return false;
            break;
          case od::json_type::null:
            if (value.is_null().get(null) || !null) return false;
            break;
          default:
            return false;  // an array or an object
        }
        continue;
      }
      if (seen & bit) return false;  // given twice: CocoReader's rule decides
      seen |= bit;
    }
    if (seen != 15) return false;
    if (!std::binary_search(gt.image_ids.begin(), gt.image_ids.end(), d.image_id)) return false;
    dets->push_back(d);
  }
  // Nothing after the array.
  const char* rest = nullptr;
  return doc.current_location().get(rest) == simdjson::OUT_OF_BOUNDS;
}

constexpr bool IsJsonWhitespace(char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; }

}  // namespace

size_t CocoArrayScanner::Scan(const char* text, size_t from, size_t to, size_t* last_cut) {
  for (size_t i = from; i < to; ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
      continue;
    }
    switch (c) {
      case '"':
        in_string = true;
        break;
      case '[':
      case '{':
        ++depth;
        break;
      case ']':
      case '}':
        if (--depth == 0) return i;
        break;
      case ',':
        if (depth == 1) *last_cut = i;
        break;
      default:
        break;
    }
  }
  return kNoClose;
}

namespace {

// The offset of the last comma in text[begin, end) that follows a '}' (whitespace between), or 0.
size_t LastCommaAfterBrace(std::string_view text, size_t begin, size_t end) {
  size_t comma = end;
  while (comma > begin) {
    comma = text.rfind(',', comma - 1);
    if (comma == std::string_view::npos || comma < begin) return 0;
    size_t before = comma;
    while (before > begin && IsJsonWhitespace(text[before - 1])) --before;
    if (before > begin && text[before - 1] == '}') return comma;
  }
  return 0;
}

// The buffer holds '[' then the text not parsed yet. After each read, everything before the last
// comma between two elements of the top array is parsed as one array (the comma overwritten by
// ']') and the rest moved to the front; at the end of the file, the rest with its ']'. That comma
// is guessed first, as the last one after a '}' (the elements are objects; the guess is wrong only
// where a string holds "},"), and found by CocoArrayScanner where the guessed piece does not parse.
// Splitting the array so is sound whatever the guess or the scanner decide: every piece is checked
// by simdjson as an array of at least one element (an empty piece means ",," or a comma next to a
// bracket: refused), and arrays of elements joined by commas are the array of all of them; a wrong
// split can only refuse a file, never accept a wrong one. An element longer than the block doubles
// the buffer.
bool StreamCocoDetections(RegularFileReader& reader, const CocoGroundTruth& gt, size_t block_bytes,
                          std::vector<CocoDetection>* dets, uint64_t* fnv1a64) {
  constexpr size_t kPadding = simdjson::SIMDJSON_PADDING;
  std::string buffer(1 + std::max<size_t>(block_bytes, 1) + kPadding, ' ');
  buffer[0] = '[';
  size_t end = 1;       // buffer[0, end): '[' and the text not parsed yet
  bool opened = false;  // the file's '[' read
  size_t pieces = 0;    // parsed
  simdjson::ondemand::parser parser;
  // Parses buffer[0, length), "[...]"; false, with *dets as it was, if it is not an array of
  // valid detections or, unless `may_be_empty`, holds none.
  auto parse = [&](size_t length, bool may_be_empty) {
    const size_t before = dets->size();
    const simdjson::padded_string_view view(buffer.data(), length, buffer.size());
    if (!FastParseCocoArray(parser, view, gt, dets) || (!may_be_empty && dets->size() == before)) {
      dets->resize(before);
      return false;
    }
    ++pieces;
    return true;
  };
  // Parses the elements before the comma at `cut` and keeps the text after it; false (the buffer
  // as it was) if they are not an array of detections.
  auto parse_before = [&](size_t cut) {
    buffer[cut] = ']';
    if (!parse(cut + 1, /*may_be_empty=*/false)) {
      buffer[cut] = ',';
      return false;
    }
    const size_t rest = end - cut - 1;
    std::memmove(buffer.data() + 1, buffer.data() + cut + 1, rest);
    end = 1 + rest;
    return true;
  };
  while (true) {
    if (end + kPadding == buffer.size()) buffer.resize(2 * buffer.size(), ' ');
    const size_t got = reader.Read(buffer.data() + end, buffer.size() - kPadding - end);
    if (got == 0) break;
    if (fnv1a64 != nullptr) {
      *fnv1a64 = Fnv1a64(std::string_view(buffer.data() + end, got), *fnv1a64);
    }
    size_t from = end;
    end += got;
    if (!opened) {
      while (from < end && IsJsonWhitespace(buffer[from])) ++from;
      if (from == end) {
        end = 1;
        continue;
      }
      if (buffer[from] != '[') return false;
      opened = true;
      std::memmove(buffer.data() + 1, buffer.data() + from + 1, end - from - 1);
      end -= from;
    }
    const size_t guess = LastCommaAfterBrace(std::string_view(buffer.data(), end), 1, end);
    if (guess > 0 && parse_before(guess)) continue;
    // No guess, or a wrong one, or a malformed file: the scanner decides (a comma after the top
    // array's end is never one between its elements: it stops there).
    CocoArrayScanner scanner;
    size_t cut = 0;
    scanner.Scan(buffer.data(), 1, end, &cut);
    if (cut > 0 && !parse_before(cut)) return false;
  }
  if (!opened) return false;
  // The last piece: the rest up to the file's ']', whitespace after it. "[]" is the one array
  // that may be empty; a last piece without elements after others was "...,]".
  size_t last = end;
  while (last > 1 && IsJsonWhitespace(buffer[last - 1])) --last;
  if (last <= 1 || buffer[last - 1] != ']') return false;
  return parse(last, /*may_be_empty=*/pieces == 0);
}

}  // namespace

std::vector<CocoDetection> ReadCocoDetectionsInBlocks(const std::filesystem::path& path,
                                                      const CocoGroundTruth& gt, size_t block_bytes,
                                                      uint64_t* fnv1a64, bool* streamed) {
  std::vector<CocoDetection> dets;
  const uint64_t seed = fnv1a64 != nullptr ? *fnv1a64 : 0;
  {
    RegularFileReader reader(path, "COCO results");
    // About 90 bytes a detection as json.dump and detectron2 write them (a denser file grows the
    // vector once or twice); not the densest possible 56, which would reserve far more memory
    // than is filled.
    ReserveOnHugePages(dets, static_cast<size_t>(reader.size() / 90) + 1);
    if (StreamCocoDetections(reader, gt, block_bytes, &dets, fnv1a64)) {
      if (streamed != nullptr) *streamed = true;
      return dets;
    }
  }
  // Refused: read whole by the reader that names what is wrong (or accepts what the fast path
  // does not, such as a detection with a nested field).
  if (streamed != nullptr) *streamed = false;
  const std::string text = ReadFile(path, kMaxReadFileBytes, "COCO results");
  if (fnv1a64 != nullptr) *fnv1a64 = Fnv1a64(text, seed);
  return ParseCocoDetectionsNamingErrors(text, path.string(), gt);
}

// The fast path where it reads the text, CocoReader where it does not.
std::vector<CocoDetection> ParseCocoDetections(std::string_view text, const std::string& source,
                                               const CocoGroundTruth& gt) {
  std::vector<CocoDetection> dets;
  // About 90 bytes a detection ({"image_id": 1, "category_id": 1, "bbox": [...], "score": ...}).
  dets.reserve(text.size() / 90);
  const simdjson::padded_string copy(text);
  simdjson::ondemand::parser parser;
  if (FastParseCocoArray(parser, copy, gt, &dets)) return dets;
  return ParseCocoDetectionsNamingErrors(text, source, gt);
}

std::vector<CocoDetection> ParseCocoDetectionsNamingErrors(std::string_view text,
                                                           const std::string& source,
                                                           const CocoGroundTruth& gt) {
  std::vector<CocoDetection> dets;
  dets.reserve(text.size() / 90);
  CocoReader(text, source, gt, &dets).Read();
  return dets;
}

std::vector<CocoDetection> ReadCocoDetections(const std::filesystem::path& path,
                                              const CocoGroundTruth& gt, uint64_t* fnv1a64) {
  return ReadCocoDetectionsInBlocks(path, gt, kCocoReadBlockBytes, fnv1a64, nullptr);
}

// -----------------------------------------------------------------------------------------------
// Options.

const char* CocoMatcherName(CocoMatcher matcher) {
  return matcher == CocoMatcher::kOptimal ? "optimal" : "coco";
}

std::optional<CocoMatcher> ParseCocoMatcher(std::string_view text) {
  if (text == "coco" || text == "greedy") return CocoMatcher::kCoco;
  if (text == "optimal") return CocoMatcher::kOptimal;
  return std::nullopt;
}

std::vector<double> CocoIouThresholds() {
  // numpy's linspace: start + i * step, with the end point set exactly.
  constexpr int kNum = 10;
  const double step = (0.95 - 0.5) / (kNum - 1);
  std::vector<double> thresholds(kNum);
  for (int i = 0; i < kNum; ++i) thresholds[i] = i * step + 0.5;
  thresholds.back() = 0.95;
  return thresholds;
}

std::vector<double> CocoRecallThresholds() {
  constexpr int kNum = 101;
  const double step = (1.0 - 0.0) / (kNum - 1);
  std::vector<double> thresholds(kNum);
  for (int i = 0; i < kNum; ++i) thresholds[i] = i * step + 0.0;
  thresholds.back() = 1.0;
  return thresholds;
}

std::vector<CocoAreaRange> CocoAreaRanges() {
  return {{"all", 0, 1e5 * 1e5},
          {"small", 0, 32 * 32},
          {"medium", 32 * 32, 96 * 96},
          {"large", 96 * 96, 1e5 * 1e5}};
}

void CocoEvalOptions::Check() const {
  STEREODET_CHECK(!iou_thresholds.empty()) << "COCO evaluation: no IoU threshold";
  for (const double t : iou_thresholds) {
    STEREODET_CHECK(t >= 0 && t <= 1)
        << "COCO evaluation: IoU threshold " << t << " outside [0, 1]";
  }
  STEREODET_CHECK(!recall_thresholds.empty()) << "COCO evaluation: no recall threshold";
  for (size_t r = 0; r < recall_thresholds.size(); ++r) {
    STEREODET_CHECK(recall_thresholds[r] >= 0 && recall_thresholds[r] <= 1)
        << "COCO evaluation: recall threshold " << recall_thresholds[r] << " outside [0, 1]";
    STEREODET_CHECK(r == 0 || recall_thresholds[r] >= recall_thresholds[r - 1])
        << "COCO evaluation: recall thresholds must not decrease (" << recall_thresholds[r - 1]
        << " then " << recall_thresholds[r] << ")";
  }
  STEREODET_CHECK_EQ(max_dets.size(), 3u) << "(COCO evaluation's max_dets: the summary's three)";
  for (size_t m = 0; m < max_dets.size(); ++m) {
    STEREODET_CHECK(max_dets[m] >= 1 && (m == 0 || max_dets[m] > max_dets[m - 1]))
        << "COCO evaluation: max_dets must be >= 1 and strictly increasing, got "
        << fmt::format("{}", fmt::join(max_dets, ", "));
  }
  STEREODET_CHECK(!area_ranges.empty()) << "COCO evaluation: no area range";
  for (size_t a = 0; a < area_ranges.size(); ++a) {
    const CocoAreaRange& range = area_ranges[a];
    STEREODET_CHECK(!range.label.empty()) << "COCO evaluation: area range " << a << " has no label";
    STEREODET_CHECK(range.min_area <= range.max_area)
        << "COCO evaluation: area range '" << range.label << "' is [" << range.min_area << ", "
        << range.max_area << "]";
    for (size_t b = 0; b < a; ++b) {
      STEREODET_CHECK(area_ranges[b].label != range.label)
          << "COCO evaluation: area range label '" << range.label << "' given twice";
    }
  }
  if (stable_area_ranges) {
    STEREODET_CHECK(matcher == CocoMatcher::kCoco)
        << "COCO evaluation: stable area ranges are counted from the greedy matching of range "
           "\"all\"; with the optimal matcher they are not there yet";
    STEREODET_CHECK(std::any_of(area_ranges.begin(), area_ranges.end(), [](const CocoAreaRange& r) {
      return r.label == "all";
    })) << "COCO evaluation: stable area ranges need an area range labelled \"all\"";
  }
  STEREODET_CHECK_GE(calibration_bins, 1) << "(COCO evaluation's calibration_bins)";
  STEREODET_CHECK(!std::isnan(score_threshold)) << "COCO evaluation: score_threshold is NaN";
  STEREODET_CHECK_GE(num_threads, 0) << "(COCO evaluation's num_threads)";
}

size_t CocoEvalResult::PrecisionIndex(int t, int r, int k, int a, int m) const {
  const size_t R = options.recall_thresholds.size(), K = category_ids.size(),
               A = options.area_ranges.size(), M = options.max_dets.size();
  return (((t * R + r) * K + k) * A + a) * M + m;
}

size_t CocoEvalResult::RecallIndex(int t, int k, int a, int m) const {
  const size_t K = category_ids.size(), A = options.area_ranges.size(), M = options.max_dets.size();
  return ((t * K + k) * A + a) * M + m;
}

size_t CocoEvalResult::CellIndex(int t, int k, int a) const {
  const size_t K = category_ids.size(), A = options.area_ranges.size();
  return (t * K + k) * A + a;
}

std::string FormatCocoCategories(const CocoEvalResult& result) {
  constexpr std::array<int, 7> kColumns = {0, 1, 2, 3, 4, 5, 8};
  constexpr std::array<const char*, 7> kTitles = {"AP", "AP50", "AP75", "APs", "APm", "APl", "AR"};
  std::string out = fmt::format("{:<20} {:>8}", "category", "id");
  for (size_t c = 0; c < kColumns.size(); ++c) {
    out += fmt::format(" {:>6}", c + 1 == kColumns.size()
                                     ? fmt::format("AR{}", result.options.max_dets.back())
                                     : std::string(kTitles[c]));
  }
  out += "\n";
  for (size_t k = 0; k < result.category_ids.size(); ++k) {
    std::string name = result.category_names[k].empty() ? "-" : result.category_names[k];
    if (name.size() > 20) name = name.substr(0, 19) + "~";
    out += fmt::format("{:<20} {:>8}", name, result.category_ids[k]);
    for (const int s : kColumns) {
      const double v = result.category_stats[k][s];
      out += v < 0 ? fmt::format(" {:>6}", "-") : fmt::format(" {:6.3f}", v);
    }
    out += "\n";
  }
  return out;
}

const std::array<const char*, kNumCocoScoreStats>& CocoScoreStatNames() {
  static const std::array<const char*, kNumCocoScoreStats> kNames = {
      "BL", "BL50", "BL75", "BD", "BD50", "BD75", "BA", "BA50", "BA75", "ECE", "ECE50", "ECE75"};
  return kNames;
}

// -----------------------------------------------------------------------------------------------
// The optimal matcher (coco_internal.h).

void CocoOptimalMatcher::BuildGraph(const CocoImageCell& cell, double tau, int num_present) {
  const int G = cell.num_gts;
  adjacency_.num_labels = G;
  adjacency_.begin.assign(1, 0);
  adjacency_.labels.clear();
  excusable_.assign(num_present, 0);
  for (int d = 0; d < num_present; ++d) {
    excusable_[d] = cell.det_outside[d];
    for (int g = 0; g < G; ++g) {
      if (cell.iou[static_cast<size_t>(d) * G + g] < tau) continue;
      if (cell.gt_valid[g]) {
        adjacency_.labels.push_back(g);
      } else {
        excusable_[d] = 1;
      }
    }
    adjacency_.begin.push_back(static_cast<int32_t>(adjacency_.labels.size()));
  }
}

void CocoOptimalMatcher::Outcomes(const CocoImageCell& cell, double tau,
                                  std::vector<uint8_t>* flags) {
  BuildGraph(cell, tau, cell.num_dets);
  all_.Reset(&adjacency_);
  unexcusable_.Reset(&adjacency_);
  flags->assign(cell.num_dets, kCocoIgnored);
  for (int d = 0; d < cell.num_dets; ++d) {
    // TP(s) = rank of all detections above s; FP(s) = unexcusable ones above s minus their rank
    // (a maximum matching can be extended to cover a largest matchable set of them).
    if (all_.AddDet(d)) {
      (*flags)[d] = kCocoMatched;
      if (!excusable_[d]) unexcusable_.AddDet(d);  // grows too
    } else if (!excusable_[d] && !unexcusable_.AddDet(d)) {
      (*flags)[d] = 0;  // one more false positive
    }
  }
}

void CocoOptimalMatcher::Associate(const CocoImageCell& cell, double tau, int num_present,
                                   std::vector<int32_t>* det_gt, std::vector<uint8_t>* flags) {
  BuildGraph(cell, tau, num_present);
  det_gt->assign(cell.num_dets, -1);
  flags->assign(cell.num_dets, kCocoIgnored);
  // Weight of a pair: K (one TP) + 1 (a detection nothing else would excuse), then the IoU. With K
  // above any count of pairs the integer part orders matchings by (TPs, FPs avoided) exactly.
  const int64_t big_k = num_present + 1;
  edges_.clear();
  for (int d = 0; d < num_present; ++d) {
    for (int e = adjacency_.begin[d]; e < adjacency_.begin[d + 1]; ++e) {
      const int g = adjacency_.labels[e];
      WeightedEdge edge;
      edge.label = g;
      edge.det = d;
      edge.weight.major = big_k + (excusable_[d] ? 0 : 1);
      edge.weight.minor = cell.iou[static_cast<size_t>(d) * cell.num_gts + g];
      edges_.push_back(edge);
    }
  }
  if (!edges_.empty()) {
    const std::vector<int32_t> gt_det = MaxWeightAssignment(cell.num_gts, num_present, edges_);
    for (int g = 0; g < cell.num_gts; ++g) {
      if (gt_det[g] >= 0) (*det_gt)[gt_det[g]] = g;
    }
  }
  for (int d = 0; d < num_present; ++d) {
    if ((*det_gt)[d] >= 0) {
      (*flags)[d] = kCocoMatched;
    } else if (!excusable_[d]) {
      (*flags)[d] = 0;
    }
  }
}

// -----------------------------------------------------------------------------------------------
// Evaluation.

namespace {

// np.spacing(1): what pycocotools adds to tp + fp so that precision is defined without detections.
constexpr double kNumpySpacingOfOne = std::numeric_limits<double>::epsilon();

// The IoU of a detection and a ground-truth box, as maskApi.c's bbIou computes it, operation by
// operation: for a crowd the union is the detection's area.
double BoxIou(const CocoBox& d, const CocoBox& g, bool crowd) {
  const double w = std::min(d.width + d.x, g.width + g.x) - std::max(d.x, g.x);
  if (w <= 0) return 0;
  const double h = std::min(d.height + d.y, g.height + g.y) - std::max(d.y, g.y);
  if (h <= 0) return 0;
  const double intersection = w * h;
  const double det_area = d.width * d.height;
  const double union_area = crowd ? det_area : det_area + g.width * g.height - intersection;
  return intersection / union_area;
}

bool OutsideRange(double area, const CocoAreaRange& range) {
  return area < range.min_area || area > range.max_area;
}

// Per detection and (area range, IoU threshold): evaluateImg's dtMatches != 0 (kCocoMatched:
// matched to a ground truth whose id is not 0) and dtIgnore (kCocoIgnored); the optimal matcher's
// outcomes in the same flags (coco_internal.h).
constexpr uint8_t kMatched = kCocoMatched;
constexpr uint8_t kIgnored = kCocoIgnored;

using CategoryDetections = CocoCategoryDetections;

// The indices of the items whose category and image are known (index >= 0), grouped by
// (category, image), each group in file order: the stable sort on the pair, as a counting sort by
// image and then by category (least significant key first; each pass stable). Linear, and each
// pass reads in order: the comparison sort it replaces spent its time on cache misses.
std::vector<uint32_t> GroupByCategoryAndImage(const std::vector<int32_t>& category,
                                              const std::vector<int32_t>& image,
                                              size_t num_categories, size_t num_images) {
  const size_t n = category.size();
  std::vector<uint32_t> start(std::max(num_categories, num_images) + 1);
  // Counts -> where each key's run starts.
  auto starts = [&](size_t num_keys, auto key_of, const auto& items) {
    std::fill(start.begin(), start.begin() + num_keys + 1, 0u);
    for (const uint32_t i : items) ++start[key_of(i) + 1];
    std::partial_sum(start.begin(), start.begin() + num_keys + 1, start.begin());
  };
  std::vector<uint32_t> known;
  known.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (category[i] >= 0 && image[i] >= 0) known.push_back(static_cast<uint32_t>(i));
  }
  std::vector<uint32_t> by_image(known.size()), order(known.size());
  auto image_of = [&](uint32_t i) { return static_cast<size_t>(image[i]); };
  auto category_of = [&](uint32_t i) { return static_cast<size_t>(category[i]); };
  starts(num_images, image_of, known);
  for (const uint32_t i : known) by_image[start[image_of(i)]++] = i;
  starts(num_categories, category_of, by_image);
  for (const uint32_t i : by_image) order[start[category_of(i)]++] = i;
  return order;
}

// numpy's float64 add.reduce of a contiguous array: pairwise summation, 8 accumulators in blocks
// of at most 128, over buffer-sized chunks of 8192 elements added in order.
double NumpyPairwiseSum(const double* a, size_t n) {
  if (n < 8) {
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) sum += a[i];
    return sum;
  }
  if (n <= 128) {
    double r[8];
    for (int j = 0; j < 8; ++j) r[j] = a[j];
    size_t i = 8;
    for (; i < n - n % 8; i += 8) {
      for (int j = 0; j < 8; ++j) r[j] += a[i + j];
    }
    double sum = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for (; i < n; ++i) sum += a[i];
    return sum;
  }
  size_t half = n / 2;
  half -= half % 8;
  return NumpyPairwiseSum(a, half) + NumpyPairwiseSum(a + half, n - half);
}

double NumpyMean(const std::vector<double>& values) {
  constexpr size_t kBufferSize = 8192;
  double sum = 0.0;
  for (size_t start = 0; start < values.size(); start += kBufferSize) {
    sum += NumpyPairwiseSum(values.data() + start, std::min(kBufferSize, values.size() - start));
  }
  return sum / static_cast<double>(values.size());
}

// One line of summarize() (_summarizeDets): AP or AR, at one IoU threshold or averaged over all,
// in one area range, at one max_dets.
struct SummaryLine {
  bool ap = true;
  std::optional<double> iou;  // unset: all thresholds
  const char* area = "all";
  int max_dets = 100;
};

std::array<SummaryLine, kNumCocoStats> SummaryLines(const std::vector<int>& max_dets) {
  const int m0 = max_dets.at(0), m1 = max_dets.at(1), m2 = max_dets.at(2);
  // The first line's 100 is _summarize's default argument, not max_dets[2] (reproduced).
  return {{{true, std::nullopt, "all", 100},
           {true, 0.5, "all", m2},
           {true, 0.75, "all", m2},
           {true, std::nullopt, "small", m2},
           {true, std::nullopt, "medium", m2},
           {true, std::nullopt, "large", m2},
           {false, std::nullopt, "all", m0},
           {false, std::nullopt, "all", m1},
           {false, std::nullopt, "all", m2},
           {false, std::nullopt, "small", m2},
           {false, std::nullopt, "medium", m2},
           {false, std::nullopt, "large", m2}}};
}

}  // namespace

// numpy computes, for every detection j, rc[j] = tp[j] / npig and pr[j] = tp[j] / (fp[j] + tp[j]
// + eps) from the cumulative counts, raises each pr[j] to the largest after it, and reads, for
// each recall threshold, pr and the score at the first j with rc[j] >= the threshold. The same
// numbers from the true positives alone:
// - rc[j] is a function of tp[j] (one division, monotone in it), so the first j with rc[j] >= x
//   is where the c-th true positive is, c the least count with c / npig >= x (or j = 0, c = 0);
// - after a true positive, pr only falls (a false positive) or stays (an ignored detection)
//   until the next one, so the largest pr[j] at or after a true positive is the largest at the
//   true positives from there on, and before the first one pr is 0.
// Each pr at a true positive is the division numpy makes there (tp and fp are exact integers in
// a double); the counting pass is branch-free, and there are npig divisions at most instead of
// two per detection.
void CocoAccumulateCurve(const uint8_t* flags, const double* scores, size_t nd, int64_t npig,
                         const std::vector<double>& recall_thresholds, CocoCurveScratch* scratch,
                         double* recall, double* precision, double* score_at, size_t stride) {
  const size_t R = recall_thresholds.size();
  std::vector<uint32_t>& tp_at = scratch->tp_at;          // where the c-th true positive is
  std::vector<uint32_t>& fp_before = scratch->fp_before;  // the false positives before it
  tp_at.resize(nd + 1);
  fp_before.resize(nd + 1);
  size_t num_tp = 0;
  uint32_t num_fp = 0;
  for (size_t j = 0; j < nd; ++j) {
    const bool counted = !(flags[j] & kIgnored);
    const bool tp = counted && (flags[j] & kMatched);
    tp_at[num_tp] = static_cast<uint32_t>(j);
    fp_before[num_tp] = num_fp;
    num_tp += tp;
    num_fp += counted && !tp;
  }
  const double n = static_cast<double>(npig);
  *recall = nd > 0 ? static_cast<double>(num_tp) / n : 0.0;
  // pr at each true positive, then the envelope from the right.
  std::vector<double>& pr = scratch->tp_precision;
  pr.resize(num_tp);
  for (size_t c = 0; c < num_tp; ++c) {
    const double tp = static_cast<double>(c + 1);
    pr[c] = tp / (static_cast<double>(fp_before[c]) + tp + kNumpySpacingOfOne);
  }
  for (size_t c = num_tp; c-- > 1;) {
    if (pr[c] > pr[c - 1]) pr[c - 1] = pr[c];
  }
  // The thresholds ascend, so the least count reaching each only grows.
  size_t count = 0;
  for (size_t r = 0; r < R; ++r) {
    while (count <= num_tp && static_cast<double>(count) / n < recall_thresholds[r]) ++count;
    if (nd == 0 || count > num_tp) {
      // np.searchsorted past the end: this threshold and the rest keep their zeros.
      for (size_t rest = r; rest < R; ++rest) {
        precision[rest * stride] = 0.0;
        score_at[rest * stride] = 0.0;
      }
      break;
    }
    const size_t at = count == 0 ? 0 : tp_at[count - 1];
    precision[r * stride] = count == 0 ? (num_tp > 0 ? pr[0] : 0.0) : pr[count - 1];
    score_at[r * stride] = scores[at];
  }
}

void CocoAccumulateCurves(const CocoCategoryDetections& in, const std::vector<uint32_t>& sequence,
                          int k, int a, int m, int64_t npig, CocoCurveScratch* scratch,
                          CocoEvalResult* result) {
  const CocoEvalOptions& o = result->options;
  const size_t T = o.iou_thresholds.size(), A = o.area_ranges.size(), nd = sequence.size();
  // Each detection's T flags are adjacent in `in`: gathered once, threshold-major.
  scratch->scores.resize(nd);
  scratch->flags.resize(T * nd);
  for (size_t j = 0; j < nd; ++j) {
    scratch->scores[j] = in.score[sequence[j]];
    const uint8_t* flags = &in.flags[(sequence[j] * A + a) * T];
    for (size_t t = 0; t < T; ++t) scratch->flags[t * nd + j] = flags[t];
  }
  for (size_t t = 0; t < T; ++t) {
    const int ti = static_cast<int>(t);
    const size_t at = result->PrecisionIndex(ti, 0, k, a, m);
    CocoAccumulateCurve(scratch->flags.data() + t * nd, scratch->scores.data(), nd, npig,
                        o.recall_thresholds, scratch,
                        &result->recall[result->RecallIndex(ti, k, a, m)], &result->precision[at],
                        &result->scores[at], result->PrecisionIndex(ti, 1, k, a, m) - at);
  }
}

std::vector<CocoSummarySlice> CocoSummarySlices(const CocoEvalOptions& options) {
  std::vector<CocoSummarySlice> slices;
  for (const SummaryLine& line : SummaryLines(options.max_dets)) {
    CocoSummarySlice slice;
    slice.ap = line.ap;
    for (size_t i = 0; i < options.area_ranges.size(); ++i) {
      if (options.area_ranges[i].label == line.area) slice.area = static_cast<int>(i);
    }
    for (size_t i = 0; i < options.max_dets.size(); ++i) {
      if (options.max_dets[i] == line.max_dets) slice.max_dets = static_cast<int>(i);
    }
    if (slice.area < 0 || slice.max_dets < 0) slice.area = slice.max_dets = -1;
    slices.push_back(slice);
  }
  return slices;
}

namespace {

// summarize()'s 12 numbers over the categories [k_begin, k_end).
std::array<double, kNumCocoStats> SummaryOf(const CocoEvalResult* result, int k_begin, int k_end) {
  const CocoEvalOptions& options = result->options;
  const int T = static_cast<int>(options.iou_thresholds.size()),
            R = static_cast<int>(options.recall_thresholds.size());
  std::array<double, kNumCocoStats> stats;
  const std::array<SummaryLine, kNumCocoStats> lines = SummaryLines(options.max_dets);
  const std::vector<CocoSummarySlice> slices = CocoSummarySlices(options);
  std::vector<double> values;
  for (int s = 0; s < kNumCocoStats; ++s) {
    const SummaryLine& line = lines[s];
    const int a = slices[s].area, m = slices[s].max_dets;
    values.clear();
    if (a >= 0) {
      for (int t = 0; t < T; ++t) {
        // np.where(iouThr == p.iouThrs): exact equality.
        if (line.iou && options.iou_thresholds[t] != *line.iou) continue;
        if (line.ap) {
          for (int r = 0; r < R; ++r) {
            for (int k = k_begin; k < k_end; ++k) {
              const double v = result->precision[result->PrecisionIndex(t, r, k, a, m)];
              if (v > -1) values.push_back(v);
            }
          }
        } else {
          for (int k = k_begin; k < k_end; ++k) {
            const double v = result->recall[result->RecallIndex(t, k, a, m)];
            if (v > -1) values.push_back(v);
          }
        }
      }
    }
    stats[s] = values.empty() ? -1.0 : NumpyMean(values);
  }
  return stats;
}

}  // namespace

void SummarizeCoco(CocoEvalResult* result) {
  result->stats = SummaryOf(result, 0, static_cast<int>(result->category_ids.size()));
}

void SummarizeCocoCategories(CocoEvalResult* result) {
  const int K = static_cast<int>(result->category_ids.size());
  result->category_stats.resize(K);
  for (int k = 0; k < K; ++k) result->category_stats[k] = SummaryOf(result, k, k + 1);
}

namespace {

// Ids -> their index in a list of distinct ids. A table where the ids are small enough (COCO's:
// image ids up to about 600,000 for 5000 images, category ids up to 90), else a hash map: the
// half million lookups of a COCO-sized results file cost a twentieth of the run through the map.
class IdIndex {
 public:
  explicit IdIndex(const std::vector<int64_t>& ids) {
    int64_t lowest = 0, highest = -1;
    if (!ids.empty()) {
      const auto [lo, hi] = std::minmax_element(ids.begin(), ids.end());
      lowest = *lo;
      highest = *hi;
    }
    const size_t n = ids.size();
    if (lowest >= 0 && highest < static_cast<int64_t>(std::max<size_t>(1024, 256 * n))) {
      table_.assign(static_cast<size_t>(highest + 1), -1);
      for (size_t i = 0; i < n; ++i) table_[ids[i]] = static_cast<int32_t>(i);
    } else {
      map_.reserve(n);
      for (size_t i = 0; i < n; ++i) map_.emplace(ids[i], static_cast<int32_t>(i));
    }
  }
  // The id's index, or -1.
  int32_t Find(int64_t id) const {
    if (map_.empty()) {
      return id >= 0 && id < static_cast<int64_t>(table_.size()) ? table_[id] : -1;
    }
    const auto it = map_.find(id);
    return it == map_.end() ? -1 : it->second;
  }

 private:
  std::vector<int32_t> table_;
  std::unordered_map<int64_t, int32_t> map_;
};

class CocoEvaluator {
 public:
  // With `keep`, every category's detections are handed over there.
  CocoEvaluator(const CocoGroundTruth& gt, const std::vector<CocoDetection>& dets,
                CocoEvalResult* result, std::vector<CocoCategoryDetections>* keep = nullptr)
      : gt_(gt), dets_(dets), result_(*result), options_(result->options), keep_(keep) {}

  void Run() {
    Index();
    const size_t T = options_.iou_thresholds.size(), R = options_.recall_thresholds.size(),
                 K = result_.category_ids.size(), A = options_.area_ranges.size(),
                 M = options_.max_dets.size();
    // 15.5 MB for COCO's shape: on huge pages (malloc_tuning.h says why).
    for (std::vector<double>* array : {&result_.precision, &result_.scores}) {
      ReserveOnHugePages(*array, T * R * K * A * M);
      array->assign(T * R * K * A * M, -1.0);
    }
    result_.recall.assign(T * K * A * M, -1.0);
    if (keep_ != nullptr) keep_->assign(K, CocoCategoryDetections());
    for (size_t a = 0; a < A; ++a) {
      if (options_.area_ranges[a].label == "all") area_all_ = static_cast<int>(a);
    }
    // Range "all" first: with stable area ranges the others are counted from its matching.
    if (area_all_ >= 0) area_order_.push_back(static_cast<size_t>(area_all_));
    for (size_t a = 0; a < A; ++a) {
      if (static_cast<int>(a) != area_all_) area_order_.push_back(a);
    }
    if (options_.score_metrics) {
      result_.cells.assign(T * K * A, CocoCell());
      if (options_.score_transform == ScoreTransform::kNone) {
        for (const uint32_t i : det_order_) {
          if (!(dets_[i].score >= 0 && dets_[i].score <= 1)) result_.probability_metrics = false;
        }
      }
    }
    ParallelFor(
        K,
        [&](size_t k) {
          CategoryDetections category = EvaluateCategory(k);
          Accumulate(static_cast<int>(k), category);
          if (options_.score_metrics) FinishCells(static_cast<int>(k), category);
          if (keep_ != nullptr) (*keep_)[k] = std::move(category);
        },
        options_.num_threads);
    SummarizeCoco(&result_);
    SummarizeCocoCategories(&result_);
    result_.score_stats.fill(-1.0);
    if (options_.score_metrics && result_.probability_metrics) SummarizeCells();
  }

 private:
  // Maps ids to indices; groups the ground truths and detections by category and image.
  void Index() {
    result_.image_ids = gt_.image_ids;
    for (const CocoCategory& c : gt_.categories) {
      result_.category_ids.push_back(c.id);
      result_.category_names.push_back(c.name);
    }
    const IdIndex image_index(result_.image_ids), category_index(result_.category_ids);
    auto lookup = [](const IdIndex& index, int64_t id) { return index.Find(id); };
    std::vector<int32_t> gt_category(gt_.annotations.size()), gt_image(gt_.annotations.size());
    for (size_t i = 0; i < gt_.annotations.size(); ++i) {
      gt_category[i] = lookup(category_index, gt_.annotations[i].category_id);
      gt_image[i] = lookup(image_index, gt_.annotations[i].image_id);
    }
    std::vector<int32_t> det_category(dets_.size()), det_image(dets_.size());
    for (size_t i = 0; i < dets_.size(); ++i) {
      det_category[i] = lookup(category_index, dets_[i].category_id);
      det_image[i] = lookup(image_index, dets_[i].image_id);
      STEREODET_CHECK(det_image[i] >= 0)
          << "COCO detection " << i << " is on image " << dets_[i].image_id
          << ", which the ground truth does not have";
    }
    const size_t K = result_.category_ids.size(), num_images = result_.image_ids.size();
    gt_order_ = GroupByCategoryAndImage(gt_category, gt_image, K, num_images);
    det_order_ = GroupByCategoryAndImage(det_category, det_image, K, num_images);
    result_.num_gt = static_cast<int64_t>(gt_order_.size());
    result_.num_gt_skipped = static_cast<int64_t>(gt_.annotations.size()) - result_.num_gt;
    result_.num_detections = static_cast<int64_t>(det_order_.size());
    result_.num_detections_skipped = static_cast<int64_t>(dets_.size()) - result_.num_detections;
    // Where each category's range starts in the two orders.
    gt_start_.assign(K + 1, 0);
    det_start_.assign(K + 1, 0);
    for (const uint32_t i : gt_order_) ++gt_start_[gt_category[i] + 1];
    for (const uint32_t i : det_order_) ++det_start_[det_category[i] + 1];
    std::partial_sum(gt_start_.begin(), gt_start_.end(), gt_start_.begin());
    std::partial_sum(det_start_.begin(), det_start_.end(), det_start_.begin());
    // The evaluation reads the detections in that order, each category's once: copied so, in
    // one pass, instead of reading the file-order detections at random in every category.
    ReserveOnHugePages(sorted_dets_, det_order_.size());
    sorted_dets_.resize(det_order_.size());
    det_sorted_image_.resize(det_order_.size());
    for (size_t p = 0; p < det_order_.size(); ++p) {
      const CocoDetection& d = dets_[det_order_[p]];
      sorted_dets_[p] = {d.bbox, d.score};
      det_sorted_image_[p] = det_image[det_order_[p]];
    }
    gt_sorted_image_.resize(gt_order_.size());
    for (size_t p = 0; p < gt_order_.size(); ++p) gt_sorted_image_[p] = gt_image[gt_order_[p]];
  }

  // evaluate() for one category: evaluateImg on every image with a ground truth or a detection
  // of it, for every area range, at the largest max_dets; the results in accumulate()'s order.
  // With the optimal matcher, its outcomes in evaluateImg's place.
  CategoryDetections EvaluateCategory(size_t k) const {
    const size_t T = options_.iou_thresholds.size(), A = options_.area_ranges.size();
    const int max_det = options_.max_dets.back();
    CategoryDetections out;
    out.num_valid_gt.assign(A, 0);
    std::vector<uint32_t> gts, dts, gt_sorted;
    std::vector<double> iou, iou_sorted;
    std::vector<int> candidate_begin, candidates;
    std::vector<int32_t> all_gt;
    // The loop's starting bar at the lowest threshold: below it nothing ever matches.
    const double lowest_threshold =
        std::min(*std::min_element(options_.iou_thresholds.begin(), options_.iou_thresholds.end()),
                 1 - 1e-10);
    std::vector<uint8_t> gt_ignore, det_outside, gt_valid, det_flags, gt_crowd, gt_findable;
    std::vector<char> gt_matched;
    std::vector<int32_t> det_gt;
    CocoOptimalMatcher optimal;
    if (options_.score_metrics) {
      out.cell_tp.assign(T * A, 0);
      out.cell_fp.assign(T * A, 0);
      out.cell_fn.assign(T * A, 0);
      out.cell_terms.assign(T * A, ScoreMetricsAccumulator(options_.calibration_bins, 1.0, 1.0,
                                                           options_.score_transform));
    }
    // gts: indices into the annotations; dts: positions in det_order_ (sorted_dets_).
    size_t g_at = gt_start_[k], d_at = det_start_[k];
    const size_t most = det_start_[k + 1] - d_at;  // max_det may keep fewer
    out.score.reserve(most);
    out.image.reserve(most);
    out.rank.reserve(most);
    out.flags.reserve(most * A * T);
    while (g_at < gt_start_[k + 1] || d_at < det_start_[k + 1]) {
      // The next image of the category, and its ground truths and detections in file order.
      const int32_t image = std::min(
          g_at < gt_start_[k + 1] ? gt_sorted_image_[g_at] : std::numeric_limits<int>::max(),
          d_at < det_start_[k + 1] ? det_sorted_image_[d_at] : std::numeric_limits<int>::max());
      gts.clear();
      dts.clear();
      for (; g_at < gt_start_[k + 1] && gt_sorted_image_[g_at] == image; ++g_at) {
        gts.push_back(gt_order_[g_at]);
      }
      for (; d_at < det_start_[k + 1] && det_sorted_image_[d_at] == image; ++d_at) {
        dts.push_back(static_cast<uint32_t>(d_at));
      }
      // Highest score first, ties in file order (numpy's stable mergesort), at most max_det. A
      // cell holds a detection or two: insertion sort (stable, no buffer to allocate) there.
      auto higher = [&](uint32_t a, uint32_t b) {
        return sorted_dets_[a].score > sorted_dets_[b].score;
      };
      if (dts.size() <= 16) {
        for (size_t i = 1; i < dts.size(); ++i) {
          const uint32_t moving = dts[i];
          size_t j = i;
          for (; j > 0 && higher(moving, dts[j - 1]); --j) dts[j] = dts[j - 1];
          dts[j] = moving;
        }
      } else {
        std::stable_sort(dts.begin(), dts.end(), higher);
      }
      if (dts.size() > static_cast<size_t>(max_det)) dts.resize(max_det);
      const size_t G = gts.size(), D = dts.size();

      iou.resize(D * G);
      for (size_t d = 0; d < D; ++d) {
        for (size_t g = 0; g < G; ++g) {
          const CocoAnnotation& truth = gt_.annotations[gts[g]];
          iou[d * G + g] = BoxIou(sorted_dets_[dts[d]].bbox, truth.bbox, truth.iscrowd);
        }
      }

      // The detections at the operating point: a prefix, as they are sorted by score.
      size_t num_present = 0;
      while (num_present < D && sorted_dets_[dts[num_present]].score >= options_.score_threshold) {
        ++num_present;
      }
      const size_t first = out.score.size();
      for (size_t d = 0; d < D; ++d) {
        out.score.push_back(sorted_dets_[dts[d]].score);
        out.image.push_back(image);
        out.rank.push_back(static_cast<int32_t>(d));
      }
      out.flags.resize(out.score.size() * A * T, 0);
      // With stable area ranges: range "all"'s matched ground truth of each detection and
      // threshold (an index into gts), or -1.
      if (options_.stable_area_ranges) all_gt.assign(D * T, -1);
      for (const size_t a : area_order_) {
        const CocoAreaRange& range = options_.area_ranges[a];
        // Ground truths not ignored first, each part in file order (a stable sort on _ignore).
        gt_sorted.clear();
        gt_ignore.clear();
        for (const bool ignored_part : {false, true}) {
          for (size_t g = 0; g < G; ++g) {
            const CocoAnnotation& truth = gt_.annotations[gts[g]];
            const bool ignored = truth.iscrowd || (options_.honor_ignore_flag && truth.ignore) ||
                                 OutsideRange(truth.area, range);
            if (ignored != ignored_part) continue;
            gt_sorted.push_back(static_cast<uint32_t>(g));
            gt_ignore.push_back(ignored);
          }
        }
        const int32_t valid =
            static_cast<int32_t>(std::count(gt_ignore.begin(), gt_ignore.end(), 0));
        out.num_valid_gt[a] += valid;
        if (G > 0) {
          if (a == area_order_.front()) {
            out.valid_image.push_back(image);
            out.valid_count.resize(out.valid_count.size() + A, 0);
          }
          out.valid_count[out.valid_count.size() - A + a] = valid;
        }
        det_outside.resize(D);
        for (size_t d = 0; d < D; ++d) {
          const CocoBox& box = sorted_dets_[dts[d]].bbox;
          det_outside[d] = OutsideRange(box.width * box.height, range);
        }
        gt_valid.assign(G, 0);
        for (size_t j = 0; j < G; ++j) gt_valid[gt_sorted[j]] = !gt_ignore[j];
        if (options_.score_metrics) {
          det_flags.assign(D, 0);
          det_gt.assign(D, -1);
        }
        if (G == 0 && !options_.score_metrics) {
          // Nothing to match, under either matcher: a detection outside the range is ignored,
          // any other a FP.
          for (size_t d = 0; d < D; ++d) {
            if (det_outside[d]) std::fill_n(&out.flags[((first + d) * A + a) * T], T, kIgnored);
          }
          continue;
        }
        if (options_.stable_area_ranges && static_cast<int>(a) != area_all_) {
          StableRange(dts, gt_valid, det_outside, all_gt, iou.data(), first, num_present, image, a,
                      &det_flags, &det_gt, &out);
          continue;
        }
        if (options_.matcher == CocoMatcher::kOptimal) {
          CocoImageCell cell;
          cell.num_dets = static_cast<int>(D);
          cell.num_gts = static_cast<int>(G);
          cell.iou = iou.data();
          cell.gt_valid = gt_valid.data();
          cell.det_outside = det_outside.data();
          for (size_t t = 0; t < T; ++t) {
            const double tau = std::min(options_.iou_thresholds[t], 1 - 1e-10);
            optimal.Outcomes(cell, tau, &det_flags);
            for (size_t d = 0; d < D; ++d) out.flags[((first + d) * A + a) * T + t] = det_flags[d];
            if (options_.score_metrics) {
              optimal.Associate(cell, tau, static_cast<int>(num_present), &det_gt, &det_flags);
              AddCellTerms(dts, gt_valid, det_flags, det_gt, iou.data(), num_present, image, t, a,
                           &out);
            }
          }
          continue;
        }
        // The ground truths' crowd flags, ids and IoUs in the order the loop visits them.
        gt_crowd.resize(G);
        gt_findable.resize(G);
        for (size_t j = 0; j < G; ++j) {
          const CocoAnnotation& truth = gt_.annotations[gts[gt_sorted[j]]];
          gt_crowd[j] = truth.iscrowd;
          // dtMatches holds the matched ground truth's id, and 0 means unmatched: a match to
          // id 0 is no match (pycocotools' quirk, reproduced).
          gt_findable[j] = truth.id != 0;
        }
        iou_sorted.resize(D * G);
        for (size_t d = 0; d < D; ++d) {
          for (size_t j = 0; j < G; ++j) iou_sorted[d * G + j] = iou[d * G + gt_sorted[j]];
        }
        // Per detection, the ground truths it overlaps by the lowest threshold at least, in
        // visiting order: at every threshold the loop below skips the others anyway (an IoU under
        // the threshold never matches, and skipping an ignored one cannot miss the stop, as every
        // ground truth after an ignored one is ignored too).
        candidate_begin.assign(1, 0);
        candidates.clear();
        for (size_t d = 0; d < D; ++d) {
          for (size_t j = 0; j < G; ++j) {
            if (iou_sorted[d * G + j] >= lowest_threshold)
              candidates.push_back(static_cast<int>(j));
          }
          candidate_begin.push_back(static_cast<int>(candidates.size()));
        }
        for (size_t t = 0; t < T; ++t) {
          gt_matched.assign(G, 0);
          for (size_t d = 0; d < D; ++d) {
            // evaluateImg's loop: the best IoU >= the threshold among the ground truths not yet
            // matched (crowds match any number of times), stopping at the ignored ones once a
            // valid one is found.
            double best = std::min(options_.iou_thresholds[t], 1 - 1e-10);
            int match = -1;
            const double* overlaps = &iou_sorted[d * G];
            for (int c = candidate_begin[d]; c < candidate_begin[d + 1]; ++c) {
              const int j = candidates[c];
              if (gt_matched[j] && !gt_crowd[j]) continue;
              if (match > -1 && !gt_ignore[match] && gt_ignore[j]) break;
              if (overlaps[j] < best) continue;
              best = overlaps[j];
              match = j;
            }
            uint8_t flags = 0;
            bool matched = false;
            if (match > -1) {
              gt_matched[match] = 1;
              matched = gt_findable[match];
              if (gt_ignore[match]) flags |= kIgnored;
            }
            if (matched) flags |= kMatched;
            if (!matched && det_outside[d]) flags |= kIgnored;
            out.flags[((first + d) * A + a) * T + t] = flags;
            if (options_.stable_area_ranges) {
              all_gt[d * T + t] = matched ? static_cast<int32_t>(gt_sorted[match]) : -1;
            }
            if (options_.score_metrics) {
              det_flags[d] = flags;
              det_gt[d] = matched ? static_cast<int32_t>(gt_sorted[match]) : -1;
            }
          }
          if (options_.score_metrics) {
            // Greedy in score order: the association of the detections at the operating point
            // is the whole one's restricted to them.
            AddCellTerms(dts, gt_valid, det_flags, det_gt, iou.data(), num_present, image, t, a,
                         &out);
          }
        }
      }
    }
    return out;
  }

  // Area range a (not "all") of one image and category counted from range "all"'s matching,
  // already in out->flags (CocoEvalOptions::stable_area_ranges): a pair is a TP where its ground
  // truth is valid in the range and drops out (ignored) where not; a detection "all" excused stays
  // excused; one matched to nothing (or to ground-truth id 0, pycocotools' quirk) is a FP where
  // its own area is in the range.
  void StableRange(const std::vector<uint32_t>& dts, const std::vector<uint8_t>& gt_valid,
                   const std::vector<uint8_t>& det_outside, const std::vector<int32_t>& all_gt,
                   const double* iou, size_t first, size_t num_present, int32_t image, size_t a,
                   std::vector<uint8_t>* det_flags, std::vector<int32_t>* det_gt,
                   CategoryDetections* out) const {
    const size_t T = options_.iou_thresholds.size(), A = options_.area_ranges.size(),
                 D = dts.size();
    for (size_t t = 0; t < T; ++t) {
      for (size_t d = 0; d < D; ++d) {
        const uint8_t in_all = out->flags[((first + d) * A + area_all_) * T + t];
        const int32_t g = all_gt[d * T + t];
        uint8_t flags = 0;
        if (in_all & kIgnored) {
          flags = kIgnored;
        } else if (in_all & kMatched) {
          flags = gt_valid[g] ? kMatched : kIgnored;
        } else if (det_outside[d]) {
          flags = kIgnored;
        }
        out->flags[((first + d) * A + a) * T + t] = flags;
        if (options_.score_metrics) {
          (*det_flags)[d] = flags;
          (*det_gt)[d] = flags == kMatched ? g : -1;
        }
      }
      if (options_.score_metrics) {
        AddCellTerms(dts, gt_valid, *det_flags, *det_gt, iou, num_present, image, t, a, out);
      }
    }
  }

  // One image's share of cell `cell` (t * A + a) at the operating point: `flags` and `det_gt` are
  // the association of the first num_present detections of `dts` (kMatched alone: a TP with
  // ground truth det_gt[d], an index into the image's ground truths; 0: a FP; else neither);
  // iou[d * G + g] the IoU of detection d with ground truth g (G = gt_valid.size()), a TP's for
  // LaECE. Label terms first, in file order, then the detections' in score order.
  void AddCellTerms(const std::vector<uint32_t>& dts, const std::vector<uint8_t>& gt_valid,
                    const std::vector<uint8_t>& flags, const std::vector<int32_t>& det_gt,
                    const double* iou, size_t num_present, int32_t image, size_t t, size_t a,
                    CategoryDetections* out) const {
    const size_t cell = t * options_.area_ranges.size() + a;
    ScoreMetricsAccumulator& terms = out->cell_terms[cell];
    // The image's own terms, kept for the bootstrap (area "all" only: the summary's).
    const bool keep = keep_ != nullptr && static_cast<int>(a) == area_all_;
    CocoImageBrierTerms own;
    own.image = image;
    own.t = static_cast<int32_t>(t);
    std::vector<int32_t>& gt_tp_det = out->gt_tp_det;
    gt_tp_det.assign(gt_valid.size(), -1);
    for (size_t d = 0; d < num_present; ++d) {
      if (flags[d] == kMatched) gt_tp_det[det_gt[d]] = static_cast<int32_t>(d);
    }
    auto probability = [&](size_t d) {
      return ApplyScoreTransform(options_.score_transform, sorted_dets_[dts[d]].score);
    };
    for (size_t g = 0; g < gt_valid.size(); ++g) {
      if (!gt_valid[g]) continue;
      double term = 1.0;
      if (gt_tp_det[g] >= 0) {
        const double s = probability(gt_tp_det[g]);
        term = (1 - s) * (1 - s);
      } else {
        ++out->cell_fn[cell];
      }
      terms.AddLabelTerm(term);
      own.label_sum += term;
      ++own.labels;
    }
    for (size_t d = 0; d < num_present; ++d) {
      if (flags[d] != kMatched && flags[d] != 0) continue;
      const bool tp = flags[d] == kMatched;
      const double s = probability(d);
      terms.AddDetectionTerm(s, tp, tp ? iou[d * gt_valid.size() + det_gt[d]] : 0.0);
      ++(tp ? out->cell_tp : out->cell_fp)[cell];
      own.detection_sum += (s - (tp ? 1.0 : 0.0)) * (s - (tp ? 1.0 : 0.0));
      ++own.detections;
      if (!tp) {
        own.fp_square_sum += s * s;
        ++own.fps;
      }
    }
    if (keep && (own.labels > 0 || own.detections > 0)) out->brier_terms.push_back(own);
  }

  // The cells of category k from its operating-point terms.
  void FinishCells(int k, const CategoryDetections& in) {
    const size_t T = options_.iou_thresholds.size(), A = options_.area_ranges.size();
    for (size_t t = 0; t < T; ++t) {
      for (size_t a = 0; a < A; ++a) {
        const size_t i = t * A + a;
        CocoCell& cell =
            result_.cells[result_.CellIndex(static_cast<int>(t), k, static_cast<int>(a))];
        cell.num_valid_gt = in.num_valid_gt[a];
        cell.at_threshold = MakeOperatingPoint(options_.score_threshold, in.cell_tp[i],
                                               in.cell_fp[i], in.cell_fn[i]);
        cell.brier = in.cell_terms[i].Brier();
        cell.calibration = in.cell_terms[i].Calibration();
        if (!result_.probability_metrics) {
          cell.brier = WithoutProbabilities(cell.brier);
          cell.calibration = WithoutProbabilities(cell.calibration);
        }
      }
    }
  }

  // accumulate() for one category: precision, recall and scores at every threshold, area range
  // and max_dets.
  void Accumulate(int k, const CategoryDetections& in) {
    const size_t T = options_.iou_thresholds.size(), A = options_.area_ranges.size(),
                 M = options_.max_dets.size();
    // All of the category's detections by score, ties in concatenation order (numpy's stable
    // mergesort). Keeping those of rank < max_dets[m] gives the order of each smaller max_dets.
    // Sorted as (score, index) pairs with the index breaking ties: the stable sort's order,
    // without its indirect comparisons.
    std::vector<std::pair<double, uint32_t>> by_score(in.score.size());
    for (uint32_t i = 0; i < by_score.size(); ++i) by_score[i] = {in.score[i], i};
    std::sort(by_score.begin(), by_score.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    std::vector<uint32_t> order(by_score.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = by_score[i].second;
    std::vector<uint32_t> kept;
    CocoCurveScratch scratch;
    const int ki = k;
    for (size_t a = 0; a < A; ++a) {
      const int64_t npig = in.num_valid_gt[a];
      if (npig == 0) continue;  // -1 stays: no ground truth to find
      const int ai = static_cast<int>(a);
      size_t previous_nd = 0;
      for (size_t m = 0; m < M; ++m) {
        const int mi = static_cast<int>(m);
        kept.clear();
        for (const uint32_t i : order) {
          if (in.rank[i] < options_.max_dets[m]) kept.push_back(i);
        }
        // max_dets ascend, so each kept set holds the one before: as many means the same curves.
        if (m > 0 && kept.size() == previous_nd) {
          for (size_t t = 0; t < T; ++t) {
            const int ti = static_cast<int>(t);
            result_.recall[result_.RecallIndex(ti, ki, ai, mi)] =
                result_.recall[result_.RecallIndex(ti, ki, ai, mi - 1)];
            for (int r = 0; r < static_cast<int>(options_.recall_thresholds.size()); ++r) {
              result_.precision[result_.PrecisionIndex(ti, r, ki, ai, mi)] =
                  result_.precision[result_.PrecisionIndex(ti, r, ki, ai, mi - 1)];
              result_.scores[result_.PrecisionIndex(ti, r, ki, ai, mi)] =
                  result_.scores[result_.PrecisionIndex(ti, r, ki, ai, mi - 1)];
            }
          }
          continue;
        }
        previous_nd = kept.size();
        CocoAccumulateCurves(in, kept, ki, ai, mi, npig, &scratch, &result_);
      }
    }
  }

  // score_stats: per metric, the mean over categories (area "all") and the thresholds of each
  // summary line of the cells' values that are numbers.
  void SummarizeCells() {
    if (area_all_ < 0) return;
    AverageScoreStats(
        options_.iou_thresholds, static_cast<int>(result_.category_ids.size()), 4,
        [&](int metric, int t, int k) {
          const CocoCell& cell = result_.cells[result_.CellIndex(t, k, area_all_)];
          return metric == 0   ? cell.brier.over_labels
                 : metric == 1 ? cell.brier.over_detections
                 : metric == 2 ? cell.brier.over_all
                               : cell.calibration.ece;
        },
        -1.0, result_.score_stats.data());
  }

  const CocoGroundTruth& gt_;
  const std::vector<CocoDetection>& dets_;
  CocoEvalResult& result_;
  const CocoEvalOptions& options_;
  std::vector<CocoCategoryDetections>* keep_;
  int area_all_ = -1;               // the index of area range "all", or -1
  std::vector<size_t> area_order_;  // the area ranges, "all" first
  // Ground truths and detections grouped by category then image, file order within; category
  // k's are [start_[k], start_[k + 1]). The image index of every annotation and detection.
  std::vector<uint32_t> gt_order_, det_order_;
  std::vector<size_t> gt_start_, det_start_;
  // At each position of det_order_: the detection's box and score, and its image index; at each
  // of gt_order_, the annotation's image index.
  struct SortedDetection {
    CocoBox bbox;
    double score = 0;
  };
  std::vector<SortedDetection> sorted_dets_;
  std::vector<int32_t> det_sorted_image_, gt_sorted_image_;
};

}  // namespace

CocoEvalResult EvaluateCocoKeepingDetections(const CocoGroundTruth& gt,
                                             const std::vector<CocoDetection>& dets,
                                             const CocoEvalOptions& options,
                                             std::vector<CocoCategoryDetections>* categories) {
  options.Check();
  const Timer timer;
  CocoEvalResult result;
  result.options = options;
  CocoEvaluator(gt, dets, &result, categories).Run();
  result.seconds = timer.ElapsedSeconds();
  return result;
}

CocoEvalResult EvaluateCoco(const CocoGroundTruth& gt, const std::vector<CocoDetection>& dets,
                            const CocoEvalOptions& options) {
  return EvaluateCocoKeepingDetections(gt, dets, options, nullptr);
}

std::string FormatCocoSummary(const CocoEvalResult& result) {
  const CocoEvalOptions& o = result.options;
  const std::array<SummaryLine, kNumCocoStats> lines = SummaryLines(o.max_dets);
  std::string out;
  for (int s = 0; s < kNumCocoStats; ++s) {
    const SummaryLine& line = lines[s];
    const std::string iou = line.iou ? fmt::format("{:0.2f}", *line.iou)
                                     : fmt::format("{:0.2f}:{:0.2f}", o.iou_thresholds.front(),
                                                   o.iou_thresholds.back());
    out += fmt::format(" {:<18} {} @[ IoU={:<9} | area={:>6s} | maxDets={:>3d} ] = {:0.3f}\n",
                       line.ap ? "Average Precision" : "Average Recall", line.ap ? "(AP)" : "(AR)",
                       iou, line.area, line.max_dets, result.stats[s]);
  }
  if (!o.score_metrics) return out;
  // The operating-point lines, in the same layout: each metric at [.50:.95], .50 and .75.
  constexpr std::array<std::pair<const char*, const char*>, 4> kMetrics = {
      {{"Brier over labels", "(BL)"},
       {"Brier over dets", "(BD)"},
       {"Brier over all", "(BA)"},
       {"Calibration error", "(ECE)"}}};
  for (int s = 0; s < kNumCocoScoreStats; ++s) {
    const std::string iou = s % 3 == 1   ? "0.50"
                            : s % 3 == 2 ? "0.75"
                                         : fmt::format("{:0.2f}:{:0.2f}", o.iou_thresholds.front(),
                                                       o.iou_thresholds.back());
    const auto& [name, tag] = kMetrics[s / 3];
    // Name and tag fill the 23 characters "Average Precision  (AP)" does.
    out += fmt::format(" {:<{}} {} @[ IoU={:<9} | area={:>6s} | maxDets={:>3d} ] = {:0.3f}\n", name,
                       22 - std::strlen(tag), tag, iou, "all", o.max_dets.back(),
                       result.score_stats[s]);
  }
  return out;
}

}  // namespace stereodet
