#include "dump_compare.h"

#include <ImathBox.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <vector>

namespace rbRender {

namespace {

struct Image {
  int width = 0, height = 0, channels = 0;
  std::vector<float> values;
};

// R, or R, G and B where the file has G.
Image readExr(const std::filesystem::path& path) {
  Imf::InputFile file(path.string().c_str());
  const Imath::Box2i dw = file.header().dataWindow();
  Image im;
  im.width = dw.max.x - dw.min.x + 1;
  im.height = dw.max.y - dw.min.y + 1;
  im.channels = file.header().channels().findChannel("G") ? 3 : 1;
  im.values.assign(size_t(im.width) * im.height * im.channels, 0.0f);
  Imf::FrameBuffer fb;
  const char* names[] = {"R", "G", "B"};
  const size_t pixel = sizeof(float) * im.channels;
  for (int c = 0; c < im.channels; ++c) {
    char* base = reinterpret_cast<char*>(im.values.data() + c) - (dw.min.x + size_t(dw.min.y) * im.width) * pixel;
    fb.insert(names[c], Imf::Slice(Imf::FLOAT, base, pixel, pixel * im.width));
  }
  file.setFrameBuffer(fb);
  file.readPixels(dw.min.y, dw.max.y);
  return im;
}

}  // namespace

nlohmann::json compareDumps(const std::filesystem::path& reference, const std::filesystem::path& test,
                            std::string& error) {
  nlohmann::json images = nlohmann::json::object();
  for (const char* name : {"shadow", "ao", "reflection", "lights"}) {
    const std::filesystem::path r = reference / (std::string(name) + ".exr");
    const std::filesystem::path t = test / (std::string(name) + ".exr");
    if (!std::filesystem::exists(r) || !std::filesystem::exists(t)) continue;
    Image a, b;
    try {
      a = readExr(r);
      b = readExr(t);
    } catch (const std::exception& e) {
      error = "--compare-with: cannot read " + r.string() + " or " + t.string() + ": " + e.what();
      return {};
    }
    if (a.width != b.width || a.height != b.height || a.channels != b.channels) {
      error = "--compare-with: " + r.string() + " is " + std::to_string(a.width) + "x" + std::to_string(a.height) +
              " but this run's is " + std::to_string(b.width) + "x" + std::to_string(b.height) +
              ": compare dumps of the same size and effects";
      return {};
    }
    double squared = 0.0, referenceSquared = 0.0;
    for (size_t i = 0; i < a.values.size(); ++i) {
      const double d = double(b.values[i]) - double(a.values[i]);
      squared += d * d;
      referenceSquared += double(a.values[i]) * double(a.values[i]);
    }
    const double n = double(std::max<size_t>(a.values.size(), 1));
    const double rmse = std::sqrt(squared / n), rms = std::sqrt(referenceSquared / n);
    images[name] = {{"rmse", rmse}, {"relative_rmse", rms > 0.0 ? rmse / rms : 0.0}};
  }
  return {{"reference", reference.string()}, {"images", images}};
}

}  // namespace rbRender
