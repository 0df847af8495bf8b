// memory_budget.h — the memory budget (--max-memory) every stage checks before it allocates.
//
// Each stage of build_shell() estimates its peak before it allocates anything that scales with
// the input: what it allocates itself, plus what earlier stages still hold, plus the program
// (kProgramBytes). An estimate above the budget throws ResourceError naming the stage, the
// estimate, what it is for and what lowers it (CLI exit code 3); nothing has been written then.
// The estimates are upper bounds of measured peaks within about 2x (the constants next to each
// stage's estimate say what they were calibrated on).
//
// Units: bytes throughout; the budget is given in GiB (2^30 bytes), as --max-memory is.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace vdb_shell {

/// Bytes of one GiB (--max-memory's unit).
inline constexpr double kBytesPerGiB = 1024.0 * 1024.0 * 1024.0;

/// The program itself, counted in every estimate: code, libraries and the allocator's slack
/// (measured at 40-45 MB resident before any input; the fields' estimate counts the same).
inline constexpr std::size_t kProgramBytes = std::size_t{64} << 20;

/// `gib` GiB in bytes (saturating; a non-positive or NaN budget gives 0).
std::size_t budget_bytes(double gib);

/// "0.0627 GiB": bytes as GiB with 3 significant digits, for messages.
std::string format_gib(double bytes);

/// \throw ResourceError
///   "<stage>: about X GiB estimated for <what>, more than --max-memory G GiB; <remedy>"
///   when estimated_bytes > budget (bytes). `what` says what the estimate covers, with its
///   counts; `remedy` what lowers it, ending with "or raise --max-memory".
void check_memory_budget(const std::string& stage, std::size_t estimated_bytes, std::size_t budget,
                         const std::string& what, const std::string& remedy);

/// Bytes a vector's buffer holds (its capacity).
template <class T>
std::size_t bytes_of(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}

/// Bytes a vector of vectors holds: the outer buffer and every inner one.
template <class T>
std::size_t bytes_of(const std::vector<std::vector<T>>& v) {
  std::size_t bytes = v.capacity() * sizeof(std::vector<T>);
  for (const std::vector<T>& inner : v) bytes += bytes_of(inner);
  return bytes;
}

}  // namespace vdb_shell
