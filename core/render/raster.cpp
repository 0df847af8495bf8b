#include "core/render/raster.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <limits>

#include "core/base/errors.h"

namespace vdb_shell {

namespace {

std::uint8_t clamp_channel(double v) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
}

void append_png(png_structp png, png_bytep data, png_size_t length) {
  static_cast<std::string*>(png_get_io_ptr(png))
      ->append(reinterpret_cast<const char*>(data), length);
}

void flush_png(png_structp) {}

}  // namespace

Rgb scaled(const Rgb& c, double f) {
  return {clamp_channel(c.r * f), clamp_channel(c.g * f), clamp_channel(c.b * f)};
}

Rgb mix(const Rgb& a, const Rgb& b, double t) {
  return {clamp_channel(a.r + (b.r - a.r) * t), clamp_channel(a.g + (b.g - a.g) * t),
          clamp_channel(a.b + (b.b - a.b) * t)};
}

std::string hex(const Rgb& c) {
  static const char* digits = "0123456789abcdef";
  std::string s = "#";
  for (const std::uint8_t v : {c.r, c.g, c.b}) {
    s += digits[v >> 4];
    s += digits[v & 15];
  }
  return s;
}

std::string encode_png(const Image& image) {
  std::string out;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, nullptr);
    throw ResourceError("PNG encoding: libpng could not start (out of memory?)");
  }
  std::vector<png_bytep> rows(image.height);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw ResourceError("PNG encoding of a " + std::to_string(image.width) + "x" +
                        std::to_string(image.height) + " picture failed in libpng");
  }
  png_set_write_fn(png, &out, append_png, flush_png);
  png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, 6);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y)
    rows[y] =
        reinterpret_cast<png_bytep>(const_cast<Rgb*>(&image.pixels[std::size_t(y) * image.width]));
  png_write_image(png, rows.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

Camera Camera::framing(const BBox& bounds, const Vec3d& forward, const Vec3d& up_hint, int width,
                       int height, double fill) {
  Camera c;
  c.width = width;
  c.height = height;
  c.forward = normalized(forward);
  Vec3d up = up_hint - c.forward * dot(up_hint, c.forward);
  if (!(norm(up) > 1e-9)) {  // looking along up_hint: any perpendicular will do
    const Vec3d other = std::fabs(c.forward.x) < 0.9 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
    up = other - c.forward * dot(other, c.forward);
  }
  c.up = normalized(up);
  c.right = cross(c.forward, c.up);  // x right, y up, looking along forward: right-handed
  // Fit the box's corners as projected: centred, `fill` of the picture in its tighter direction.
  c.centre = bounds.empty() ? Vec3d{} : (bounds.lo + bounds.hi) * 0.5;
  double ex = 0, ey = 0;
  for (int k = 0; k < 8; ++k) {
    const Vec3d corner{(k & 1) ? bounds.hi.x : bounds.lo.x, (k & 2) ? bounds.hi.y : bounds.lo.y,
                       (k & 4) ? bounds.hi.z : bounds.lo.z};
    const Vec3d d = bounds.empty() ? Vec3d{} : corner - c.centre;
    ex = std::max(ex, std::fabs(dot(d, c.right)));
    ey = std::max(ey, std::fabs(dot(d, c.up)));
  }
  c.scale = ex > 0 || ey > 0 ? fill * std::min(ex > 0 ? 0.5 * width / ex : INFINITY,
                                               ey > 0 ? 0.5 * height / ey : INFINITY)
                             : 1.0;
  return c;
}

Canvas::Canvas(const Camera& camera, int supersample, Rgb background)
    : camera_(camera), ss_(std::max(1, supersample)) {
  camera_.scale *= ss_;
  camera_.width *= ss_;
  camera_.height *= ss_;
  w_ = camera_.width;
  h_ = camera_.height;
  colour_.assign(std::size_t(w_) * h_, background);
  depth_.assign(std::size_t(w_) * h_, std::numeric_limits<float>::infinity());
}

void Canvas::triangle(const Vec3d& a, const Vec3d& b, const Vec3d& c,
                      const std::array<Rgb, 3>& colour, double edge_shade, double min_edge_px) {
  const Vec3d p[3] = {camera_.project(a), camera_.project(b), camera_.project(c)};
  const double area = (p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[2].x - p[0].x) * (p[1].y - p[0].y);
  if (!(std::fabs(area) > 1e-12)) return;
  const double x0 = std::floor(std::min({p[0].x, p[1].x, p[2].x}));
  const double x1 = std::ceil(std::max({p[0].x, p[1].x, p[2].x}));
  const double y0 = std::floor(std::min({p[0].y, p[1].y, p[2].y}));
  const double y1 = std::ceil(std::max({p[0].y, p[1].y, p[2].y}));
  const int xa = std::max(0, int(x0)), xb = std::min(w_ - 1, int(x1));
  const int ya = std::max(0, int(y0)), yb = std::min(h_ - 1, int(y1));
  if (xa > xb || ya > yb) return;
  // Edge i is opposite corner i; its length in samples scales the barycentric to a distance.
  double edge_len[3];
  bool wire = edge_shade < 1.0;
  for (int i = 0; i < 3; ++i) {
    const Vec3d& u = p[(i + 1) % 3];
    const Vec3d& v = p[(i + 2) % 3];
    edge_len[i] = std::hypot(v.x - u.x, v.y - u.y);
    if (edge_len[i] < min_edge_px * ss_) wire = false;
  }
  const double wire_width = 0.55 * ss_;
  const double inv = 1.0 / area;
  for (int y = ya; y <= yb; ++y) {
    const double sy = y + 0.5;
    for (int x = xa; x <= xb; ++x) {
      const double sx = x + 0.5;
      double l[3];
      for (int i = 0; i < 3; ++i) {
        const Vec3d& u = p[(i + 1) % 3];
        const Vec3d& v = p[(i + 2) % 3];
        l[i] = ((v.x - u.x) * (sy - u.y) - (sx - u.x) * (v.y - u.y)) * inv;
      }
      if (l[0] < 0 || l[1] < 0 || l[2] < 0) continue;
      const float z = float(l[0] * p[0].z + l[1] * p[1].z + l[2] * p[2].z);
      const std::size_t k = std::size_t(y) * w_ + x;
      if (!(z < depth_[k])) continue;
      depth_[k] = z;
      Rgb col = colour[0];
      if (!(colour[0] == colour[1] && colour[0] == colour[2])) {
        double r = 0, g = 0, bl = 0;
        for (int i = 0; i < 3; ++i) {
          r += l[i] * colour[i].r;
          g += l[i] * colour[i].g;
          bl += l[i] * colour[i].b;
        }
        col = {clamp_channel(r), clamp_channel(g), clamp_channel(bl)};
      }
      if (wire) {
        const double area_abs = std::fabs(area);
        for (int i = 0; i < 3; ++i)
          if (l[i] * area_abs / edge_len[i] < wire_width) {
            col = scaled(col, edge_shade);
            break;
          }
      }
      colour_[k] = col;
    }
  }
}

void Canvas::line(const Vec3d& a, const Vec3d& b, Rgb colour, double width_px) {
  const Vec3d p = camera_.project(a), q = camera_.project(b);
  const double len = std::hypot(q.x - p.x, q.y - p.y);
  const int steps = std::max(1, int(std::ceil(len * 2)));
  const double r = std::max(0.5, 0.5 * width_px * ss_);
  for (int s = 0; s <= steps; ++s) {
    const double t = double(s) / steps;
    const double cx = p.x + (q.x - p.x) * t, cy = p.y + (q.y - p.y) * t;
    const int xa = std::max(0, int(std::floor(cx - r + 0.5)));
    const int xb = std::min(w_ - 1, int(std::floor(cx + r - 0.5)));
    const int ya = std::max(0, int(std::floor(cy - r + 0.5)));
    const int yb = std::min(h_ - 1, int(std::floor(cy + r - 0.5)));
    for (int y = ya; y <= yb; ++y)
      for (int x = xa; x <= xb; ++x) colour_[std::size_t(y) * w_ + x] = colour;
  }
}

void Canvas::fade(Rgb to, double t) {
  for (Rgb& c : colour_) c = mix(c, to, t);
}

Image Canvas::resolve() const {
  Image image;
  image.width = w_ / ss_;
  image.height = h_ / ss_;
  image.pixels.resize(std::size_t(image.width) * image.height);
  const int n = ss_ * ss_;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      int r = 0, g = 0, b = 0;
      for (int dy = 0; dy < ss_; ++dy)
        for (int dx = 0; dx < ss_; ++dx) {
          const Rgb& c = colour_[std::size_t(y * ss_ + dy) * w_ + (x * ss_ + dx)];
          r += c.r;
          g += c.g;
          b += c.b;
        }
      image.pixels[std::size_t(y) * image.width + x] = {std::uint8_t((r + n / 2) / n),
                                                        std::uint8_t((g + n / 2) / n),
                                                        std::uint8_t((b + n / 2) / n)};
    }
  return image;
}

Rgb shade(const Rgb& c, const Vec3d& n, const Vec3d& light) {
  const double len = norm(n);
  const double diffuse = len > 0 ? std::fabs(dot(n, light)) / (len * norm(light)) : 0.0;
  return scaled(c, 0.38 + 0.62 * diffuse);
}

Rgb ColourMap::operator()(double x) const {
  if (!(x > stops_.front().at)) return stops_.front().colour;
  for (std::size_t i = 1; i < stops_.size(); ++i)
    if (x <= stops_[i].at) {
      const double t = (x - stops_[i - 1].at) / (stops_[i].at - stops_[i - 1].at);
      return mix(stops_[i - 1].colour, stops_[i].colour, t);
    }
  return stops_.back().colour;
}

const ColourMap& ColourMap::quality() {
  static const ColourMap map({{0.0, {165, 0, 38}},
                              {0.08, {215, 48, 39}},
                              {0.16, {244, 109, 67}},
                              {0.25, {253, 174, 97}},
                              {0.35, {254, 224, 139}},
                              {0.5, {166, 217, 106}},
                              {0.7, {26, 152, 80}},
                              {1.0, {0, 104, 55}}});
  return map;
}

const ColourMap& ColourMap::sequential() {
  static const ColourMap map({{0.0, {68, 1, 84}},
                              {0.25, {59, 82, 139}},
                              {0.5, {33, 145, 140}},
                              {0.75, {94, 201, 98}},
                              {1.0, {253, 231, 37}}});
  return map;
}

}  // namespace vdb_shell
