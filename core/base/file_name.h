// file_name.h — what the tools read from a file name: its extension, compared case-insensitively.
#pragma once

#include <cctype>
#include <filesystem>
#include <string>

namespace vdb_shell {

/// The extension of `path` with its dot, lower-cased (".obj"; "" when there is none).
inline std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace vdb_shell
