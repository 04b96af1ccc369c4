// Reading and writing KITTI label files (15 fields a line) and detection files (16, score last).
#ifndef STEREODET_KITTI_LABEL_IO_H_
#define STEREODET_KITTI_LABEL_IO_H_

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/kitti/object.h"

namespace stereodet {

enum class ObjectFileKind {
  kLabel,      // exactly 15 fields a line
  kDetection,  // exactly 16 fields a line, the score last
  kAny,  // 15 or 16 fields, each line on its own (KITTI's devkit accepts both in result files)
};

// The longest class token (an object's type) the parser accepts; KITTI's longest is
// "Person_sitting" (14).
inline constexpr size_t kMaxObjectTypeLength = 64;

struct ObjectParseOptions {
  ObjectFileKind kind = ObjectFileKind::kLabel;
  // Strict (default): the first bad line throws a ParseError naming the file, line and field.
  // Lenient: bad lines are skipped and counted in ObjectFile::skipped_lines.
  bool lenient = false;
};

struct ObjectFile {
  std::vector<Object> objects;  // in file order
  int skipped_lines = 0;        // lenient mode only
  // "FILE:LINE: field F: message" for each skipped line (lenient mode), in file order.
  std::vector<std::string> problems;
};

// Parses the text of a label or detection file. `source` names the file in error messages. Blank
// lines are ignored, and so is a UTF-8 byte-order mark at the start of the text. A bad line (wrong
// field count; a type that is not 1 to kMaxObjectTypeLength bytes of printable ASCII, reported
// escaped and shortened to 40 characters; text, NaN or infinity where a number belongs;
// a negative dimension other than KITTI's -1 "not estimated"; occluded not an integer) throws
// ParseError(source, line, field, ...), or is skipped in lenient mode. In a detection line (16
// fields, kDetection or kAny) occluded may be any finite number, as the devkit reads it as a
// throw-away double ("-1.0000"): an integral value is kept, another becomes -1. Labels stay strict.
ObjectFile ParseObjects(std::string_view text, const std::string& source,
                        const ObjectParseOptions& options = {});
// Reads and parses a file. Throws std::runtime_error if it cannot be read.
ObjectFile ReadObjects(const std::filesystem::path& path, const ObjectParseOptions& options = {});

// One line, no newline. Detections (objects with a score) get 16 fields. Numbers are written with
// two decimals when that reads back exactly (KITTI's own style, so real KITTI files round-trip byte
// for byte), otherwise with the shortest text that reads back exactly; KITTI's sentinels are
// written as KITTI writes them, as integers: truncated -1, alpha -10, dimensions -1, location
// -1000, rotation_y -10 ("DontCare -1 -1 -10 503.89 169.71 590.61 190.13 -1 -1 -1 -1000 -1000 -1000
// -10"). Throws std::invalid_argument for a number that is NaN or infinite, or a type the parser
// would refuse (empty, longer than kMaxObjectTypeLength, not printable ASCII): the file could not
// be read back.
std::string FormatObject(const Object& object);
// Whole file: one line per object, each ending in '\n'.
std::string FormatObjects(const std::vector<Object>& objects);
// The name of field `index` (0-based, file order) as used in ParseError: "type", "truncated",
// "occluded", "alpha", "bbox.left", "bbox.top", "bbox.right", "bbox.bottom", "dimensions.h",
// "dimensions.w", "dimensions.l", "location.x", "location.y", "location.z", "rotation_y", "score".
// A line with the wrong number of fields names the first missing field, "score" for a 16th field
// in a label file, or "field count".
const char* ObjectFieldName(int index);

// Writes atomically (temp file + rename).
void WriteObjects(const std::filesystem::path& path, const std::vector<Object>& objects);

}  // namespace stereodet

#endif  // STEREODET_KITTI_LABEL_IO_H_
