// memory_budget_test.cpp — the budget check every stage shares (core/base/memory_budget.h).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/base/errors.h"
#include "core/base/memory_budget.h"

namespace vdb_shell {
namespace {

TEST(MemoryBudget, GiBAreBytesExactly) {
  EXPECT_EQ(budget_bytes(8.0), std::size_t{8} << 30);
  EXPECT_EQ(budget_bytes(0.5), std::size_t{1} << 29);
  EXPECT_EQ(budget_bytes(0.0), 0u);
  EXPECT_EQ(budget_bytes(-1.0), 0u);
  // A byte count over 2^30 round-trips: what the tests and the report rely on.
  const std::size_t bytes = 123456789;
  EXPECT_EQ(budget_bytes(double(bytes) / kBytesPerGiB), bytes);
  EXPECT_GT(budget_bytes(1e30), std::size_t{1} << 60);  // saturates, no overflow
}

TEST(MemoryBudget, AnEstimateUpToTheBudgetPassesOneByteMoreThrows) {
  const std::size_t budget = std::size_t{3} << 29;  // 1.5 GiB
  EXPECT_NO_THROW(check_memory_budget("trace", budget, budget, "x", "y"));
  EXPECT_NO_THROW(check_memory_budget("trace", 0, budget, "x", "y"));
  EXPECT_THROW(check_memory_budget("trace", budget + 1, budget, "x", "y"), ResourceError);
}

TEST(MemoryBudget, MessageNamesStageEstimateWhatBudgetAndRemedy) {
  try {
    check_memory_budget("validity", std::size_t{3} << 30, std::size_t{1} << 30,
                        "the validity search (12 prisms)",
                        "give fewer faces or raise --max-memory");
    FAIL() << "expected ResourceError";
  } catch (const ResourceError& e) {
    EXPECT_EQ(std::string(e.what()),
              "validity: about 3 GiB estimated for the validity search (12 prisms), more than "
              "--max-memory 1 GiB; give fewer faces or raise --max-memory");
  }
  try {  // the budget comes back as the user gave it
    check_memory_budget("trace", std::size_t{1} << 30, budget_bytes(0.07), "t", "r");
    FAIL() << "expected ResourceError";
  } catch (const ResourceError& e) {
    EXPECT_NE(std::string(e.what()).find("more than --max-memory 0.07 GiB;"), std::string::npos)
        << e.what();
  }
}

TEST(MemoryBudget, BytesOfCountCapacities) {
  std::vector<double> v;
  v.reserve(10);
  v.push_back(1.0);
  EXPECT_EQ(bytes_of(v), 10 * sizeof(double));
  std::vector<std::vector<int>> vv(2);
  vv[1].reserve(4);
  EXPECT_EQ(bytes_of(vv), 2 * sizeof(std::vector<int>) + 4 * sizeof(int));
}

}  // namespace
}  // namespace vdb_shell
