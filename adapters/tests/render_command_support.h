// What the tests that run raybridge-render as a subprocess share: its command line (RAYBRIDGE_RENDER overrides
// the path, e.g. on the GPU machine) and reading the EXR images it dumps.
#pragma once

#include <ImathBox.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace rbRenderTest {

// The quoted path of the render command, for building a shell command line.
inline std::string renderCommand() {
  const char* overridden = std::getenv("RAYBRIDGE_RENDER");
  return std::string("\"") + (overridden && *overridden ? overridden : RAYBRIDGE_RENDER_EXE) + "\"";
}

// Runs the render command with the validation layer on; returns its exit status.
inline int runRender(const std::string& args) {
  return std::system((renderCommand() + " --validation " + args).c_str());
}

inline std::vector<float> readExrRed(const std::filesystem::path& path, int& width, int& height) {
  Imf::InputFile file(path.string().c_str());
  Imath::Box2i dw = file.header().dataWindow();
  width = dw.max.x - dw.min.x + 1;
  height = dw.max.y - dw.min.y + 1;
  std::vector<float> red(size_t(width) * height);
  Imf::FrameBuffer fb;
  fb.insert("R", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(red.data() - dw.min.x - dw.min.y * width),
                            sizeof(float), sizeof(float) * width));
  file.setFrameBuffer(fb);
  file.readPixels(dw.min.y, dw.max.y);
  return red;
}

// R, G and B of an EXR image, interleaved, rows from the top.
inline std::vector<float> readExrRgb(const std::filesystem::path& path, int& width, int& height) {
  Imf::InputFile file(path.string().c_str());
  Imath::Box2i dw = file.header().dataWindow();
  width = dw.max.x - dw.min.x + 1;
  height = dw.max.y - dw.min.y + 1;
  std::vector<float> rgb(size_t(width) * height * 3);
  Imf::FrameBuffer fb;
  for (int c = 0; c < 3; ++c)
    fb.insert(c == 0   ? "R"
              : c == 1 ? "G"
                       : "B",
              Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(rgb.data() + c - 3 * (dw.min.x + dw.min.y * width)),
                         3 * sizeof(float), 3 * sizeof(float) * width));
  file.setFrameBuffer(fb);
  file.readPixels(dw.min.y, dw.max.y);
  return rgb;
}

}  // namespace rbRenderTest
