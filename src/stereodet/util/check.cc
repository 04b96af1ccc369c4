#include "stereodet/util/check.h"

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
}  // namespace

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
