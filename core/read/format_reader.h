// format_reader.h — what the surface readers (read_obj.cpp, read_off.cpp, read_ply.cpp,
// read_stl.cpp) share: cursors over a file's bytes that hand out lines and words with their line
// numbers, exact locale-free number parsing, and the errors they throw.
//
// Every reader works on the whole file in memory and checks what a header announces against the
// bytes that are there before it reserves anything, so no reader allocates more than a small
// multiple of the file's size.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/base/vec3.h"
#include "core/read/polygon_soup.h"

namespace vdb_shell::read_detail {

inline bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

/// The lines of a text from `offset` on, one at a time, with their 1-based numbers.
class Lines {
 public:
  explicit Lines(std::string_view text, std::size_t offset = 0, std::size_t first_line = 1)
      : text_(text), pos_(offset), next_no_(first_line) {}
  /// The next line without its end of line; false at the end of the text.
  bool next(std::string_view& line);
  /// The number of the line next() returned last.
  std::size_t line_no() const { return next_no_ - 1; }
  /// The byte after the line next() returned last (its end of line included).
  std::size_t offset() const { return pos_; }

 private:
  std::string_view text_;
  std::size_t pos_;
  std::size_t next_no_;
};

/// The blank-separated words of `line` before `comment` ('\0': no comment character), at most
/// `max` of them.
std::vector<std::string_view> words(std::string_view line, char comment = '#',
                                    std::size_t max = SIZE_MAX);

/// The blank-separated words of a text across its lines, with the line each is on.
class Tokens {
 public:
  explicit Tokens(std::string_view text, std::size_t offset = 0, std::size_t first_line = 1)
      : text_(text), pos_(offset), line_no_(first_line) {}
  /// The next word; false at the end of the text.
  bool next(std::string_view& word);
  /// The line of the word next() returned last (or of the end of the text).
  std::size_t line_no() const { return line_no_; }
  /// Skips the rest of the current line.
  void skip_line();

 private:
  std::string_view text_;
  std::size_t pos_;
  std::size_t line_no_;
};

/// `word` as a whole is a number (a leading '+' allowed); "nan" and "inf" parse.
bool parse_number(std::string_view word, double& value);
/// `word` as a whole is an integer that fits a long long.
bool parse_integer(std::string_view word, long long& value);
/// `word` starts with an integer that fits a long long ("12/4/7" gives 12).
bool leading_integer(std::string_view word, long long& value);

/// `text` in quotes, cut to `max` characters.
std::string quoted(std::string_view text, std::size_t max = 24);

/// Throws InputError "`name`: `what` — fix: `fix`".
[[noreturn]] void fail(const std::string& name, const std::string& what,
                       const std::string& fix = "re-export the mesh");

/// Vertices whose coordinates are unreadable or not finite: collected while reading (the first
/// three are named) and thrown together at the end.
class BadCoordinates {
 public:
  /// Records the vertex `where` ("vertex 3 (line 5)") unless `p` is finite and `readable`.
  void check(bool readable, const Vec3d& p, const std::string& where, std::string_view text);
  /// Throws InputError naming the first ones if there were any.
  void throw_if_any(const std::string& name) const;

 private:
  std::vector<std::string> first_;
  std::size_t count_ = 0;
};

/// One index per distinct position, in order of first appearance (STL stores each triangle's
/// corners; 0 and -0 are one position).
class PositionWelder {
 public:
  explicit PositionWelder(std::vector<Vec3d>& points) : points_(points) {}
  std::int64_t index(const Vec3d& p);

 private:
  std::size_t hash(const Vec3d& p) const;
  void grow();
  std::vector<Vec3d>& points_;
  std::vector<std::int64_t> table_;  ///< open addressing: index into points_, -1 empty
};

// The readers, each given a whole file's bytes; `name` is the path for messages.
PolygonSoup read_obj(std::string_view bytes, const std::string& name);
PolygonSoup read_off(std::string_view bytes, const std::string& name);
PolygonSoup read_ply(std::string_view bytes, const std::string& name);
PolygonSoup read_stl(std::string_view bytes, const std::string& name);

}  // namespace vdb_shell::read_detail
