#include <tbs/errors.h>
#include <tbs/image_export.h>
#include <tbs/io.h>

#include <ImathBox.h>
#include <ImfBoxAttribute.h>
#include <ImfChannelList.h>
#include <ImfDoubleAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIntAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>

#include <stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <array>
#include <deque>
#include <string>
#include <vector>

namespace tbs {

void write_error_exr(const std::string& path, const ErrorMap& m, ErrorMeasure measure, const ExrOptions& o) {
  const size_t np = static_cast<size_t>(m.width) * static_cast<size_t>(m.height);
  if (m.width < 1 || m.height < 1 || m.mask.size() != np)
    throw InvalidInput(path + ": the error map is empty or inconsistent");
  // Every channel as its own float plane. A deque, because plane() hands out references that
  // must stay valid while more planes are added.
  std::deque<std::pair<std::string, std::vector<float>>> planes;
  auto plane = [&](const std::string& name) -> std::vector<float>& {
    planes.emplace_back(name, std::vector<float>(np));
    return planes.back().second;
  };
  {
    auto& e = plane("error");
    auto& se = plane("signed_error");
    auto& r = plane("rms");
    auto& c = plane("count");
    auto& k = plane("mask");
    auto& t = plane("triangle");
    for (size_t i = 0; i < np; ++i) {
      e[i] = m.error[i];
      se[i] = m.signed_error[i];
      r[i] = m.rms[i];
      c[i] = static_cast<float>(m.count[i]);
      k[i] = static_cast<float>(static_cast<int>(m.mask[i]));
      t[i] = static_cast<float>(m.triangle[i]);
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    const char* suffix[3] = {"X", "Y", "Z"};
    auto& p = plane(std::string("P.") + suffix[axis]);
    auto& n = plane(std::string("N.") + suffix[axis]);
    for (size_t i = 0; i < np; ++i) {
      p[i] = m.position[3 * i + axis];
      n[i] = m.normal[3 * i + axis];
    }
  }
  try {
    Imf::Header header(m.width, m.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const auto& [name, data] : planes) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    header.insert("tbs.domain", Imf::Box2fAttribute(Imath::Box2f(
                                    Imath::V2f(static_cast<float>(m.domain.min.x()), static_cast<float>(m.domain.min.y())),
                                    Imath::V2f(static_cast<float>(m.domain.max.x()), static_cast<float>(m.domain.max.y())))));
    header.insert("tbs.units", Imf::StringAttribute(o.units));
    header.insert("tbs.measure", Imf::StringAttribute(measure == ErrorMeasure::Closest ? "closest" : "parameter"));
    if (o.tolerance > 0) header.insert("tbs.tolerance", Imf::DoubleAttribute(o.tolerance));
    header.insert("tbs.max", Imf::DoubleAttribute(m.stats.max));
    header.insert("tbs.rms", Imf::DoubleAttribute(m.stats.rms));
    header.insert("tbs.p95", Imf::DoubleAttribute(m.stats.p95));
    header.insert("tbs.points", Imf::IntAttribute(static_cast<int>(m.stats.count)));
    Imf::FrameBuffer fb;
    for (auto& [name, data] : planes)
      fb.insert(name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(data.data()), sizeof(float),
                                 sizeof(float) * static_cast<size_t>(m.width)));
    AtomicOutput out(path);
    {
      Imf::OutputFile file(out.temp_path().c_str(), header);
      file.setFrameBuffer(fb);
      file.writePixels(m.height);
    }
    out.commit();
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw IoError(path + ": OpenEXR could not write the file: " + e.what());
  }
}

namespace {

void collect_png(void* context, void* data, int size) {
  auto* out = static_cast<std::string*>(context);
  out->append(static_cast<const char*>(data), static_cast<size_t>(size));
}

}  // namespace

void write_error_png(const std::string& path, const ErrorMap& m, double scale_max) {
  const size_t np = static_cast<size_t>(m.width) * static_cast<size_t>(m.height);
  if (m.width < 1 || m.height < 1 || m.mask.size() != np)
    throw InvalidInput(path + ": the error map is empty or inconsistent");
  if (!(scale_max > 0)) scale_max = m.stats.max > 0 ? m.stats.max : 1.0;
  const int bar = 12, h = m.height + bar;
  std::vector<uint8_t> rgba(static_cast<size_t>(m.width) * h * 4, 0);
  for (size_t i = 0; i < np; ++i) {
    if (m.mask[i] == PixelKind::Outside) continue;
    auto c = heat_colour(m.error[i] / scale_max);
    if (m.mask[i] == PixelKind::Interpolated)
      for (auto& v : c) v = static_cast<uint8_t>((v + 255) / 2);
    for (int k = 0; k < 3; ++k) rgba[4 * i + k] = c[k];
    rgba[4 * i + 3] = 255;
  }
  for (int y = m.height + 2; y < h; ++y)
    for (int x = 0; x < m.width; ++x) {
      const auto c = heat_colour(m.width > 1 ? double(x) / (m.width - 1) : 0.0);
      const size_t i = static_cast<size_t>(y) * m.width + x;
      for (int k = 0; k < 3; ++k) rgba[4 * i + k] = c[k];
      rgba[4 * i + 3] = 255;
    }
  std::string png;
  if (!stbi_write_png_to_func(collect_png, &png, m.width, h, 4, rgba.data(), m.width * 4))
    throw IoError(path + ": stb could not encode the PNG");
  write_file_atomic(path, png);
}

}  // namespace tbs
