// Errors and checks: exceptions with context, never aborts.
//
//   STEREODET_CHECK(options.block_size % 2 == 1) << "block_size must be odd, got " << block_size;
//       throws std::invalid_argument (the caller's mistake) when the condition is false.
//   STEREODET_CHECK_IO(file.good()) << "cannot open " << path;
//       throws std::runtime_error (I/O, bad files, the outside world).
//   STEREODET_THROW_IO() << "...";  STEREODET_THROW_ARG() << "...";
//       throw unconditionally.
//
//   STEREODET_CHECK_GE(calibration_bins, 1) << "(--calibration-bins)";
//       comparison checks (_EQ, _NE, _LT, _LE, _GT, _GE, and _IO_ variants) that describe
//       themselves: "calibration_bins = 0, must be >= 1 (--calibration-bins)". Each operand is
//       evaluated once.
//
// The message is assembled with operator<< and the exception is thrown when the full expression
// ends, so the streamed operands are evaluated only when the check fails. The source location and
// the failed condition are appended for developers. If evaluating a streamed operand itself throws,
// that exception propagates and the check's own is dropped (never std::terminate).
//
// Users read messages without those tags: front ends print UserMessage(error), which strips them
// unless debug messages are on (`--debug`, or the environment variable STEREODET_DEBUG).
#ifndef STEREODET_UTIL_CHECK_H_
#define STEREODET_UTIL_CHECK_H_

#include <exception>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>

namespace stereodet {

// An error in an input file: names the file, the 1-based line (0 if not line-based) and the field.
// what() reads "FILE:LINE: field FIELD: MESSAGE" so a user can jump to it.
class ParseError : public std::runtime_error {
 public:
  ParseError(std::string file, int line, std::string field, std::string message);

  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& field() const { return field_; }
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  int line_;
  std::string field_;
  std::string message_;
};

// `message` without the developer tags that failed checks append: every " [NAME.cc:LINE]" and
// " [NAME.cc:LINE, CONDITION]" (NAME a file name ending in .cc, .h or .cpp; CONDITION with its
// brackets balanced) is removed, wherever it sits (messages nest: a caller may prefix or wrap a
// check's message). Anything else in brackets, a tag whose brackets never close included, stays.
std::string StripSourceTags(std::string_view message);

// Whether users see the source tags: on after SetDebugMessages(true), or when the environment
// variable STEREODET_DEBUG is set to anything but "" or "0" (read on every call). Off by default.
// Thread-safe.
bool DebugMessages();
void SetDebugMessages(bool on);

// error.what() as a user should read it: StripSourceTags unless DebugMessages().
std::string UserMessage(const std::exception& error);

namespace internal {

enum class ErrorKind { kInvalidArgument, kRuntime };

// Collects a message and throws from its destructor. Only ever a temporary inside the check macros.
class CheckFailure {
 public:
  CheckFailure(ErrorKind kind, const char* condition, const char* file, int line);
  CheckFailure(const CheckFailure&) = delete;
  CheckFailure& operator=(const CheckFailure&) = delete;
  // Throws, unless an exception thrown while the message was being built is already in flight.
  ~CheckFailure() noexcept(false);

  template <typename T>
  CheckFailure& operator<<(const T& value) {
    stream_ << value;
    return *this;
  }

 private:
  ErrorKind kind_;
  const char* condition_;
  const char* file_;
  int line_;
  int uncaught_at_start_;
  std::ostringstream stream_;
};

// The message of a failed comparison check, or nothing when `holds`: "A = 0, must be >= 1", or
// "A = 0, must be >= B (3)" where B is not a literal.
template <typename T, typename U>
std::optional<std::string> CheckOpMessage(bool holds, const T& a, const U& b, const char* text_a,
                                          const char* op, const char* text_b) {
  if (holds) return std::nullopt;
  std::ostringstream os;
  os << text_a << " = " << a << ", must be " << op << ' ';
  std::ostringstream b_value;
  b_value << b;
  os << text_b;
  if (b_value.str() != text_b) os << " (" << b_value.str() << ")";
  return os.str();
}

// Lets the macros be used as a statement followed by `<< ...` without dangling-else problems.
struct Voidify {
  void operator&(const CheckFailure&) {}
};

}  // namespace internal
}  // namespace stereodet

#define STEREODET_INTERNAL_CHECK(kind, cond)  \
  (cond) ? (void)0                            \
         : ::stereodet::internal::Voidify() & \
               ::stereodet::internal::CheckFailure((kind), #cond, __FILE__, __LINE__)

#define STEREODET_CHECK(cond) \
  STEREODET_INTERNAL_CHECK(::stereodet::internal::ErrorKind::kInvalidArgument, cond)
#define STEREODET_CHECK_IO(cond) \
  STEREODET_INTERNAL_CHECK(::stereodet::internal::ErrorKind::kRuntime, cond)
#define STEREODET_THROW_ARG() \
  STEREODET_INTERNAL_CHECK(::stereodet::internal::ErrorKind::kInvalidArgument, false)
#define STEREODET_THROW_IO() \
  STEREODET_INTERNAL_CHECK(::stereodet::internal::ErrorKind::kRuntime, false)

// A for statement that runs its body (the throwing CheckFailure) once when the comparison fails, so
// `<< ...` can follow and the operands are evaluated once.
#define STEREODET_INTERNAL_CHECK_OP(kind, op, a, b)                                   \
  for (std::optional<std::string> stereodet_check_op_message_ =                       \
           [&](const auto&x, const auto&y) {                                          \
             return ::stereodet::internal::CheckOpMessage(x op y, x, y, #a, #op, #b); \
           }((a), (b));                                                               \
       stereodet_check_op_message_.has_value(); stereodet_check_op_message_.reset())  \
  ::stereodet::internal::CheckFailure((kind), #a " " #op " " #b, __FILE__, __LINE__)  \
      << *stereodet_check_op_message_

#define STEREODET_INTERNAL_ARG ::stereodet::internal::ErrorKind::kInvalidArgument
#define STEREODET_INTERNAL_IO ::stereodet::internal::ErrorKind::kRuntime
#define STEREODET_CHECK_EQ(a, b) STEREODET_INTERNAL_CHECK_OP(STEREODET_INTERNAL_ARG, ==, a, b)
#define STEREODET_CHECK_NE(a, b) STEREODET_INTERNAL_CHECK_OP(STEREODET_INTERNAL_ARG, !=, a, b)
#define STEREODET_CHECK_LT(a, b) STEREODET_INTERNAL_CHECK_OP(STEREODET_INTERNAL_ARG, <, a, b)
#define STEREODET_CHECK_LE(a, b) STEREODET_INTERNAL_CHECK_OP(STEREODET_INTERNAL_ARG, <=, a, b)
#define STEREODET_CHECK_GT(a, b) STEREODET_INTERNAL_CHECK_OP(STEREODET_INTERNAL_ARG, >, a, b)
#define STEREODET_CHECK_GE(a, b) STEREODET_INTERNAL_CHECK_OP(STEREODET_INTERNAL_ARG, >=, a, b)
#define STEREODET_CHECK_IO_EQ(a, b) STEREODET_INTERNAL_CHECK_OP(STEREODET_INTERNAL_IO, ==, a, b)
#define STEREODET_CHECK_IO_LE(a, b) STEREODET_INTERNAL_CHECK_OP(STEREODET_INTERNAL_IO, <=, a, b)
#define STEREODET_CHECK_IO_GE(a, b) STEREODET_INTERNAL_CHECK_OP(STEREODET_INTERNAL_IO, >=, a, b)

#endif  // STEREODET_UTIL_CHECK_H_
