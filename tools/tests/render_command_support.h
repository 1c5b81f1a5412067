// What the tests that run raybridge-render as a subprocess share: its command line (RAYBRIDGE_RENDER overrides
// the path, e.g. on the GPU machine) and reading the EXR images it dumps.
#pragma once

#include <ImathBox.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

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

// Runs the render command with the validation layer; returns its output (stdout and stderr) and sets status.
inline std::string renderOutput(const std::string& args, int& status) {
  const std::string command = renderCommand() + " --validation " + args + " 2>&1";
  std::string text;
  status = -1;
  if (FILE* p = popen(command.c_str(), "r")) {
    char buf[512];
    while (fgets(buf, sizeof buf, p)) text += buf;
    status = pclose(p);
  }
  return text;
}

// The JSON file at `path`, or a discarded value (is_discarded()) when it is missing or malformed.
inline nlohmann::json readJson(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in, nullptr, false);
}

inline std::vector<float> readExrChannel(const std::filesystem::path& path, const char* channel, int& width,
                                         int& height) {
  Imf::InputFile file(path.string().c_str());
  Imath::Box2i dw = file.header().dataWindow();
  width = dw.max.x - dw.min.x + 1;
  height = dw.max.y - dw.min.y + 1;
  std::vector<float> values(size_t(width) * height);
  Imf::FrameBuffer fb;
  fb.insert(channel, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(values.data() - dw.min.x - dw.min.y * width),
                                sizeof(float), sizeof(float) * width));
  file.setFrameBuffer(fb);
  file.readPixels(dw.min.y, dw.max.y);
  return values;
}
inline std::vector<float> readExrRed(const std::filesystem::path& path, int& width, int& height) {
  return readExrChannel(path, "R", width, height);
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
