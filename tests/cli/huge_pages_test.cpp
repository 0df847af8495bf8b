// huge_pages_test.cpp — the vdb_shell program's operator new (cli/huge_pages.cpp), in a test
// binary of its own (tests/CMakeLists.txt): large blocks are aligned to a huge page and carry
// the kernel's huge-page advice, read back from /proc/self/smaps.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

namespace {

constexpr std::size_t kHugePage = std::size_t{2} << 20;

// The VmFlags line and the AnonHugePages size (kB) of the mapping holding `address`, from
// /proc/self/smaps; empty flags when no mapping holds it.
struct Mapping {
  std::string flags;
  long anon_huge_kb = -1;
};
Mapping mapping_of(std::uintptr_t address) {
  std::ifstream smaps("/proc/self/smaps");
  Mapping m;
  bool inside = false;
  for (std::string line; std::getline(smaps, line);) {
    std::uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> lo >> dash >> hi && dash == '-') {  // a mapping's first line
      if (inside) break;
      inside = lo <= address && address < hi;
      continue;
    }
    if (!inside) continue;
    if (line.rfind("AnonHugePages:", 0) == 0) m.anon_huge_kb = std::stol(line.substr(14));
    if (line.rfind("VmFlags:", 0) == 0) m.flags = line.substr(8) + " ";
  }
  return m;
}

TEST(HugePages, LargeBlocksAreAlignedAndAdvised) {
#ifndef VDB_SHELL_HUGE_PAGES
  GTEST_SKIP() << "sanitizer build: its runtime's operator new";
#else
  if (!std::filesystem::exists("/sys/kernel/mm/transparent_hugepage"))
    GTEST_SKIP() << "the kernel has no transparent huge pages";
  const std::size_t size = 16 * kHugePage + 123;
  const std::unique_ptr<char[]> block(new char[size]);
  const auto address = reinterpret_cast<std::uintptr_t>(block.get());
  EXPECT_EQ(address % kHugePage, 0u);
  std::memset(block.get(), 1, size);  // touched: the pages exist
  const Mapping m = mapping_of(address);
  ASSERT_FALSE(m.flags.empty()) << "no mapping holds the block";
  EXPECT_NE(m.flags.find(" hg "), std::string::npos) << "VmFlags:" << m.flags;
  // Whether the kernel found free huge pages is its business: reported, not asserted.
  RecordProperty("anon_huge_kb", std::to_string(m.anon_huge_kb));

  // A small block is plain malloc()'s, not advised.
  const std::unique_ptr<char[]> small(new char[4096]);
  small[0] = 1;
  EXPECT_EQ(mapping_of(reinterpret_cast<std::uintptr_t>(small.get())).flags.find(" hg "),
            std::string::npos);
#endif
}

}  // namespace
