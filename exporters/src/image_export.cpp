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

#include <exception>
#include <vector>

namespace tbs {

void write_error_exr(const std::string& path, const ErrorMap& m, ErrorMeasure measure, const ExrOptions& o) {
  const size_t np = static_cast<size_t>(m.width) * static_cast<size_t>(m.height);
  if (m.width < 1 || m.height < 1 || m.mask.size() != np)
    throw InvalidInput(path + ": the error map is empty or inconsistent");
  // Every channel as its own float plane.
  std::vector<std::pair<std::string, std::vector<float>>> planes;
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

}  // namespace tbs
