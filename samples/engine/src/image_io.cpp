// PNG/EXR writers and the CPU reference of the tonemap shader.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfRgbaFile.h>
#include <ImfStdIO.h>

#include "sample_engine/image_io.h"

namespace sample_engine {

Status writeFile(const std::string& path, std::string_view bytes) {
  errno = 0;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return Status::failure("cannot write " + path + ": " + std::strerror(errno));
  // fwrite buffers: a full disk may only show in fflush or fclose.
  int error = 0;
  if (std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size() || std::fflush(f) != 0) error = errno ? errno : EIO;
  if (std::fclose(f) != 0 && !error) error = errno ? errno : EIO;
  if (!error) return Status::success();
  const std::string reason = std::strerror(error);
  std::error_code ec;
  if (std::filesystem::is_regular_file(path, ec)) std::filesystem::remove(path, ec);
  return Status::failure("cannot write " + path + ": " + reason);
}

Status writePng(const std::string& path, const ImageRGBA8& image) {
  if (image.width == 0 || image.height == 0 || image.pixels.size() != size_t(image.width) * image.height * 4)
    return Status::failure("writePng: empty or inconsistent image");
  // stbi_write_png ignores the results of fwrite and fclose: encode here, write through writeFile.
  int size = 0;
  unsigned char* png = stbi_write_png_to_mem(image.pixels.data(), int(image.width * 4), int(image.width),
                                             int(image.height), 4, &size);
  if (!png) return Status::failure("writePng: cannot encode " + path);
  const Status s = writeFile(path, std::string_view(reinterpret_cast<const char*>(png), size_t(size)));
  STBIW_FREE(png);
  return s ? s : Status::failure("writePng: " + s.error);
}

Status writeExr(const std::string& path, const ImageRGBA32F& image, bool halfFloat) {
  if (image.width == 0 || image.height == 0 || image.pixels.size() != size_t(image.width) * image.height * 4)
    return Status::failure("writeExr: empty or inconsistent image");
  // OpenEXR's file stream leaves the last bytes to the ofstream's destructor, which reports no error: encode in
  // memory (the file objects finish the image when they go out of scope), write through writeFile.
  Imf::StdOSStream encoded;
  try {
    const int w = int(image.width), h = int(image.height);
    if (halfFloat) {
      std::vector<Imf::Rgba> px(size_t(w) * h);
      for (size_t i = 0; i < px.size(); ++i)
        px[i] = Imf::Rgba(image.pixels[i * 4], image.pixels[i * 4 + 1], image.pixels[i * 4 + 2],
                          image.pixels[i * 4 + 3]);
      Imf::Header header(w, h);
      header.compression() = Imf::PIZ_COMPRESSION;  // what RgbaOutputFile(name, w, h) wrote
      Imf::RgbaOutputFile file(encoded, header, Imf::WRITE_RGBA);
      file.setFrameBuffer(px.data(), 1, size_t(w));
      file.writePixels(h);
    } else {
      Imf::Header header(w, h);
      const char* names[4] = {"R", "G", "B", "A"};
      for (const char* n : names) header.channels().insert(n, Imf::Channel(Imf::FLOAT));
      Imf::OutputFile file(encoded, header);
      Imf::FrameBuffer fb;
      char* base = reinterpret_cast<char*>(const_cast<float*>(image.pixels.data()));
      for (int c = 0; c < 4; ++c)
        fb.insert(names[c],
                  Imf::Slice(Imf::FLOAT, base + c * sizeof(float), 4 * sizeof(float), 4 * sizeof(float) * size_t(w)));
      file.setFrameBuffer(fb);
      file.writePixels(h);
    }
  } catch (const std::exception& e) {
    return Status::failure("writeExr: " + path + ": " + std::string(e.what()));
  }
  const Status s = writeFile(path, encoded.str());
  return s ? s : Status::failure("writeExr: " + s.error);
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
