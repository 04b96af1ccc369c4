#include "stereodet/util/check.h"

#include <atomic>
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <utility>

namespace stereodet {

namespace {
std::string FormatParseError(const std::string& file, int line, const std::string& field,
                             const std::string& message) {
  std::string out = file;
  if (line > 0) out.append(":").append(std::to_string(line));
  out.append(": ");
  if (!field.empty()) out.append("field ").append(field).append(": ");
  return out.append(message);
}

// The length of the source tag that starts at message[at] (" [NAME.cc:LINE" then "]" or
// ", CONDITION]"), or 0 if none starts there. Must match what CheckFailure appends.
size_t SourceTagLength(std::string_view message, size_t at) {
  if (message.compare(at, 2, " [") != 0) return 0;
  size_t i = at + 2;
  const size_t name_begin = i;
  while (i < message.size() &&
         (std::isalnum(static_cast<unsigned char>(message[i])) || message[i] == '_' ||
          message[i] == '-' || message[i] == '.' || message[i] == '+')) {
    ++i;
  }
  const std::string_view name = message.substr(name_begin, i - name_begin);
  if (!name.ends_with(".cc") && !name.ends_with(".h") && !name.ends_with(".cpp")) return 0;
  if (i >= message.size() || message[i] != ':') return 0;
  const size_t digits_begin = ++i;
  while (i < message.size() && std::isdigit(static_cast<unsigned char>(message[i]))) ++i;
  if (i == digits_begin || i >= message.size()) return 0;
  if (message[i] == ']') return i + 1 - at;
  if (message.compare(i, 2, ", ") != 0) return 0;
  // The condition is source text: its own brackets (a[i]) are balanced.
  int depth = 0;
  for (i += 2; i < message.size(); ++i) {
    if (message[i] == '[') {
      ++depth;
    } else if (message[i] == ']') {
      if (depth == 0) return i + 1 - at;
      --depth;
    }
  }
  return 0;  // never closes: not a tag of ours
}

std::atomic<bool> debug_messages{false};

}  // namespace

std::string StripSourceTags(std::string_view message) {
  std::string out;
  out.reserve(message.size());
  for (size_t i = 0; i < message.size();) {
    if (const size_t length = SourceTagLength(message, i); length > 0) {
      i += length;
    } else {
      out += message[i++];
    }
  }
  return out;
}

bool DebugMessages() {
  if (debug_messages.load(std::memory_order_relaxed)) return true;
  const char* env = std::getenv("STEREODET_DEBUG");
  return env != nullptr && env[0] != '\0' && std::strcmp(env, "0") != 0;
}

void SetDebugMessages(bool on) { debug_messages.store(on, std::memory_order_relaxed); }

std::string UserMessage(const std::exception& error) {
  return DebugMessages() ? std::string(error.what()) : StripSourceTags(error.what());
}

ParseError::ParseError(std::string file, int line, std::string field, std::string message)
    : std::runtime_error(FormatParseError(file, line, field, message)),
      file_(std::move(file)),
      line_(line),
      field_(std::move(field)),
      message_(std::move(message)) {}

namespace internal {

CheckFailure::CheckFailure(ErrorKind kind, const char* condition, const char* file, int line)
    : kind_(kind),
      condition_(condition),
      file_(file),
      line_(line),
      uncaught_at_start_(std::uncaught_exceptions()) {}

CheckFailure::~CheckFailure() noexcept(false) {
  // Destroyed during unwinding: building the message threw (e.g. a streamed call whose own check
  // failed). Throwing now would call std::terminate; let that exception carry the error instead.
  if (std::uncaught_exceptions() > uncaught_at_start_) return;
  std::string message = stream_.str();
  // Unconditional throws pass "false" as the condition; it says nothing, so leave it out.
  const bool has_condition = std::strcmp(condition_, "false") != 0;
  if (message.empty())
    message = has_condition ? std::string("check failed: ") + condition_ : "error";
  const char* base = std::strrchr(file_, '/');
  message += " [" + std::string(base != nullptr ? base + 1 : file_) + ":" + std::to_string(line_);
  if (has_condition) message += std::string(", ") + condition_;
  message += "]";
  if (kind_ == ErrorKind::kInvalidArgument) throw std::invalid_argument(message);
  throw std::runtime_error(message);
}

}  // namespace internal
}  // namespace stereodet
