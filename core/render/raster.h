// raster.h — the software rasterizer behind the HTML report's pictures: orthographic cameras, a
// supersampled colour + depth canvas for triangles and lines, and PNG encoding.
//
// Conventions: picture pixels have x to the right and y down; a camera maps world units to
// pixels with one scale (orthographic: no perspective, so lengths on the picture plane are to
// scale). Everything is single-threaded and deterministic: the same calls give the same bytes.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/base/vec3.h"

namespace vdb_shell {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
};

/// `c` with every channel times `f` (clamped to [0, 255]).
Rgb scaled(const Rgb& c, double f);
/// (1 - t) a + t b, channel by channel.
Rgb mix(const Rgb& a, const Rgb& b, double t);
/// "#rrggbb".
std::string hex(const Rgb& c);

/// An 8-bit RGB picture, rows top to bottom.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<Rgb> pixels;  ///< width * height, row by row
  Rgb at(int x, int y) const { return pixels[std::size_t(y) * width + x]; }
};

/// The PNG file of `image` (8-bit RGB, no ancillary chunks: the same image gives the same bytes).
/// \throw ResourceError if libpng fails.
std::string encode_png(const Image& image);

/// An orthographic view. project() gives picture pixels (x right, y down) and a depth that
/// grows away from the viewer.
struct Camera {
  Vec3d centre;      ///< world point at the picture's centre
  Vec3d right;       ///< unit world direction of picture x
  Vec3d up;          ///< unit world direction of picture -y
  Vec3d forward;     ///< unit viewing direction (from the viewer into the scene)
  double scale = 1;  ///< pixels per world unit
  int width = 0, height = 0;

  /// A camera looking along `forward` at the centre of `bounds`, the world vector `up_hint`
  /// (projected) pointing up the picture, scaled so the projected corners of `bounds` fill
  /// `fill` of the picture in its tighter direction.
  static Camera framing(const BBox& bounds, const Vec3d& forward, const Vec3d& up_hint, int width,
                        int height, double fill = 0.94);

  Vec3d project(const Vec3d& p) const {
    const Vec3d d = p - centre;
    return {0.5 * width + scale * dot(d, right), 0.5 * height - scale * dot(d, up),
            dot(d, forward)};
  }
};

/// A picture being drawn: colour and depth at `supersample`² samples per pixel, reduced to an
/// Image (box filter) by resolve().
class Canvas {
 public:
  Canvas(const Camera& camera, int supersample, Rgb background);

  const Camera& camera() const { return camera_; }

  /// Draws world triangle (a, b, c), depth-tested, colours interpolated from its corners'.
  /// With `edge_shade` < 1, samples within about one pixel of an edge are darkened by that
  /// factor (wireframe over the fill) when every edge is at least `min_edge_px` pixels long.
  void triangle(const Vec3d& a, const Vec3d& b, const Vec3d& c, const std::array<Rgb, 3>& colour,
                double edge_shade = 1.0, double min_edge_px = 6.0);

  /// Draws world segment (a, b), `width_px` pixels wide, over everything (no depth test).
  void line(const Vec3d& a, const Vec3d& b, Rgb colour, double width_px = 1.0);

  /// Moves every sample drawn so far a fraction `t` of the way to `to` (an x-ray backdrop).
  void fade(Rgb to, double t);

  Image resolve() const;

 private:
  Camera camera_;  // at sample resolution
  int ss_;
  int w_, h_;
  std::vector<Rgb> colour_;
  std::vector<float> depth_;
};

/// Lambert shading for two-sided faces: `c` times ambient + diffuse |n . light|, with `n` the
/// face normal (any length; a zero normal gets the ambient term alone).
Rgb shade(const Rgb& c, const Vec3d& n, const Vec3d& light);

/// A piecewise-linear colour map: stops at increasing positions, clamped at both ends.
class ColourMap {
 public:
  struct Stop {
    double at;
    Rgb colour;
  };
  explicit ColourMap(std::vector<Stop> stops) : stops_(std::move(stops)) {}
  Rgb operator()(double x) const;
  const std::vector<Stop>& stops() const { return stops_; }

  /// Tet quality (volume-length ratio) in [0, 1]: dark red for flat tets through yellow to green.
  static const ColourMap& quality();
  /// A sequential map over [0, 1] (viridis): dark blue-purple for 0, yellow for 1.
  static const ColourMap& sequential();

 private:
  std::vector<Stop> stops_;
};

}  // namespace vdb_shell
