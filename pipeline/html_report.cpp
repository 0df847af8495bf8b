// html_report.cpp — the HTML report (report_html(), html_index()): one self-contained page per
// run, every picture inline (PNG as data: URIs from core/render, plots and sections as SVG).
// docs/report.md describes what the page shows.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "core/assemble/quality.h"
#include "core/base/memory_budget.h"
#include "core/base/tet_faces.h"
#include "core/render/pictures.h"
#include "core/render/raster.h"
#include "core/render/sections.h"
#include "core/write/atomic_file.h"
#include "pipeline/html_report.h"
#include "vdb_shell/vdb_shell.h"

namespace vdb_shell {

namespace {

constexpr int kSupersample = 2;
constexpr const char* kQualityBars = "#2f6db5";   // unique on the page: the browser test finds it
constexpr const char* kDihedralBars = "#7d52b8";  // likewise
constexpr const char* kMarker = "#c0392b";
constexpr std::size_t kQualityBins = 20;
constexpr std::size_t kDihedralBins = 36;  // 5 degrees each
constexpr std::size_t kMaxTraces = 1500;

std::string num(double v, int digits = 4) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

std::string escape(const std::string& s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string base64(const std::string& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (unsigned char)bytes[i] << 16 | (unsigned char)bytes[i + 1] << 8 |
                       (unsigned char)bytes[i + 2];
    for (int k = 18; k >= 0; k -= 6) out += table[(v >> k) & 63];
  }
  if (i < bytes.size()) {
    unsigned v = (unsigned char)bytes[i] << 16;
    if (i + 1 < bytes.size()) v |= (unsigned char)bytes[i + 1] << 8;
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? table[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

/// An <img> of `image`, with the camera's scale as a data attribute (the browser test measures
/// silhouettes with it).
std::string img(const Image& image, const Camera& camera, const std::string& alt) {
  return "<img class=\"pic\" width=\"" + std::to_string(image.width) + "\" height=\"" +
         std::to_string(image.height) + "\" data-scale=\"" + num(camera.scale, 9) + "\" alt=\"" +
         escape(alt) + "\" src=\"data:image/png;base64," + base64(encode_png(image)) + "\">";
}

/// The views of the pictures: from the front-right-above, and its opposite.
Vec3d view(int i) { return i == 0 ? Vec3d{-0.55, 1.0, -0.45} : Vec3d{0.55, -1.0, -0.45}; }

/// Cut-away view k: the cut normal to world axis k through the centre, seen from the removed
/// side and off to one side so the cut face and the outside both show.
struct CutView {
  Vec3d cut, forward, up;
};
CutView cut_view(int axis) {
  Vec3d cut{}, forward{}, up{0, 0, 1};
  cut[axis] = 1;
  const int a = (axis + 1) % 3, b = (axis + 2) % 3;
  forward[axis] = -1;
  forward[a] = 0.55;
  forward[b] = -0.4;
  if (axis == 2) up = {0, 1, 0};
  return {cut, forward, up};
}

/// The shell cut away as cut_view(axis) shows it, `width` x `height`.
struct CutAway {
  Camera camera;
  Image image;
};
CutAway cut_away(const ShellResult& r, const ShellFaces& faces, const BBox& box, int axis,
                 int width, int height) {
  const CutView v = cut_view(axis);
  const Camera camera = Camera::framing(box, v.forward, v.up, width, height);
  return {camera,
          render_cut_away(r.mesh, faces, camera, (box.lo + box.hi) * 0.5, v.cut, kSupersample)};
}

/// Two figures of the surface coloured per corner, from view(0) and view(1), each with `alt`
/// and ", front" / ", back" and the caption.
std::string front_and_back(const ShellResult& r, const BBox& box, const std::vector<Rgb>& corner,
                           const std::string& alt, const std::string& caption) {
  std::string out;
  for (int i = 0; i < 2; ++i) {
    const Camera camera = Camera::framing(box, view(i), {0, 0, 1}, 480, 420);
    out += "<figure>" +
           img(render_surface(r.surface, corner, camera, kSupersample), camera,
               alt + (i == 0 ? ", front" : ", back")) +
           "<figcaption>" + caption + "</figcaption></figure>\n";
  }
  return out;
}

std::string legend_swatch(const Rgb& c, const std::string& label) {
  return "<span class=\"sw\" style=\"background:" + hex(c) + "\"></span>" + escape(label);
}

/// A CSS gradient bar for `map` over [lo, hi] with its end labels.
std::string colour_bar(const ColourMap& map, double lo, double hi, const std::string& what) {
  std::string stops;
  for (const ColourMap::Stop& s : map.stops())
    stops += "," + hex(s.colour) + " " + num(100 * s.at, 3) + "%";
  return "<div class=\"cbar\"><span>" + num(lo) +
         "</span><span class=\"grad\" "
         "style=\"background:linear-gradient(to right" +
         stops + ")\"></span><span>" + num(hi) + "</span> " + escape(what) + "</div>";
}

struct Marker {
  std::string label;
  double value;
};

/// A bar chart of `counts` over [lo, hi] in equal bins, with vertical markers.
std::string histogram_svg(const std::vector<std::size_t>& counts, double lo, double hi,
                          const char* colour, const std::vector<Marker>& markers,
                          const std::string& x_label, double tick) {
  const int w = 600, h = 300, left = 56, right = 14, top = 48, bottom = 44;
  const double pw = w - left - right, ph = h - top - bottom;
  const std::size_t peak =
      std::max<std::size_t>(1, *std::max_element(counts.begin(), counts.end()));
  std::ostringstream s;
  s << "<svg class=\"plot\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << w << "\" height=\""
    << h << "\" viewBox=\"0 0 " << w << " " << h
    << "\" font-family=\"sans-serif\" font-size=\"12\">";
  s << "<line x1=\"" << left << "\" y1=\"" << top + ph << "\" x2=\"" << left + pw << "\" y2=\""
    << top + ph << "\" stroke=\"#444\"/>";
  const double bw = pw / counts.size();
  for (std::size_t i = 0; i < counts.size(); ++i) {
    const double bh = std::round(ph * double(counts[i]) / double(peak));
    if (counts[i] == 0) continue;
    s << "<rect shape-rendering=\"crispEdges\" fill=\"" << colour << "\" x=\""
      << num(left + i * bw + 1, 6) << "\" y=\"" << num(top + ph - bh, 6) << "\" width=\""
      << num(bw - 2, 6) << "\" height=\"" << num(bh, 6) << "\"><title>" << counts[i]
      << "</title></rect>";
  }
  for (double x = lo; x <= hi + 1e-9; x += tick) {
    const double px = left + (x - lo) / (hi - lo) * pw;
    s << "<line x1=\"" << num(px, 6) << "\" y1=\"" << top + ph << "\" x2=\"" << num(px, 6)
      << "\" y2=\"" << top + ph + 5 << "\" stroke=\"#444\"/><text x=\"" << num(px, 6) << "\" y=\""
      << top + ph + 18 << "\" text-anchor=\"middle\">" << num(x) << "</text>";
  }
  s << "<text x=\"" << left + pw / 2 << "\" y=\"" << h - 6 << "\" text-anchor=\"middle\">"
    << escape(x_label) << "</text>";
  s << "<text x=\"" << left - 6 << "\" y=\"" << top + 4 << "\" text-anchor=\"end\">" << peak
    << "</text><text x=\"" << left - 6 << "\" y=\"" << top + ph
    << "\" text-anchor=\"end\">0</text>";
  for (std::size_t i = 0; i < markers.size(); ++i) {
    const double px = left + std::clamp((markers[i].value - lo) / (hi - lo), 0.0, 1.0) * pw;
    s << "<line x1=\"" << num(px, 6) << "\" y1=\"" << top - 4 << "\" x2=\"" << num(px, 6)
      << "\" y2=\"" << top + ph << "\" stroke=\"" << kMarker
      << "\" stroke-dasharray=\"4 3\"/><text x=\"" << num(px + 3, 6) << "\" y=\"" << 12 + 12 * i
      << "\" fill=\"" << kMarker << "\" font-size=\"11\">" << escape(markers[i].label) << "</text>";
  }
  s << "</svg>";
  return s.str();
}

/// A row of a two-column table.
std::string row(const std::string& key, const std::string& value) {
  return "<tr><th>" + escape(key) + "</th><td>" + value + "</td></tr>\n";
}

std::string count_of(std::size_t n) { return std::to_string(n); }

/// Thickness under each surface vertex: its distance to its inner vertex (0 if kept on the
/// surface). inner_surface triangle t is surface triangle t reversed ({0, 2, 1}).
std::vector<double> vertex_thickness(const ShellResult& r) {
  std::vector<double> th(r.surface.points.size(), 0.0);
  const int corner[3] = {0, 2, 1};
  for (std::size_t t = 0; t < r.surface.triangles.size() && t < r.inner_surface.triangles.size();
       ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = r.surface.triangles[t][k];
      th[v] = distance(r.surface.points[v],
                       r.inner_surface.points[r.inner_surface.triangles[t][corner[k]]]);
    }
  return th;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  const std::size_t k = std::min(v.size() - 1, std::size_t(p * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

const char* kStyle = R"(<style>
body{font-family:sans-serif;margin:24px auto;padding:0 16px;max-width:1520px;color:#222;background:#fff}
h1{font-size:22px;margin:0 0 4px}h2{font-size:18px;margin:28px 0 8px;border-bottom:1px solid #ddd}
p.lead{margin:4px 0 12px;color:#444}
table{border-collapse:collapse;font-size:14px}th,td{padding:3px 10px;text-align:left;vertical-align:top}
th{font-weight:600;color:#333}tr:nth-child(even){background:#f6f6f6}
.grid{display:flex;flex-wrap:wrap;gap:14px;align-items:flex-start}
figure{margin:0}figcaption{font-size:13px;color:#444;max-width:600px;margin-top:4px}
img.pic{border:1px solid #c8c8c8;display:block}
.sw{display:inline-block;width:12px;height:12px;margin:0 4px 0 12px;vertical-align:-1px;border:1px solid #888}
.cbar{font-size:13px;margin:6px 0}.grad{display:inline-block;width:220px;height:12px;margin:0 6px;vertical-align:-1px;border:1px solid #888}
.bar{display:inline-block;height:10px;background:#8aa8cf;vertical-align:0}
.bad{color:#b00020;font-weight:600}.ok{color:#17692f;font-weight:600}
pre{font-size:12px;background:#f6f6f6;padding:8px;overflow:auto;max-height:480px}
</style>)";

std::string page_head(const std::string& title) {
  return "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" +
         escape(title) + "</title>\n" + kStyle + "</head><body>\n";
}

}  // namespace

std::size_t estimate_html_bytes(const SurfaceMesh& surface, const TetMesh& mesh) {
  const std::size_t tets = mesh.tets.size();
  // Tets cut by the three middle planes: each becomes about 170 bytes of SVG path, held in the
  // section and again in the page.
  const BBox box = bounding_box(surface);
  const Vec3d centre = (box.lo + box.hi) * 0.5;
  std::size_t cut = 0;
  for (const Tet& t : mesh.tets)
    for (int a = 0; a < 3; ++a) {
      int above = 0;
      for (const std::uint32_t v : t) above += mesh.points[v][a] >= centre[a];
      cut += above != 0 && above != 4;
    }
  const std::size_t faces = 4 * tets * (sizeof(FaceRecord) + sizeof(std::int64_t) + 1);
  const std::size_t angles = 6 * tets * sizeof(double);
  const std::size_t per_triangle =
      surface.triangles.size() * (3 * sizeof(Rgb) + 2 * sizeof(double));
  const std::size_t canvas =
      std::size_t(kSupersample * 560) * (kSupersample * 480) * (sizeof(Rgb) + sizeof(float));
  const std::size_t pictures = 8 * std::size_t(560 * 480 * 3) * 2;  // PNG and base64, worst case
  return faces + angles + per_triangle + canvas + pictures + 2 * 170 * cut;
}

std::string html_thumbnail(const ShellResult& r) {
  if (r.mesh.tets.empty()) return {};
  return encode_png(
      cut_away(r, shell_faces(r.mesh, r.surface), r.input.stats.bbox, 1, 200, 160).image);
}

std::string report_html(const ShellResult& r, const ReportFiles& files, double read_seconds,
                        double write_seconds) {
  check_memory_budget("write", r.memory.write_html, budget_bytes(r.options.fields.max_memory_gb),
                      "making the HTML report of " + std::to_string(r.mesh.tets.size()) +
                          " tets (the tet faces, 8 pictures, 3 sections)",
                      "drop --html, or raise --max-memory");
  const InputReport& in = r.input;
  const SurfaceStats& st = in.stats;
  const BBox box = st.bbox;
  Vec3d centre = (box.lo + box.hi) * 0.5;
  for (int a = 0; a < 3; ++a)  // no -5.55e-17 in captions
    if (std::fabs(centre[a]) < 1e-12 * box.diagonal()) centre[a] = 0;
  const bool shell = !r.options.traces_only && !r.mesh.tets.empty();
  const std::size_t layers = std::size_t(r.options.validity.layers);
  const std::size_t bound = 3 * layers * st.faces + 2 * r.validity.sectors;
  std::ostringstream h;
  h << page_head("vdb_shell: " + in.source);
  h << "<h1>Volumetric shell of " << escape(in.source) << "</h1>\n";
  h << "<p class=\"lead\">" << r.mesh.tets.size() << " tets from " << st.faces
    << " surface triangles; coverage " << num(r.quality.coverage, 3) << " of the enclosed "
    << "volume; quality min " << num(r.quality.min_quality, 3) << ", median "
    << num(r.quality.median_quality, 3) << "; "
    << (r.checks.valid() ? "<span class=\"ok\">valid</span>"
                         : "<span class=\"bad\">NOT valid</span>")
    << (files.shell.empty() ? "" : "; written to " + escape(files.shell)) << ".</p>\n";

  // The input.
  h << "<h2>Input</h2><table>\n";
  h << row("file", escape(in.source));
  h << row("vertices / faces", count_of(st.vertices) + " / " + count_of(st.faces));
  h << row("components / genus", count_of(st.components) + " / " + std::to_string(st.genus));
  h << row("bounding box", "(" + num(box.lo.x) + ", " + num(box.lo.y) + ", " + num(box.lo.z) +
                               ") to (" + num(box.hi.x) + ", " + num(box.hi.y) + ", " +
                               num(box.hi.z) + "), diagonal " + num(box.diagonal()));
  h << row("mean edge length", num(st.mean_edge_length));
  h << row("enclosed volume", num(st.enclosed_volume));
  h << row("oriented", in.flipped              ? "inward in the file: flipped"
                       : in.flipped_components ? count_of(in.flipped_components) +
                                                     " components inward in the file: flipped"
                                               : "outward");
  if (r.repair) {
    const RepairReport& p = *r.repair;
    if (p.kept)
      h << row("repair",
               "none needed: the input is closed, 2-manifold and does not cross "
               "itself, kept as it is");
    else
      h << row("repair",
               "rebuilt watertight through a volume (voxel " + num(p.voxel_size) + ", closing " +
                   num(p.closing) + " voxels): " + count_of(p.input_faces) + " input polygons, " +
                   count_of(p.holes_closed) + " holes closed, " + count_of(p.faces) +
                   " faces; repaired to input distance max " + num(p.distance_max) + ", mean " +
                   num(p.distance_mean) + "; input to repaired max " + num(p.input_distance_max) +
                   " (on the enclosed solid " + num(p.solid_input_distance_max) + ")");
  }
  std::string notices;
  for (const std::string& n : r.notices) notices += "<li>" + escape(n) + "</li>";
  h << row("notices", notices.empty()
                          ? "none"
                          : "<ul style=\"margin:0;padding-left:18px\">" + notices + "</ul>");
  h << "</table>\n";

  if (shell) {
    const ShellFaces faces = shell_faces(r.mesh, r.surface);
    const ColourMap& qmap = ColourMap::quality();
    h << "<h2>Cut-away views</h2><div class=\"grid\">\n";
    const char* axis_name[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
      const CutAway view = cut_away(r, faces, box, a, 480, 420);
      h << "<figure>" << img(view.image, view.camera, std::string("cut-away at ") + axis_name[a])
        << "<figcaption>Tets with their centre at " << axis_name[a] << " &gt; " << num(centre[a])
        << " removed.</figcaption></figure>\n";
    }
    h << "</div><p>" << legend_swatch(kOuterColour, "input surface")
      << legend_swatch(kInnerColour, "inner surface") << "; cut tets by quality:</p>"
      << colour_bar(qmap, 0, 1, "volume-length ratio (1: regular)") << "\n";

    h << "<h2>Cross-sections through the middle</h2><div class=\"grid\">\n";
    for (int a = 0; a < 3; ++a) {
      const SectionAxes ax = section_axes(a);
      h << "<figure>" << section_svg(r.surface, r.mesh, a, centre[a], box, 480, 420)
        << "<figcaption>" << axis_name[a] << " = " << num(centre[a]) << " (" << axis_name[ax.u]
        << " right, " << axis_name[ax.v] << " up)</figcaption></figure>\n";
    }
    h << "</div><p>Tets coloured by quality as above; <span class=\"sw\" style=\"background:"
      << kUncoveredColour << "\"></span>interior the shell does not cover; black: the input "
      << "surface.</p>\n";

    // Thickness.
    const std::vector<double> th = vertex_thickness(r);
    const double th_max = th.empty() ? 0 : *std::max_element(th.begin(), th.end());
    std::vector<Rgb> corner(3 * r.surface.triangles.size());
    for (std::size_t t = 0; t < r.surface.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k)
        corner[3 * t + k] =
            ColourMap::sequential()(th_max > 0 ? th[r.surface.triangles[t][k]] / th_max : 0.0);
    h << "<h2>Thickness</h2><div class=\"grid\">\n"
      << front_and_back(r, box, corner, "thickness", "From the front and from the back.")
      << "</div>"
      << colour_bar(ColourMap::sequential(), 0, th_max,
                    "distance from each surface vertex to its inner vertex (world units)")
      << "<p>Thickness min " << num(th.empty() ? 0 : *std::min_element(th.begin(), th.end()))
      << ", median " << num(percentile(th, 0.5)) << ", max " << num(th_max) << " ("
      << num(th_max / std::max(r.field_stats.voxel_size, 1e-300), 3) << " voxels); "
      << r.counts.thickness_limited_vertices << " vertices shortened by a thickness limit, "
      << r.validity.on_surface_vertices << " kept on the surface.</p>\n";

    // Worst tets: each surface triangle coloured by the worst tet of its prism.
    std::vector<double> worst(r.surface.triangles.size(), 1.0);
    if (r.mesh.source_triangle.size() == r.mesh.tets.size() &&
        r.mesh.quality.size() == r.mesh.tets.size())
      for (std::size_t t = 0; t < r.mesh.tets.size(); ++t) {
        const std::uint32_t f = r.mesh.source_triangle[t];
        if (f < worst.size()) worst[f] = std::min(worst[f], r.mesh.quality[t]);
      }
    for (std::size_t t = 0; t < worst.size(); ++t)
      corner[3 * t] = corner[3 * t + 1] = corner[3 * t + 2] = qmap(worst[t]);
    h << "<h2>Where the worst tets are</h2><div class=\"grid\">\n"
      << front_and_back(r, box, corner, "worst tet quality",
                        "Each surface triangle coloured by the lowest quality of the tets built "
                        "on it.")
      << "</div>" << colour_bar(qmap, 0, 1, "volume-length ratio") << "\n";
  }

  // Traces.
  const TraceResult& tr = r.traces;
  h << "<h2>Traces</h2><div class=\"grid\"><figure>";
  {
    const Camera camera = Camera::framing(box, view(0), {0, 0, 1}, 560, 480);
    const std::size_t stride = trace_stride(tr.num_traces(), kMaxTraces);
    h << img(render_traces(r.surface, tr, camera, kMaxTraces, kSupersample), camera, "traces")
      << "<figcaption>"
      << (stride > 1 ? "One in " + std::to_string(stride) + " of the " +
                           std::to_string(tr.num_traces()) + " traces"
                     : "All " + std::to_string(tr.num_traces()) + " traces")
      << ", from the surface vertex to where it stopped.</figcaption></figure><table>\n";
  }
  const char* reasons[4] = {"critical point", "merge", "flux", "cap"};
  for (int s = 0; s < 4; ++s) {
    const std::size_t n = tr.stop_count[s];
    h << row(reasons[s], legend_swatch(kStopColour[s], "") + count_of(n) + " (" +
                             num(100.0 * n / std::max<std::size_t>(tr.num_traces(), 1), 3) + "%)");
  }
  h << row("step / point size", num(tr.parameters.step) + " / " + num(tr.parameters.point_size));
  h << row("samples", count_of(tr.samples.size()));
  h << "</table></div>\n";

  if (shell) {
    // Quality histograms.
    std::vector<std::size_t> qh(kQualityBins, 0), dh(kDihedralBins, 0);
    std::vector<double> angles;
    angles.reserve(6 * r.mesh.tets.size());
    for (std::size_t t = 0; t < r.mesh.tets.size(); ++t) {
      const Tet& v = r.mesh.tets[t];
      const double q = r.mesh.quality.size() == r.mesh.tets.size()
                           ? r.mesh.quality[t]
                           : tet_quality(r.mesh.points[v[0]], r.mesh.points[v[1]],
                                         r.mesh.points[v[2]], r.mesh.points[v[3]]);
      ++qh[std::clamp(int(std::ceil(q * kQualityBins)) - 1, 0, int(kQualityBins) - 1)];
      for (const double a : tet_dihedrals_deg(r.mesh.points[v[0]], r.mesh.points[v[1]],
                                              r.mesh.points[v[2]], r.mesh.points[v[3]])) {
        ++dh[std::min<std::size_t>(kDihedralBins - 1, std::size_t(a / (180.0 / kDihedralBins)))];
        angles.push_back(a);
      }
    }
    const QualitySummary& q = r.quality;
    h << "<h2>Quality</h2><div class=\"grid\"><figure>"
      << histogram_svg(qh, 0, 1, kQualityBars,
                       {{"min " + num(q.min_quality, 3), q.min_quality},
                        {"p5 " + num(q.p5_quality, 3), q.p5_quality},
                        {"median " + num(q.median_quality, 3), q.median_quality}},
                       "volume-length ratio (tets per bin of 0.05)", 0.2)
      << "<figcaption>Tet quality (paper Fig. 10); " << q.non_positive
      << " tets flat or inverted.</figcaption></figure><figure>";
    const double a_min = angles.empty() ? 0 : *std::min_element(angles.begin(), angles.end());
    const double a_p5 = percentile(angles, 0.05), a_median = percentile(angles, 0.5);
    h << histogram_svg(dh, 0, 180, kDihedralBars,
                       {{"min " + num(a_min, 3), a_min},
                        {"p5 " + num(a_p5, 3), a_p5},
                        {"median " + num(a_median, 3), a_median}},
                       "dihedral angle, degrees (all six of every tet, bins of 5)", 30)
      << "<figcaption>Dihedral angles; the regular tet's are 70.5 degrees.</figcaption>"
      << "</figure></div>\n";

    // The shell's figures.
    const ShellCheckResult& c = r.checks;
    const ValidityReport& v = r.validity;
    h << "<h2>Shell</h2><div class=\"grid\"><table>\n";
    h << row("tets", count_of(r.mesh.tets.size()) + " of at most " + count_of(bound) + " (" +
                         (layers > 1 ? "3F x " + std::to_string(layers) + " layers" : "3F") +
                         (v.sectors ? " + 2 per sector" : std::string()) + "), " +
                         num(100.0 * r.mesh.tets.size() / std::max<std::size_t>(bound, 1), 3) +
                         "%");
    h << row("points", count_of(r.mesh.points.size()));
    h << row("coverage", "<span class=\"bar\" style=\"width:" +
                             num(std::clamp(r.quality.coverage, 0.0, 1.0) * 200, 4) +
                             "px\"></span> " + num(r.quality.coverage, 4) + " (shell volume " +
                             num(r.quality.shell_volume) + " of " + num(r.quality.enclosed_volume) +
                             ")");
    h << row("valid",
             (c.valid() ? "<span class=\"ok\">yes</span>" : "<span class=\"bad\">no</span>") +
                 std::string(": ") + count_of(c.inverted_tets) + " inverted, " +
                 count_of(c.zero_volume_tets) + " zero-volume, " + count_of(c.overlapping_pairs) +
                 " intersecting pairs, " + count_of(c.outside_inner_vertices) +
                 " inner vertices outside, " + count_of(c.missing_triangles) +
                 " surface triangles missing");
    h << row("welded / collapsed", count_of(r.counts.welded_vertices) + " welded vertices, " +
                                       count_of(r.counts.collapsed_prisms) + " collapsed prisms, " +
                                       count_of(r.counts.dropped_degenerate_tets) +
                                       " degenerate tets dropped");
    h << "</table><table>\n";
    h << row("validity rounds / checks",
             std::to_string(v.rounds) + " / " + std::to_string(v.checks_run));
    h << row("moved back", count_of(v.moved_back_vertices) + " vertices, by " +
                               num(v.moved_back_mean_fraction, 3) + " of their trace on average");
    h << row("unwelded", count_of(v.unwelded_vertices));
    h << row("folded vertices", count_of(v.folded_vertices) + " (" + count_of(v.sectors) +
                                    " sectors, " + count_of(v.gap_tets) + " gap tets)");
    h << row("kept on the surface", count_of(v.on_surface_vertices));
    if (v.flat_tets > 0)
      h << row("zero-area faces",
               count_of(v.flat_tets) + " flat tets keep them on the outer boundary (zero volume)");
    if (r.optimize.report.ran) {
      const OptimizeSummary& o = r.optimize;
      h << row("optimised (--optimize)",
               count_of(o.report.moved_vertices) + " inner vertices moved in " +
                   std::to_string(o.report.sweeps) + " sweeps, " + count_of(o.report.recut_quads) +
                   " side quads cut the other way: quality p5 " + num(o.p5_quality_before, 3) +
                   " to " + num(r.quality.p5_quality, 3) + ", min dihedral " +
                   num(o.min_dihedral_deg_before, 3) + " to " + num(r.quality.min_dihedral_deg, 3) +
                   " degrees, coverage " + num(o.coverage_before, 4) + " to " +
                   num(r.quality.coverage, 4));
    }
    h << row("cap faces / floor drops", count_of(v.cap_faces) + " / " + count_of(v.floor_drops));
    if (v.following_vertices)
      h << row("following an edge's ends", count_of(v.following_vertices) + " vertices");
    h << "</table></div>\n";
  }

  // Time and memory.
  const StageTimings& t = r.timings;
  const double total = read_seconds + t.total + write_seconds;
  const std::vector<std::pair<std::string, double>> stages = {
      {"read", read_seconds},
      {"fields", t.fields},
      {"trace", t.trace},
      {"inner", t.inner},
      {"validity (with the final check)", t.validity},
      {"write", write_seconds}};
  h << "<h2>Time and memory</h2><div class=\"grid\"><table>\n";
  for (const auto& [name, s] : stages)
    h << row(name, "<span class=\"bar\" style=\"width:" + num(total > 0 ? 240 * s / total : 0, 4) +
                       "px\"></span> " + num(s, 3) + " s");
  h << row("total", num(total, 3) + " s");
  h << "</table><table>\n";
  const MemoryEstimates& m = r.memory;
  const auto gib = [](std::size_t b) { return num(double(b) / kBytesPerGiB, 3) + " GiB"; };
  h << row("budget (--max-memory)", m.budget ? gib(m.budget) : std::string("none"));
  const std::vector<std::pair<std::string, std::size_t>> peaks = {
      {"fields", m.fields},     {"trace", m.trace},       {"inner", m.inner},
      {"validity", m.validity}, {"write", m.write_shell}, {"html", m.write_html}};
  std::size_t peak = m.surface;
  for (const auto& [name, b] : peaks) {
    h << row("peak estimate, " + name, gib(b));
    peak = std::max(peak, b);
  }
  h << row("peak", gib(peak));
  h << "</table></div>\n";

  h << "<h2>The JSON report</h2><details><summary>as --report writes it</summary><pre>"
    << escape(report_json(r, files, read_seconds, write_seconds)) << "</pre></details>\n";
  h << "</body></html>\n";
  return h.str();
}

void write_html(const std::string& path, const ShellResult& result, const ReportFiles& files,
                double read_seconds, double write_seconds) {
  const std::string page = report_html(result, files, read_seconds, write_seconds);
  write_file_atomically(path, [&](std::ostream& os) { os << page; });
}

std::string html_index(const std::vector<HtmlIndexRow>& rows) {
  std::ostringstream h;
  h << page_head("vdb_shell: " + std::to_string(rows.size()) + " inputs");
  std::size_t ok = 0;
  for (const HtmlIndexRow& r : rows) ok += r.error.empty();
  h << "<h1>Volumetric shells of " << rows.size() << " inputs</h1><p class=\"lead\">" << ok
    << " written, " << rows.size() - ok << " failed.</p>\n<table>\n<tr><th></th><th>input</th>"
    << "<th>status</th><th>tets</th><th>coverage</th><th>quality min / median</th>"
    << "<th>seconds</th></tr>\n";
  for (const HtmlIndexRow& r : rows) {
    h << "<tr><td>";
    if (!r.thumbnail.empty())
      h << "<a href=\"" << escape(r.page) << "\"><img class=\"pic\" width=\"200\" height=\"160\" "
        << "alt=\"" << escape(r.input) << "\" src=\"data:image/png;base64," << base64(r.thumbnail)
        << "\"></a>";
    h << "</td><td>"
      << (r.page.empty() ? escape(r.input)
                         : "<a href=\"" + escape(r.page) + "\">" + escape(r.input) + "</a>")
      << "</td>";
    if (r.error.empty())
      h << "<td class=\"ok\">ok</td><td>" << r.tets << "</td><td>" << num(r.coverage, 4)
        << "</td><td>" << num(r.min_quality, 3) << " / " << num(r.median_quality, 3) << "</td><td>"
        << num(r.seconds, 3) << "</td></tr>\n";
    else
      h << "<td class=\"bad\" colspan=\"5\">error: " << escape(r.error) << "</td></tr>\n";
  }
  h << "</table></body></html>\n";
  return h.str();
}

}  // namespace vdb_shell
