// report_html() and the pictures it shows (core/render/pictures.h) on real shells.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "assets/shapes.h"
#include "core/render/pictures.h"
#include "tests/test_support.h"
#include "vdb_shell/vdb_shell.h"

namespace vdb_shell {
namespace {

ShellResult sphere_shell(int threads = 0, bool traces_only = false) {
  ShellOptions o;
  o.fields.resolution = 48;
  o.threads = threads;
  o.traces_only = traces_only;
  return build_shell(make_shape("sphere"), o, {}, "sphere");
}

/// A pixel of an outer-surface face: kOuterColour times a shading factor (blue is its largest
/// channel by far; no quality colour or the inner colour has that).
bool outer_pixel(const Rgb& c) { return c.b > c.r + 25 && c.b > c.g + 10; }

TEST(HtmlPictures, TheCutExposesTheTetsAndTheSurfaceFlagsAreExact) {
  const ShellResult r = sphere_shell();
  const ShellFaces faces = shell_faces(r.mesh, r.surface);
  // Each input triangle is the face of exactly one tet; no other shell boundary face is one.
  EXPECT_EQ(std::size_t(std::count(faces.outer.begin(), faces.outer.end(), 1)),
            r.surface.triangles.size());
  const BBox box = bounding_box(r.surface);
  const Vec3d centre = (box.lo + box.hi) * 0.5;
  // Looking straight at the cut (from +x): the whole disc is cut faces, coloured by quality.
  const Camera camera = Camera::framing(box, {-1, 0, 0}, {0, 0, 1}, 240, 240);
  const Image cut = render_cut_away(r.mesh, faces, camera, centre, {1, 0, 0}, 2);
  // With the plane beyond the sphere nothing is removed: the outer surface is all one sees.
  const Image whole = render_cut_away(r.mesh, faces, camera, centre + Vec3d{2, 0, 0}, {1, 0, 0}, 2);
  std::size_t cut_drawn = 0, cut_outer = 0, whole_drawn = 0, whole_outer = 0;
  for (const Rgb& c : cut.pixels)
    if (!(c == kBackground)) ++cut_drawn, cut_outer += outer_pixel(c);
  for (const Rgb& c : whole.pixels)
    if (!(c == kBackground)) ++whole_drawn, whole_outer += outer_pixel(c);
  const double disc = kPi * std::pow(0.5 * camera.scale, 2);
  EXPECT_NEAR(double(cut_drawn), disc, 0.04 * disc);
  EXPECT_NEAR(double(whole_drawn), disc, 0.04 * disc);
  EXPECT_LT(double(cut_outer), 0.05 * cut_drawn);
  EXPECT_GT(double(whole_outer), 0.9 * whole_drawn);
}

TEST(HtmlReport, SamePageForAnyThreadCountOnceTheTimesAreZero) {
  ShellResult one = sphere_shell(1), two = sphere_shell(2);
  one.timings = {};
  two.timings = {};
  one.field_stats.seconds_sdf = one.field_stats.seconds_fill = one.field_stats.seconds_refine =
      one.field_stats.seconds_flux = one.field_stats.seconds_gradient = 0;
  two.field_stats.seconds_sdf = two.field_stats.seconds_fill = two.field_stats.seconds_refine =
      two.field_stats.seconds_flux = two.field_stats.seconds_gradient = 0;
  one.validity.seconds = two.validity.seconds = 0;
  one.optimize.report.seconds = two.optimize.report.seconds = 0;
  const std::string page = report_html(one);
  EXPECT_EQ(page, report_html(two));
  EXPECT_NE(page.find(std::to_string(one.mesh.tets.size()) + " tets from " +
                      std::to_string(one.surface.triangles.size()) + " surface triangles"),
            std::string::npos);
  EXPECT_EQ(test::count_of(page, "<img class=\"pic\""), 8u);
  EXPECT_EQ(test::count_of(page, "<svg"), 5u);
  EXPECT_NE(page.find("<span class=\"ok\">valid</span>"), std::string::npos);
}

TEST(HtmlReport, ATracesOnlyRunShowsTheInputAndTheTraces) {
  const ShellResult r = sphere_shell(0, true);
  const std::string page = report_html(r);
  EXPECT_EQ(test::count_of(page, "<img class=\"pic\""), 1u);  // the traces
  EXPECT_EQ(test::count_of(page, "<svg"), 0u);
  EXPECT_NE(page.find("All " + std::to_string(r.surface.points.size()) + " traces"),
            std::string::npos);
  EXPECT_TRUE(html_thumbnail(r).empty());
}

TEST(HtmlReport, AFailedWriteLeavesNothingAndTheIndexLinksEachPage) {
  const ShellResult r = sphere_shell();
  EXPECT_THROW(write_html("/nonexistent-folder/r.html", r), ResourceError);
  const std::string thumb = html_thumbnail(r);
  EXPECT_EQ(thumb.substr(1, 3), "PNG");
  HtmlIndexRow ok{"sphere.obj", "sphere.html", thumb, "", r.mesh.tets.size(), 0.9, 0.1, 0.2, 1};
  HtmlIndexRow bad{"open.obj", "", "", "open.obj: not closed <edges>", 0, 0, 0, 0, 0};
  const std::string index = html_index({ok, bad});
  EXPECT_NE(index.find("<a href=\"sphere.html\"><img"), std::string::npos);
  EXPECT_NE(index.find("error: open.obj: not closed &lt;edges&gt;"), std::string::npos);
  EXPECT_NE(index.find("1 written, 1 failed"), std::string::npos);
}

}  // namespace
}  // namespace vdb_shell
