// browser_test.cpp — the --html page as a browser shows it: headless Chromium opens the page of a
// sphere's run, and the test checks its console stays silent and reads the screenshot back: one
// frame per picture at the picture's size, the sphere's silhouette at the area the picture's scale
// implies, cut-aways that are not blank, and quality bars in the proportions of --report's
// histogram. Skipped when Chromium is not installed ($VDB_SHELL_CHROMIUM names another binary).
#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/base/vec3.h"
#include "tests/test_support.h"

namespace vdb_shell::test {
namespace {

namespace fs = std::filesystem;

constexpr std::uint32_t kFrameColour = 0xc8c8c8;     // img.pic's border
constexpr std::uint32_t kQualityColour = 0x2f6db5;   // the quality histogram's bars
constexpr std::uint32_t kDihedralColour = 0x7d52b8;  // the dihedral histogram's bars
constexpr int kQualityBins = 20;
constexpr double kBinPitch = 26.5;  // the SVG's plot width 530 over 20 bins
constexpr int kPlotHeight = 208;    // the tallest bar's height

std::string quoted(const std::string& s) { return "'" + s + "'"; }

/// The Chromium to run: $VDB_SHELL_CHROMIUM when set (empty: none), else `chromium` on PATH;
/// "" when there is none.
std::string chromium_bin() {
  if (const char* env = std::getenv("VDB_SHELL_CHROMIUM")) return env;
  std::istringstream dirs(std::getenv("PATH") ? std::getenv("PATH") : "");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const fs::path candidate = fs::path(dir.empty() ? "." : dir) / "chromium";
    if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
  }
  return {};
}

/// Opens `page` in headless Chromium with a window of `width` x `height` and writes its
/// screenshot to `png`. The result's err is Chromium's log, console messages included. The
/// profile lives in `profile`, so runs never share one.
CommandResult screenshot(const fs::path& page, const fs::path& png, const fs::path& profile,
                         int width, int height) {
  return run_command(
      "timeout 60 " + quoted(chromium_bin()) +
      " --headless=new --no-sandbox --disable-gpu --disable-dev-shm-usage --hide-scrollbars"
      " --force-device-scale-factor=1 --enable-logging=stderr --v=0"
      " --user-data-dir=" +
      quoted(profile.string()) + " --window-size=" + std::to_string(width) + "," +
      std::to_string(height) + " --screenshot=" + quoted(png.string()) + " " +
      quoted("file://" + fs::absolute(page).string()));
}

/// The lines of Chromium's log that report a console message.
std::vector<std::string> console_lines(const std::string& log) {
  std::vector<std::string> lines;
  std::istringstream in(log);
  for (std::string line; std::getline(in, line);)
    if (line.find("INFO:CONSOLE") != std::string::npos) lines.push_back(line);
  return lines;
}

/// A decoded PNG, 3 bytes a pixel.
struct Pixels {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  /// The pixel as 0xRRGGBB.
  std::uint32_t at(int x, int y) const {
    const std::uint8_t* p = &rgb[3 * (std::size_t(y) * width + x)];
    return std::uint32_t(p[0]) << 16 | std::uint32_t(p[1]) << 8 | p[2];
  }
  bool non_white(int x, int y) const {
    const std::uint32_t c = at(x, y);
    return std::min({c >> 16, c >> 8 & 255, c & 255}) < 250;
  }
};

/// `path` decoded with libpng's simplified API; empty (width 0) when it cannot be.
Pixels read_png(const std::string& path) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  Pixels p;
  if (!png_image_begin_read_from_file(&image, path.c_str())) return p;
  image.format = PNG_FORMAT_RGB;
  p.rgb.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, p.rgb.data(), 0, nullptr)) return {};
  p.width = int(image.width);
  p.height = int(image.height);
  return p;
}

struct Rect {
  int x = 0, y = 0, width = 0, height = 0;
};

/// Every rectangle whose 1-px border is exactly `colour`, as its inner area, in page order (by
/// y, then x): found by the top-left corner, measured along the top and left sides, and kept
/// when the bottom and right sides close it. Pictures hold the colour in patches, so inner areas
/// under 8 x 8 and rectangles inside a frame already found do not count.
std::vector<Rect> find_frames(const Pixels& p, std::uint32_t colour) {
  std::vector<Rect> found;
  const auto is = [&](int x, int y) { return x < p.width && y < p.height && p.at(x, y) == colour; };
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x) {
      if (!is(x, y) || (x > 0 && is(x - 1, y)) || (y > 0 && is(x, y - 1))) continue;
      if (std::any_of(found.begin(), found.end(), [&](const Rect& f) {
            return x >= f.x && x < f.x + f.width && y >= f.y && y < f.y + f.height;
          }))
        continue;
      int right = x, bottom = y;
      while (is(right + 1, y)) ++right;
      while (is(x, bottom + 1)) ++bottom;
      if (right - x < 9 || bottom - y < 9) continue;
      bool closed = true;
      for (int i = x; i <= right; ++i) closed = closed && is(i, bottom);
      for (int j = y; j <= bottom; ++j) closed = closed && is(right, j);
      if (closed) found.push_back({x + 1, y + 1, right - x - 1, bottom - y - 1});
    }
  return found;
}

long non_white_pixels(const Pixels& p, const Rect& r) {
  long n = 0;
  for (int y = r.y; y < r.y + r.height; ++y)
    for (int x = r.x; x < r.x + r.width; ++x) n += p.non_white(x, y);
  return n;
}

/// The bounding box of the pixels of exactly `colour` (width 0 when there are none).
Rect box_of(const Pixels& p, std::uint32_t colour) {
  int x0 = p.width, y0 = p.height, x1 = -1, y1 = -1;
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x)
      if (p.at(x, y) == colour) {
        x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
      }
  return x1 < 0 ? Rect{} : Rect{x0, y0, x1 - x0 + 1, y1 - y0 + 1};
}

/// The x-axis of the histogram whose bars are `bars`: the run of non-white pixels in the row
/// under the bars (the axis line, from the plot's left edge to its right one, ticks included)
/// through the leftmost bar.
Rect axis_under(const Pixels& p, const Rect& bars) {
  const int y = bars.y + bars.height;
  int x0 = bars.x, x1 = bars.x;
  while (x0 > 0 && p.non_white(x0 - 1, y)) --x0;
  while (x1 + 1 < p.width && p.non_white(x1 + 1, y)) ++x1;
  return {x0, y, x1 - x0 + 1, 1};
}

/// The height of each of `bins` bars in `colour` over `axis`: the most pixels of the colour in
/// one column near the bin's centre (a dashed marker may cross one column).
std::vector<int> bar_heights(const Pixels& p, const Rect& bars, const Rect& axis,
                             std::uint32_t colour, int bins) {
  std::vector<int> heights(bins, 0);
  for (int i = 0; i < bins; ++i) {
    const int centre = axis.x + int(std::lround((i + 0.5) * axis.width / bins));
    for (int x = centre - 3; x <= centre + 3; ++x) {
      int n = 0;
      for (int y = bars.y; y < bars.y + bars.height; ++y) n += p.at(x, y) == colour;
      heights[i] = std::max(heights[i], n);
    }
  }
  return heights;
}

/// What the page says of one <img class="pic">.
struct PictureTag {
  int width = 0, height = 0;
  double scale = 0;  ///< pixels per world unit (data-scale)
};

std::vector<PictureTag> picture_tags(const std::string& html) {
  const std::string key = "<img class=\"pic\"";
  std::vector<PictureTag> tags;
  for (auto at = html.find(key); at != std::string::npos; at = html.find(key, at + 1)) {
    PictureTag t;
    std::sscanf(html.c_str() + at,
                "<img class=\"pic\" width=\"%d\" height=\"%d\" data-scale=\"%lf\"", &t.width,
                &t.height, &t.scale);
    tags.push_back(t);
  }
  return tags;
}

/// The area of the orthographic silhouette of the radius-0.5 sphere at `scale` pixels per unit.
double sphere_silhouette(double scale) { return kPi * std::pow(0.5 * scale, 2); }

/// The sphere's run (vdb_shell_shapes sphere -d 2; vdb_shell -r 48 --max-thickness 0.1 -q with
/// --html and --report: the thickness limit spreads the tet quality over six bins of the report)
/// and its page's screenshot at 1560 x 5200, made once for all tests.
struct SpherePage {
  TempDir dir;
  std::string error;  ///< what went wrong making it, "" when nothing did
  std::string html;
  nlohmann::json report;
  CommandResult browser;
  Pixels shot;
  std::vector<PictureTag> tags;
  std::vector<Rect> frames;

  SpherePage() {
    const std::string obj = dir.file("sphere.obj"), page = dir.file("sphere.html"),
                      json = dir.file("sphere.json"), png = dir.file("sphere.png");
    const CommandResult shape =
        run_command(quoted(vdb_shell_shapes_bin()) + " sphere -d 2 -o " + quoted(obj));
    if (shape.exit_code != 0) {
      error = "vdb_shell_shapes failed: " + shape.err;
      return;
    }
    const CommandResult cli = run_command(
        quoted(vdb_shell_bin()) + " " + quoted(obj) + " -o " + quoted(dir.file("sphere.vtu")) +
        " --html " + quoted(page) + " --report " + quoted(json) + " -r 48 --max-thickness 0.1 -q");
    if (cli.exit_code != 0) {
      error = "vdb_shell failed: " + cli.err;
      return;
    }
    html = read_text(page);
    report = nlohmann::json::parse(read_text(json), nullptr, false);
    if (report.is_discarded()) error = "the report is not JSON";
    browser = screenshot(page, png, dir.path() / "profile", 1560, 5200);
    shot = read_png(png);
    tags = picture_tags(html);
    frames = find_frames(shot, kFrameColour);
  }
};

const SpherePage& sphere_page() {
  static const SpherePage page;
  return page;
}

class HtmlBrowser : public ::testing::Test {
 protected:
  void SetUp() override {
    if (chromium_bin().empty())
      GTEST_SKIP() << "no chromium: none on PATH, or VDB_SHELL_CHROMIUM is empty (install the "
                      "Debian package 'chromium', or set VDB_SHELL_CHROMIUM to a binary)";
  }
};

TEST_F(HtmlBrowser, ConsoleErrorsAreSeen) {
  TempDir dir;
  write_text(dir.file("boom.html"),
             "<!DOCTYPE html><html><body><script>console.error(\"boom\")</script></body></html>");
  const CommandResult r = screenshot(dir.path() / "boom.html", dir.path() / "boom.png",
                                     dir.path() / "profile", 400, 300);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<std::string> lines = console_lines(r.err);
  EXPECT_TRUE(std::any_of(lines.begin(), lines.end(), [](const std::string& l) {
    return l.find("\"boom\"") != std::string::npos;
  })) << r.err;
}

TEST_F(HtmlBrowser, SpherePageRendersWithoutConsoleErrors) {
  const SpherePage& page = sphere_page();
  ASSERT_EQ(page.error, "");
  EXPECT_EQ(page.browser.exit_code, 0) << page.browser.err;
  for (const std::string& line : console_lines(page.browser.err)) ADD_FAILURE() << line;
  EXPECT_EQ(page.shot.width, 1560);
  EXPECT_EQ(page.shot.height, 5200);
}

TEST_F(HtmlBrowser, SpherePageFramesMatchItsPictures) {
  const SpherePage& page = sphere_page();
  ASSERT_EQ(page.error, "");
  ASSERT_GT(page.shot.width, 0);
  // 3 cut-aways, 2 thickness views, 2 worst-tet views, the traces.
  EXPECT_EQ(page.tags.size(), 8u);
  ASSERT_EQ(page.frames.size(), page.tags.size()) << "a picture is missing or the page is cut";
  for (std::size_t i = 0; i < page.frames.size(); ++i) {
    EXPECT_EQ(page.frames[i].width, page.tags[i].width) << "picture " << i;
    EXPECT_EQ(page.frames[i].height, page.tags[i].height) << "picture " << i;
  }
}

TEST_F(HtmlBrowser, SpherePageSilhouettesMatchTheirScale) {
  const SpherePage& page = sphere_page();
  ASSERT_EQ(page.error, "");
  ASSERT_GE(page.frames.size(), 5u);
  ASSERT_GE(page.tags.size(), 5u);
  for (std::size_t i : {3, 4}) {  // the thickness views, front and back
    const double expected = sphere_silhouette(page.tags[i].scale);
    const long measured = non_white_pixels(page.shot, page.frames[i]);
    EXPECT_NEAR(measured / expected, 1.0, 0.06)
        << "picture " << i << ": " << measured << " pixels, " << expected << " expected";
  }
}

TEST_F(HtmlBrowser, SpherePageCutAwaysAreNotBlank) {
  const SpherePage& page = sphere_page();
  ASSERT_EQ(page.error, "");
  ASSERT_GE(page.frames.size(), 3u);
  ASSERT_GE(page.tags.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    const Rect& f = page.frames[i];
    const long measured = non_white_pixels(page.shot, f);
    EXPECT_GT(measured, 0.02 * f.width * f.height) << "cut-away " << i;
    EXPECT_LT(measured, sphere_silhouette(page.tags[i].scale)) << "cut-away " << i;
  }
}

TEST_F(HtmlBrowser, SpherePageQualityBarsMatchTheReport) {
  const SpherePage& page = sphere_page();
  ASSERT_EQ(page.error, "");
  const Rect bars = box_of(page.shot, kQualityColour);
  const Rect dihedral = box_of(page.shot, kDihedralColour);
  ASSERT_GT(bars.width, 0) << "no quality bars";
  ASSERT_GT(dihedral.width, 0) << "no dihedral bars";
  EXPECT_TRUE(dihedral.x >= bars.x + bars.width || dihedral.y >= bars.y + bars.height)
      << "the dihedral bars overlap the quality plot";

  ASSERT_LT(bars.y + bars.height, page.shot.height) << "the page is cut below the bars";
  const Rect axis = axis_under(page.shot, bars);
  ASSERT_NEAR(double(axis.width) / kQualityBins, kBinPitch, 0.3) << "no x-axis under the bars";
  const std::vector<int> heights = bar_heights(page.shot, bars, axis, kQualityColour, kQualityBins);
  EXPECT_NEAR(*std::max_element(heights.begin(), heights.end()), kPlotHeight, 1);

  // The page's bins are half the report's, and count the non-positive tets in its first.
  const nlohmann::json& quality = page.report.at("quality");
  std::vector<double> expected = quality.at("histogram").get<std::vector<double>>();
  ASSERT_EQ(expected.size(), std::size_t(kQualityBins / 2));
  expected[0] += quality.at("non_positive").get<double>();
  double expected_sum = 0, measured_sum = 0;
  for (const double e : expected) expected_sum += e;
  for (const int h : heights) measured_sum += h;
  ASSERT_GT(expected_sum, 0);
  ASSERT_GT(measured_sum, 0);
  // Bars in several bins, so one drawn in the wrong bin shows.
  ASSERT_GE(std::count_if(expected.begin(), expected.end(), [](double e) { return e > 0; }), 4);
  for (std::size_t k = 0; k < expected.size(); ++k)
    EXPECT_NEAR((heights[2 * k] + heights[2 * k + 1]) / measured_sum, expected[k] / expected_sum,
                0.03)
        << "report bin " << k;
}

}  // namespace
}  // namespace vdb_shell::test
