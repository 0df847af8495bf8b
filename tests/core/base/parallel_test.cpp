// parallel_test.cpp — reduce_in_blocks() (core/base/parallel.h): the same floating-point sum for
// any thread count, equal to the blocks summed in order.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include "core/base/parallel.h"

namespace vdb_shell {
namespace {

TEST(Parallel, ReduceInBlocksIsTheSameSumForAnyThreadCount) {
  // Values of widely different magnitudes, so that the order of the additions shows in the sum.
  std::mt19937 random(11);
  std::uniform_real_distribution<double> exponent(-8.0, 8.0);
  std::vector<double> x(100'003);
  for (double& v : x) v = std::pow(10.0, exponent(random)) * (random() % 2 ? 1.0 : -1.0);
  const auto sum = [&] {
    return reduce_in_blocks(
        x.size(), 0.0, [&](std::size_t i) { return x[i]; },
        [](double a, double b) { return a + b; });
  };
  // The reference: blocks of 4096 summed in order, then the blocks in order.
  double expected = 0.0;
  for (std::size_t b = 0; b < x.size(); b += 4096) {
    double block = 0.0;
    for (std::size_t i = b; i < std::min(x.size(), b + 4096); ++i) block += x[i];
    expected += block;
  }
  double in_order = 0.0;
  for (const double v : x) in_order += v;
  ASSERT_NE(expected, in_order);  // the grouping shows in the last bits
  for (const int threads : {1, 2, 3, 8}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                              static_cast<std::size_t>(threads));
    EXPECT_EQ(sum(), expected) << threads << " threads";
  }
  EXPECT_EQ(reduce_in_blocks(
                0, 7.0, [](std::size_t) { return 1.0; }, [](double a, double b) { return a + b; }),
            7.0);
}

}  // namespace
}  // namespace vdb_shell
