// format_reader.cpp — the cursors, number parsing and errors the surface readers share.
#include "core/read/format_reader.h"

#include <charconv>
#include <cstdlib>
#include <cstring>

#include "core/base/errors.h"

namespace vdb_shell::read_detail {

bool Lines::next(std::string_view& line) {
  if (pos_ >= text_.size()) return false;
  const std::size_t end = text_.find('\n', pos_);
  const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
  line = text_.substr(pos_, stop - pos_);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  pos_ = end == std::string_view::npos ? text_.size() : end + 1;
  ++next_no_;
  return true;
}

std::vector<std::string_view> words(std::string_view line, char comment, std::size_t max) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (out.size() < max) {
    while (i < line.size() && is_blank(line[i])) ++i;
    if (i == line.size() || (comment != '\0' && line[i] == comment)) break;
    const std::size_t start = i;
    while (i < line.size() && !is_blank(line[i]) && !(comment != '\0' && line[i] == comment)) ++i;
    out.push_back(line.substr(start, i - start));
  }
  return out;
}

bool Tokens::next(std::string_view& word) {
  while (pos_ < text_.size() && (is_blank(text_[pos_]) || text_[pos_] == '\n')) {
    if (text_[pos_] == '\n') ++line_no_;
    ++pos_;
  }
  if (pos_ == text_.size()) return false;
  const std::size_t start = pos_;
  while (pos_ < text_.size() && !is_blank(text_[pos_]) && text_[pos_] != '\n') ++pos_;
  word = text_.substr(start, pos_ - start);
  return true;
}

void Tokens::skip_line() {
  while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
}

bool parse_number(std::string_view word, double& value) {
  const bool plus = !word.empty() && word[0] == '+';
  if (plus) word.remove_prefix(1);
  if (word.empty() || (plus && word[0] == '-')) return false;
  const char* end = word.data() + word.size();
  const auto [ptr, ec] = std::from_chars(word.data(), end, value);
  if (ptr != end) return false;
  if (ec == std::errc::result_out_of_range) {  // 1e-400 is 0; 1e400 is not finite
    value = std::strtod(std::string(word).c_str(), nullptr);
    return true;
  }
  return ec == std::errc();
}

bool leading_integer(std::string_view word, long long& value) {
  if (!word.empty() && word[0] == '+') word.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(word.data(), word.data() + word.size(), value);
  return ec == std::errc() && ptr != word.data();
}

bool parse_integer(std::string_view word, long long& value) {
  if (!word.empty() && word[0] == '+') word.remove_prefix(1);
  const char* end = word.data() + word.size();
  const auto [ptr, ec] = std::from_chars(word.data(), end, value);
  return ec == std::errc() && ptr == end && !word.empty();
}

std::string quoted(std::string_view text, std::size_t max) {
  return "'" + std::string(text.substr(0, max)) + (text.size() > max ? "...'" : "'");
}

void fail(const std::string& name, const std::string& what, const std::string& fix) {
  throw InputError(name + ": " + what + " — fix: " + fix);
}

void BadCoordinates::check(bool readable, const Vec3d& p, const std::string& where,
                           std::string_view text) {
  if (readable && is_finite(p)) return;
  if (++count_ <= 3) first_.push_back(where + ": " + quoted(text, 60));
}

void BadCoordinates::throw_if_any(const std::string& name) const {
  if (count_ == 0) return;
  std::string list;
  for (const std::string& b : first_) list += (list.empty() ? "" : "; ") + b;
  fail(name,
       std::to_string(count_) + " vertices with NaN/Inf or unreadable coordinates, first: " + list,
       "re-export the mesh with finite coordinates");
}

std::size_t PositionWelder::hash(const Vec3d& p) const {
  std::uint64_t h = 0x9e3779b97f4a7c15ull;
  for (int k = 0; k < 3; ++k) {
    const double v = p[k] == 0.0 ? 0.0 : p[k];  // -0 and 0 are one position
    std::uint64_t bits = 0;
    std::memcpy(&bits, &v, sizeof bits);
    h ^= bits + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
  }
  h ^= h >> 29;
  h *= 0xbf58476d1ce4e5b9ull;
  h ^= h >> 32;
  return static_cast<std::size_t>(h);
}

void PositionWelder::grow() {
  table_.assign(table_.empty() ? 1024 : table_.size() * 2, -1);
  const std::size_t mask = table_.size() - 1;
  for (std::size_t i = 0; i < points_.size(); ++i) {
    std::size_t slot = hash(points_[i]) & mask;
    while (table_[slot] >= 0) slot = (slot + 1) & mask;
    table_[slot] = static_cast<std::int64_t>(i);
  }
}

std::int64_t PositionWelder::index(const Vec3d& p) {
  if (2 * (points_.size() + 1) > table_.size()) grow();
  const std::size_t mask = table_.size() - 1;
  std::size_t slot = hash(p) & mask;
  for (; table_[slot] >= 0; slot = (slot + 1) & mask) {
    const Vec3d& q = points_[static_cast<std::size_t>(table_[slot])];
    if (q.x == p.x && q.y == p.y && q.z == p.z) return table_[slot];
  }
  table_[slot] = static_cast<std::int64_t>(points_.size());
  points_.push_back(p);
  return table_[slot];
}

}  // namespace vdb_shell::read_detail
