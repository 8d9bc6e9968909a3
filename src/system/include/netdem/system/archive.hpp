#pragma once
// The one state archive of every solver (issue 26): a JSON document (nlohmann-json) with a format,
// a kind and a version, exact doubles (the shortest text that reads back to the same bits; an
// infinity as the string "inf" or "-inf", NaN refused), and a reader that checks every field at
// the door. Format and rules: docs/dynamic.md "State files" (and the state sections of
// docs/quasistatic.md and docs/staggered.md).
//
// Reading: Field is a value of the document with its place (the file name and the JSON pointer);
// its accessors check the type, the range and the array sizes and throw FieldError, a
// std::invalid_argument with the one-line message "FILE: POINTER: problem" (at most 80 characters
// of a bad input quoted). A type's from_json (found by ADL, e.g. the laws' Params and histories in
// law_json.hpp) reads through Field(j) and throws FieldError with the pointer inside the value;
// Field::get<T>() puts the file and the outer pointer in front.
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace netdem::sys {

using Json = nlohmann::json;

/// The format field of every archive; its version is per kind.
inline constexpr const char* kArchiveFormat = "netdem-state";
/// The deepest nesting parse_archive accepts (a state is at most 5 levels deep).
inline constexpr std::size_t kMaxArchiveDepth = 64;

/// A refused field: std::invalid_argument with what() = "FILE: POINTER: problem" ("POINTER:
/// problem" without a file).
class FieldError : public std::invalid_argument {
 public:
  FieldError(std::string file, std::string pointer, std::string problem);
  const std::string& file() const { return file_; }
  const std::string& pointer() const { return pointer_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string file_, pointer_, problem_;
};

/// At most 80 printable characters of `s` (control characters as '?', "..." if cut).
std::string quote(std::string_view s);

/// A double for the archive: a number for a finite value, "inf" / "-inf" for an infinity; NaN
/// throws std::invalid_argument naming `what`.
Json real_json(double v, std::string_view what);

class Field {
 public:
  /// The whole document `j` of `file` (empty for a value inside a from_json).
  explicit Field(const Json& j, std::string file = {}, std::string pointer = {});

  const Json& json() const { return *j_; }
  const std::string& file() const { return file_; }
  const std::string& pointer() const { return pointer_; }  ///< "" for the document itself
  [[noreturn]] void fail(const std::string& problem) const;

  /// The member `key` of an object (refused: not an object, or no such member).
  Field operator[](std::string_view key) const;
  /// Element k of an array (the caller checked the size).
  Field operator[](std::size_t k) const;
  bool has(std::string_view key) const;
  /// An object whose members are all in `allowed` (an unknown member is refused by name).
  void object(std::initializer_list<std::string_view> allowed) const;
  /// An array of exactly n elements.
  void array(std::size_t n) const;
  /// An array of lo .. hi elements; returns its size.
  std::size_t array(std::size_t lo, std::size_t hi) const;

  /// A finite number (an integer number is read as a double).
  double real() const;
  /// A finite number in [lo, hi].
  double real(double lo, double hi) const;
  /// A number or "inf" / "-inf" (NaN is refused), in [lo, hi].
  double extended_real(double lo, double hi) const;
  /// An integer number in [lo, hi].
  std::int64_t integer(std::int64_t lo, std::int64_t hi) const;
  bool boolean() const;
  std::string string() const;
  /// A string equal to one of `choices`; returns its index.
  std::size_t choice(std::initializer_list<std::string_view> choices) const;
  std::size_t choice(std::span<const std::string_view> choices) const;

  /// T from this value through its from_json (ADL); a FieldError inside gets this place in front,
  /// any other std::exception becomes a FieldError at this place.
  template <class T>
  T get() const {
    T v{};
    try {
      from_json(*j_, v);
    } catch (const FieldError& e) {
      throw FieldError(file_, pointer_ + e.pointer(), e.problem());
    } catch (const std::exception& e) {
      fail(e.what());
    }
    return v;
  }

 private:
  const Json* j_;
  std::string file_, pointer_;
};

/// Parses the text of an archive; a syntax error is one FieldError line with the byte position.
Json parse_archive(std::string_view text, const std::string& file);
/// The header check: format kArchiveFormat, `kind`, version in [1, max_version]; returns the
/// version. An old text state (a first line "# ...") is refused with how to convert it.
int check_header(const Field& root, std::string_view kind, int max_version);
/// A new document with the header fields.
Json make_archive(std::string_view kind, int version);
/// The text of an archive (compact JSON, one line, then a newline).
std::string dump_archive(const Json& j);

/// Reads `path` whole; a missing file or a folder is a one-line std::invalid_argument naming
/// `what` (e.g. "state file").
std::string read_text_file(const std::string& path, std::string_view what);
/// Writes `text` to `path` atomically (PATH.tmp, then a rename); std::runtime_error naming the
/// file and `what` (e.g. "state file") on failure.
void write_text_file(const std::string& path, std::string_view text, std::string_view what);

}  // namespace netdem::sys
