// text_out.h — buffered, locale-independent text output for the writers (core/write): numbers
// through std::to_chars, doubles with 17 significant digits (every double reads back exactly).
// Internal to core/write.
#pragma once

#include <charconv>
#include <ostream>
#include <string>
#include <string_view>

#include "core/base/vec3.h"

namespace vdb_shell {

/// Appends text to a buffer and hands it to the stream in chunks.
class TextOut {
 public:
  explicit TextOut(std::ostream& os) : os_(os) { buffer_.reserve(kChunk + 512); }
  TextOut(const TextOut&) = delete;
  TextOut& operator=(const TextOut&) = delete;

  TextOut& str(std::string_view s) {
    buffer_.append(s.data(), s.size());
    return maybe_flush();
  }
  TextOut& ch(char c) {
    buffer_.push_back(c);
    return maybe_flush();
  }
  TextOut& real(double v) {
    char tmp[64];
    const auto r = std::to_chars(tmp, tmp + sizeof(tmp), v, std::chars_format::general, 17);
    buffer_.append(tmp, r.ptr);
    return maybe_flush();
  }
  TextOut& integer(long long v) {
    char tmp[32];
    const auto r = std::to_chars(tmp, tmp + sizeof(tmp), v);
    buffer_.append(tmp, r.ptr);
    return maybe_flush();
  }
  TextOut& point(const Vec3d& p) { return real(p.x).ch(' ').real(p.y).ch(' ').real(p.z); }
  /// Writes everything buffered to the stream.
  void flush() {
    os_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
    buffer_.clear();
  }

 private:
  static constexpr std::size_t kChunk = 1 << 16;
  TextOut& maybe_flush() {
    if (buffer_.size() >= kChunk) flush();
    return *this;
  }
  std::ostream& os_;
  std::string buffer_;
};

}  // namespace vdb_shell
