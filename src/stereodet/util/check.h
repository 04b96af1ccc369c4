// Errors and checks: exceptions with context, never aborts.
//
//   STEREODET_CHECK(options.block_size % 2 == 1) << "block_size must be odd, got " << block_size;
//       throws std::invalid_argument (the caller's mistake) when the condition is false.
//   STEREODET_CHECK_IO(file.good()) << "cannot open " << path;
//       throws std::runtime_error (I/O, bad files, the outside world).
//   STEREODET_THROW_IO() << "...";  STEREODET_THROW_ARG() << "...";
//       throw unconditionally.
//
// The message is assembled with operator<< and the exception is thrown when the full expression ends,
// so the streamed operands are evaluated only when the check fails. Every message is prefixed with the
// failed condition; the source location is appended for developers.
#ifndef STEREODET_UTIL_CHECK_H_
#define STEREODET_UTIL_CHECK_H_

#include <sstream>
#include <stdexcept>
#include <string>

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

namespace internal {

enum class ErrorKind { kInvalidArgument, kRuntime };

// Collects a message and throws from its destructor. Only ever a temporary inside the check macros.
class CheckFailure {
 public:
  CheckFailure(ErrorKind kind, const char* condition, const char* file, int line);
  CheckFailure(const CheckFailure&) = delete;
  CheckFailure& operator=(const CheckFailure&) = delete;
  [[noreturn]] ~CheckFailure() noexcept(false);

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
  std::ostringstream stream_;
};

// Lets the macros be used as a statement followed by `<< ...` without dangling-else problems.
struct Voidify {
  void operator&(const CheckFailure&) {}
};

}  // namespace internal
}  // namespace stereodet

#define STEREODET_INTERNAL_CHECK(kind, cond)                                               \
  (cond) ? (void)0                                                                         \
         : ::stereodet::internal::Voidify() &                                              \
               ::stereodet::internal::CheckFailure((kind), #cond, __FILE__, __LINE__)

#define STEREODET_CHECK(cond) \
  STEREODET_INTERNAL_CHECK(::stereodet::internal::ErrorKind::kInvalidArgument, cond)
#define STEREODET_CHECK_IO(cond) \
  STEREODET_INTERNAL_CHECK(::stereodet::internal::ErrorKind::kRuntime, cond)
#define STEREODET_THROW_ARG() \
  STEREODET_INTERNAL_CHECK(::stereodet::internal::ErrorKind::kInvalidArgument, false)
#define STEREODET_THROW_IO() \
  STEREODET_INTERNAL_CHECK(::stereodet::internal::ErrorKind::kRuntime, false)

#endif  // STEREODET_UTIL_CHECK_H_
