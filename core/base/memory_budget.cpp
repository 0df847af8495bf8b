// memory_budget.cpp — the budget check every stage shares; see memory_budget.h.
#include "core/base/memory_budget.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "core/base/errors.h"

namespace vdb_shell {

std::size_t budget_bytes(double gib) {
  if (!(gib > 0.0)) return 0;
  const double bytes = gib * kBytesPerGiB;
  constexpr double kMax = double(std::numeric_limits<std::size_t>::max() / 2);
  return bytes >= kMax ? std::size_t(kMax) : static_cast<std::size_t>(bytes);
}

std::string format_gib(double bytes) {
  std::ostringstream s;
  s.precision(3);
  s << bytes / kBytesPerGiB << " GiB";
  return s.str();
}

void check_memory_budget(const std::string& stage, std::size_t estimated_bytes, std::size_t budget,
                         const std::string& what, const std::string& remedy) {
  if (estimated_bytes <= budget) return;
  std::ostringstream budget_gib;  // the user's figure back, as given (GiB are exact in binary)
  budget_gib.precision(6);
  budget_gib << double(budget) / kBytesPerGiB;
  throw ResourceError(stage + ": about " + format_gib(double(estimated_bytes)) + " estimated for " +
                      what + ", more than --max-memory " + budget_gib.str() + " GiB; " + remedy);
}

}  // namespace vdb_shell
