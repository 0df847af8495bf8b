#include "core/render/raster.h"

#include <gtest/gtest.h>
#include <png.h>

#include <cmath>
#include <string>

#include "assets/shapes.h"
#include "core/render/pictures.h"

namespace vdb_shell {
namespace {

/// Pixels of `image` that are not the white background.
std::size_t drawn_pixels(const Image& image) {
  std::size_t n = 0;
  for (const Rgb& c : image.pixels) n += !(c == kBackground);
  return n;
}

/// `png` decoded by libpng (an implementation other than the encoder's calls).
Image decode_png(const std::string& png) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  EXPECT_TRUE(png_image_begin_read_from_memory(&img, png.data(), png.size())) << img.message;
  img.format = PNG_FORMAT_RGB;
  Image out;
  out.width = int(img.width);
  out.height = int(img.height);
  out.pixels.resize(std::size_t(out.width) * out.height);
  EXPECT_TRUE(png_image_finish_read(&img, nullptr, out.pixels.data(), 0, nullptr)) << img.message;
  return out;
}

Camera looking_down(double scale, int w, int h) {
  Camera c;
  c.centre = {0, 0, 0};
  c.right = {1, 0, 0};
  c.up = {0, 1, 0};
  c.forward = {0, 0, -1};
  c.scale = scale;
  c.width = w;
  c.height = h;
  return c;
}

TEST(Raster, ASquareCoversItsAreaInPixels) {
  // A 0.5 x 0.5 square at 100 px per unit covers 50 x 50 pixels, half of their samples on its
  // diagonal going to each triangle and none counted twice.
  Canvas canvas(looking_down(100, 120, 100), 3, kBackground);
  const Rgb red{200, 0, 0};
  canvas.triangle({-0.25, -0.25, 0}, {0.25, -0.25, 0}, {0.25, 0.25, 0}, {red, red, red});
  canvas.triangle({-0.25, -0.25, 0}, {0.25, 0.25, 0}, {-0.25, 0.25, 0}, {red, red, red});
  const Image image = canvas.resolve();
  EXPECT_EQ(drawn_pixels(image), 2500u);
  EXPECT_EQ(image.at(60, 50), red);  // the centre
  EXPECT_EQ(image.at(35, 50), red);  // x = -0.25 is pixel 35's left side
  EXPECT_EQ(image.at(34, 50), kBackground);
  EXPECT_EQ(image.at(84, 50), red);  // x = 0.25 is pixel 84's right side
  EXPECT_EQ(image.at(85, 50), kBackground);
}

TEST(Raster, TheNearerTriangleWinsInEitherOrder) {
  const Rgb near{0, 0, 200}, far{0, 200, 0};
  for (int order = 0; order < 2; ++order) {
    Canvas canvas(looking_down(100, 40, 40), 1, kBackground);
    auto draw = [&](double z, Rgb c) {
      canvas.triangle({-0.2, -0.2, z}, {0.2, -0.2, z}, {0, 0.2, z}, {c, c, c});
    };
    if (order == 0) {
      draw(0.5, near);  // forward is -z: z = 0.5 is nearer the viewer
      draw(-0.5, far);
    } else {
      draw(-0.5, far);
      draw(0.5, near);
    }
    EXPECT_EQ(canvas.resolve().at(20, 22), near) << order;
  }
}

TEST(Raster, ASphereSilhouetteIsItsDiscAndFramingFitsTheBox) {
  const SurfaceMesh sphere = make_shape("sphere", 2);  // radius 0.5
  const BBox box = bounding_box(sphere);
  for (const Vec3d& forward : {Vec3d{0, 1, 0}, Vec3d{-0.55, 1.0, -0.45}}) {
    const Camera camera = Camera::framing(box, forward, {0, 0, 1}, 300, 200);
    const std::vector<Rgb> grey(3 * sphere.triangles.size(), Rgb{120, 120, 120});
    const Image image = render_surface(sphere, grey, camera, 2);
    const double disc = kPi * std::pow(0.5 * camera.scale, 2);
    EXPECT_NEAR(double(drawn_pixels(image)), disc, 0.02 * disc) << forward.x;
    // The box's projected corners fill 0.94 of the height, so the disc does not touch it.
    EXPECT_LT(0.5 * camera.scale * 2, 200 * 0.94 + 1e-9);
    EXPECT_EQ(image.at(0, 0), kBackground);
    EXPECT_FALSE(image.at(150, 100) == kBackground);
  }
}

TEST(Raster, PngRoundTripsAndIsTheSameBytesEachTime) {
  Image image;
  image.width = 7;
  image.height = 5;
  for (int i = 0; i < 35; ++i)
    image.pixels.push_back({std::uint8_t(i * 7), std::uint8_t(255 - i), std::uint8_t(i * i)});
  const std::string png = encode_png(image);
  EXPECT_EQ(png, encode_png(image));
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  const Image back = decode_png(png);
  ASSERT_EQ(back.width, 7);
  ASSERT_EQ(back.height, 5);
  EXPECT_TRUE(back.pixels == image.pixels);
}

TEST(Raster, LinesDrawOverEverythingAndColourMapsClamp) {
  Canvas canvas(looking_down(100, 40, 40), 2, kBackground);
  const Rgb grey{90, 90, 90}, blue{0, 0, 255};
  canvas.triangle({-0.2, -0.2, 1}, {0.2, -0.2, 1}, {0, 0.2, 1}, {grey, grey, grey});
  canvas.line({-0.15, 0, -1}, {0.15, 0, -1}, blue, 2.0);  // behind the triangle, drawn anyway
  const Image image = canvas.resolve();
  EXPECT_EQ(image.at(20, 19), blue);  // rows 19 and 20 on either side of y = 0
  EXPECT_EQ(image.at(20, 20), blue);
  EXPECT_EQ(image.at(20, 24), grey);
  const ColourMap& q = ColourMap::quality();
  EXPECT_EQ(q(-1.0), q(0.0));
  EXPECT_EQ(q(2.0), q(1.0));
  EXPECT_EQ(hex(q(1.0)), "#006837");
}

}  // namespace
}  // namespace vdb_shell
