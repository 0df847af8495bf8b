// The --html option: one page per run (or per input and an index in batch mode), written with
// the other outputs or not at all.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "assets/shapes.h"
#include "core/write/shell_writers.h"
#include "tests/test_support.h"

namespace vdb_shell {
namespace {

using test::TempDir;

using test::cli;
using test::CliRun;

TEST(CliHtml, APageWithEveryPictureNextToTheShell) {
  TempDir dir;
  write_surface(dir.file("horn.obj"), make_shape("horn"));
  const CliRun r = cli({dir.file("horn.obj"), "-o", dir.file("horn.vtu"), "--html",
                        dir.file("horn.html"), "-r", "48", "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string page = test::read_text(dir.file("horn.html"));
  EXPECT_EQ(page.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_EQ(test::count_of(page, "<img class=\"pic\""), 8u);  // 3 cut-aways, 2 + 2 surfaces, traces
  EXPECT_EQ(test::count_of(page, "<svg"), 5u);                // 3 sections, 2 histograms
  EXPECT_EQ(test::count_of(page, "src=\"http"), 0u);          // nothing fetched from anywhere
  EXPECT_NE(page.find(dir.file("horn.vtu")), std::string::npos);  // names the shell it shows
  // With --progress the page is a seventh stage.
  const CliRun p = cli({dir.file("horn.obj"), "-o", dir.file("horn.vtu"), "--html",
                        dir.file("horn.html"), "-r", "48", "--progress"});
  ASSERT_EQ(p.code, 0) << p.err;
  EXPECT_NE(p.err.find("[6/7] write ..."), std::string::npos) << p.err;
  EXPECT_NE(p.err.find("[7/7] html ..."), std::string::npos) << p.err;
}

TEST(CliHtml, BadPathsExit2BeforeAnyWork) {
  TempDir dir;
  write_surface(dir.file("horn.obj"), make_shape("horn"));
  const CliRun ext =
      cli({dir.file("horn.obj"), "-o", dir.file("s.vtu"), "--html", dir.file("r.htm")});
  EXPECT_EQ(ext.code, 2);
  EXPECT_NE(ext.err.find("--html " + dir.file("r.htm") + ": must end in .html"), std::string::npos)
      << ext.err;
  const CliRun alone = cli({dir.file("horn.obj"), "--html", dir.file("r.html")});
  EXPECT_EQ(alone.code, 2);
  EXPECT_NE(alone.err.find("give -o OUTPUT"), std::string::npos) << alone.err;
  const CliRun folder =
      cli({dir.file("horn.obj"), "-o", dir.file("s.vtu"), "--html", dir.file("no/r.html")});
  EXPECT_EQ(folder.code, 2);
  EXPECT_NE(folder.err.find("does not exist"), std::string::npos) << folder.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("s.vtu")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("r.html")));
}

TEST(CliHtml, AFailedRunWritesNoPage) {
  TempDir dir;
  SurfaceMesh open = make_shape("sphere");
  open.triangles.pop_back();
  write_surface(dir.file("open.obj"), open);
  const CliRun r =
      cli({dir.file("open.obj"), "-o", dir.file("s.vtu"), "--html", dir.file("r.html")});
  EXPECT_EQ(r.code, 2);
  EXPECT_FALSE(std::filesystem::exists(dir.file("r.html")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("s.vtu")));
}

TEST(CliHtml, APageOverTheMemoryBudgetExits3AndWritesNothing) {
  TempDir dir;
  write_surface(dir.file("sphere.obj"), make_shape("sphere"));
  const std::vector<std::string> run = {
      dir.file("sphere.obj"), "-r", "32", "-o", dir.file("s.vtu"), "--html",
      dir.file("s.html"),     "-q"};
  std::vector<std::string> with_report = run;
  with_report.insert(with_report.end(), {"--report", dir.file("r.json")});
  ASSERT_EQ(cli(with_report).code, 0);
  const auto memory = nlohmann::json::parse(test::read_text(dir.file("r.json")))["memory_gb"];
  double others = 0;
  for (const auto& [key, gib] : memory.items())
    if (key != "budget" && key != "write_html") others = std::max(others, gib.get<double>());
  const double html = memory["write_html"].get<double>();
  ASSERT_GT(html, others);  // the page's pictures outgrow every stage of this small run
  for (const char* f : {"s.vtu", "s.html", "r.json"}) std::filesystem::remove(dir.file(f));
  std::vector<std::string> tight = run;
  tight.insert(tight.end(), {"--max-memory", std::to_string((html + others) / 2)});
  const CliRun r = cli(tight);
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_EQ(r.err.rfind("vdb_shell: error: write: about ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("HTML report"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("s.vtu")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("s.html")));
}

TEST(CliHtml, BatchWritesAPagePerInputAndAnIndexRowForEach) {
  TempDir dir;
  write_surface(dir.file("horn.obj"), make_shape("horn"));
  write_surface(dir.file("box.obj"), make_shape("box"));
  SurfaceMesh open = make_shape("sphere");
  open.triangles.pop_back();
  write_surface(dir.file("open.obj"), open);
  const CliRun r = cli({dir.file("horn.obj"), dir.file("open.obj"), dir.file("box.obj"), "-o",
                        dir.file("shells"), "--html", dir.file("pages"), "-r", "32", "-q"});
  EXPECT_EQ(r.code, 2) << r.err;  // the open sphere is bad input
  for (const char* name : {"box.html", "horn.html", "index.html"})
    EXPECT_TRUE(std::filesystem::exists(dir.path() / "pages" / name)) << name;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "pages" / "open.html"));
  const std::string index = test::read_text((dir.path() / "pages" / "index.html").string());
  // One row per input in input order: two link their page with a thumbnail, one says why not.
  const std::regex rows("<tr><td>(<a href=\"([a-z]+)\\.html\"><img[^>]*></a>)?</td>");
  std::vector<std::string> linked;
  for (auto it = std::sregex_iterator(index.begin(), index.end(), rows);
       it != std::sregex_iterator(); ++it)
    linked.push_back((*it)[2].str());
  EXPECT_EQ(linked, (std::vector<std::string>{"horn", "", "box"}));
  EXPECT_EQ(test::count_of(index, "<td class=\"bad\" colspan=\"5\">error: "), 1u);
  EXPECT_NE(index.find("boundary edges"), std::string::npos);

  // A page named index would replace the index: refused before any work.
  write_surface(dir.file("index.obj"), make_shape("box"));
  const CliRun clash = cli(
      {dir.file("index.obj"), dir.file("box.obj"), "-o", dir.file("s2"), "--html", dir.file("p2")});
  EXPECT_EQ(clash.code, 2);
  EXPECT_NE(clash.err.find("an input named index"), std::string::npos) << clash.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("s2")));
}

}  // namespace
}  // namespace vdb_shell
