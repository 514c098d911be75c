// Error maps written as OpenEXR and read back with OpenEXR: channels, attributes, values.
#include <tbs/error_map.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/image_export.h>

#include "random_spline.h"

#include <ImfBoxAttribute.h>
#include <ImfChannelList.h>
#include <ImfDoubleAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfIntAttribute.h>
#include <ImfStringAttribute.h>
#include <gtest/gtest.h>
#include <stb_image.h>

#include <filesystem>

namespace tbs {
namespace {

namespace fs = std::filesystem;

TEST(Exr, ReadsBackWithTheChannelsAttributesAndValuesWritten) {
  test::GridOptions o;
  o.nx = o.ny = 6;
  o.hole = true;
  const Spline s = test::random_spline(3, o, 91);
  const Evaluator ev(s);
  const auto uv = test::random_domain_points(s.domain(), 3000, 4);
  std::vector<Point3> pts;
  for (size_t i = 0; i < uv.size(); ++i) pts.push_back(ev.value(uv[i]) + 1e-3 * std::sin(double(i)) * ev.normal(uv[i]));
  const PointErrors e = point_errors(s, pts, uv);
  const ErrorMap m = make_error_map(s, uv, e, {.width = 48, .height = 32});
  const fs::path file = fs::temp_directory_path() / ("tbs_exr_test_" + std::to_string(::getpid()) + ".exr");
  write_error_exr(file, m, ErrorMeasure::Parameter, {.units = "mm", .tolerance = 0.01});

  Imf::InputFile in(file.c_str());
  const Imf::Header& h = in.header();
  const auto dw = h.dataWindow();
  ASSERT_EQ(dw.max.x - dw.min.x + 1, 48);
  ASSERT_EQ(dw.max.y - dw.min.y + 1, 32);
  EXPECT_EQ(h.compression(), Imf::ZIP_COMPRESSION);
  for (const char* c : {"error", "signed_error", "rms", "count", "mask", "triangle", "P.X", "P.Y", "P.Z", "N.X", "N.Y", "N.Z"})
    EXPECT_NE(h.channels().findChannel(c), nullptr) << c;
  EXPECT_EQ(h.typedAttribute<Imf::StringAttribute>("tbs.units").value(), "mm");
  EXPECT_EQ(h.typedAttribute<Imf::StringAttribute>("tbs.measure").value(), "parameter");
  EXPECT_EQ(h.typedAttribute<Imf::DoubleAttribute>("tbs.tolerance").value(), 0.01);
  EXPECT_EQ(h.typedAttribute<Imf::DoubleAttribute>("tbs.max").value(), e.stats.max);
  EXPECT_EQ(h.typedAttribute<Imf::DoubleAttribute>("tbs.rms").value(), e.stats.rms);
  EXPECT_EQ(h.typedAttribute<Imf::IntAttribute>("tbs.points").value(), 3000);
  const auto box = h.typedAttribute<Imf::Box2fAttribute>("tbs.domain").value();
  EXPECT_EQ(box.min.x, static_cast<float>(m.domain.min.x()));
  EXPECT_EQ(box.max.y, static_cast<float>(m.domain.max.y()));

  const size_t np = 48 * 32;
  std::vector<float> err(np), mask(np), px(np), tri(np);
  Imf::FrameBuffer fb;
  auto slice = [&](std::vector<float>& v) { return Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(v.data()), sizeof(float), 48 * sizeof(float)); };
  fb.insert("error", slice(err));
  fb.insert("mask", slice(mask));
  fb.insert("P.X", slice(px));
  fb.insert("triangle", slice(tri));
  in.setFrameBuffer(fb);
  in.readPixels(dw.min.y, dw.max.y);
  fs::remove(file);
  int outside = 0;
  for (size_t i = 0; i < np; ++i) {
    ASSERT_EQ(err[i], m.error[i]);
    ASSERT_EQ(mask[i], static_cast<float>(static_cast<int>(m.mask[i])));
    ASSERT_EQ(px[i], m.position[3 * i]);
    ASSERT_EQ(tri[i], static_cast<float>(m.triangle[i]));
    outside += m.mask[i] == PixelKind::Outside;
  }
  EXPECT_GT(outside, 0);  // the hole
}

TEST(Png, PreviewDecodesWithTheMapsSizeAndTransparentOutside) {
  test::GridOptions o;
  o.nx = o.ny = 6;
  o.hole = true;
  const Spline s = test::random_spline(3, o, 93);
  const auto uv = test::random_domain_points(s.domain(), 2000, 6);
  const Evaluator ev(s);
  std::vector<Point3> pts;
  for (const auto& u : uv) pts.push_back(ev.value(u) + 1e-3 * ev.normal(u));
  const PointErrors e = point_errors(s, pts, uv);
  const ErrorMap m = make_error_map(s, uv, e, {.width = 40, .height = 30});
  const fs::path file = fs::temp_directory_path() / ("tbs_png_test_" + std::to_string(::getpid()) + ".png");
  write_error_png(file, m);
  int w = 0, h = 0, c = 0;
  unsigned char* img = stbi_load(file.c_str(), &w, &h, &c, 4);
  fs::remove(file);
  ASSERT_NE(img, nullptr);
  EXPECT_EQ(w, 40);
  EXPECT_EQ(h, 30 + 12);  // the map and the colour bar
  int transparent = 0, opaque = 0;
  for (size_t i = 0; i < m.mask.size(); ++i) {
    const unsigned char alpha = img[4 * i + 3];
    if (m.mask[i] == PixelKind::Outside) {
      EXPECT_EQ(alpha, 0);
      ++transparent;
    } else {
      EXPECT_EQ(alpha, 255);
      ++opaque;
    }
  }
  stbi_image_free(img);
  EXPECT_GT(transparent, 0);
  EXPECT_GT(opaque, 0);
}

TEST(Exr, AFailedWriteLeavesNothing) {
  const Spline s = test::random_spline(2, test::GridOptions{}, 92);
  const std::vector<Point2> uv = {Point2(0.5, 0.5)};
  const std::vector<Point3> pts = {Point3(0, 0, 0)};
  const PointErrors e = point_errors(s, pts, uv);
  const ErrorMap m = make_error_map(s, uv, e, {.width = 8});
  const fs::path dir = fs::temp_directory_path() / "tbs_no_such_dir_for_exr";
  EXPECT_THROW(write_error_exr(dir / "x.exr", m, ErrorMeasure::Parameter), IoError);
  EXPECT_FALSE(fs::exists(dir));
  EXPECT_THROW(write_error_exr(fs::temp_directory_path() / "x.exr", ErrorMap{}, ErrorMeasure::Parameter), InvalidInput);
}

}  // namespace
}  // namespace tbs
