// PNG/EXR writers and the CPU reference of the tonemap shader.
#include <algorithm>
#include <cmath>

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfRgbaFile.h>

#include "sample_engine/image_io.h"

namespace sample_engine {

Status writePng(const std::string& path, const ImageRGBA8& image) {
  if (image.width == 0 || image.height == 0 || image.pixels.size() != size_t(image.width) * image.height * 4)
    return Status::failure("writePng: empty or inconsistent image");
  if (!stbi_write_png(path.c_str(), int(image.width), int(image.height), 4, image.pixels.data(), int(image.width * 4)))
    return Status::failure("writePng: cannot write " + path);
  return Status::success();
}

Status writeExr(const std::string& path, const ImageRGBA32F& image, bool halfFloat) {
  if (image.width == 0 || image.height == 0 || image.pixels.size() != size_t(image.width) * image.height * 4)
    return Status::failure("writeExr: empty or inconsistent image");
  try {
    const int w = int(image.width), h = int(image.height);
    if (halfFloat) {
      std::vector<Imf::Rgba> px(size_t(w) * h);
      for (size_t i = 0; i < px.size(); ++i)
        px[i] = Imf::Rgba(image.pixels[i * 4], image.pixels[i * 4 + 1], image.pixels[i * 4 + 2],
                          image.pixels[i * 4 + 3]);
      Imf::RgbaOutputFile file(path.c_str(), w, h, Imf::WRITE_RGBA);
      file.setFrameBuffer(px.data(), 1, size_t(w));
      file.writePixels(h);
    } else {
      Imf::Header header(w, h);
      const char* names[4] = {"R", "G", "B", "A"};
      for (const char* n : names) header.channels().insert(n, Imf::Channel(Imf::FLOAT));
      Imf::OutputFile file(path.c_str(), header);
      Imf::FrameBuffer fb;
      char* base = reinterpret_cast<char*>(const_cast<float*>(image.pixels.data()));
      for (int c = 0; c < 4; ++c)
        fb.insert(names[c],
                  Imf::Slice(Imf::FLOAT, base + c * sizeof(float), 4 * sizeof(float), 4 * sizeof(float) * size_t(w)));
      file.setFrameBuffer(fb);
      file.writePixels(h);
    }
  } catch (const std::exception& e) {
    return Status::failure("writeExr: " + std::string(e.what()));
  }
  return Status::success();
}

// Must match shaders/tonemap.frag.
glm::vec3 tonemapLinear(const glm::vec3& hdr, float exposure) {
  glm::vec3 x = glm::max(hdr * exposure, glm::vec3(0.0f));
  // Narkowicz's ACES filmic fit.
  glm::vec3 y = (x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f);
  return glm::clamp(y, glm::vec3(0.0f), glm::vec3(1.0f));
}

glm::u8vec3 tonemapToSrgb8(const glm::vec3& hdr, float exposure) {
  glm::vec3 l = tonemapLinear(hdr, exposure);
  glm::u8vec3 out;
  for (int c = 0; c < 3; ++c) {
    float v = l[c] <= 0.0031308f ? 12.92f * l[c] : 1.055f * std::pow(l[c], 1.0f / 2.4f) - 0.055f;
    out[c] = static_cast<uint8_t>(std::clamp(v * 255.0f + 0.5f, 0.0f, 255.0f));
  }
  return out;
}

}  // namespace sample_engine
