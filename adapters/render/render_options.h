// Command line of raybridge-render: parsing and validation (every error names the option and the bad value).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <glm/glm.hpp>

namespace rbRender {

enum class Mode { Raster, Hybrid };

struct RenderOptions {
  std::string scene;  // empty = the engine's procedural demo scene
  uint32_t width = 1280, height = 720;
  // Eye, target, vertical fov in degrees; empty = the scene's own camera, else framed on the scene bounds.
  std::optional<glm::vec3> eye, target;
  float fovYDegrees = 0.0f;
  std::optional<glm::vec3> sun;  // towards the sun; empty = the scene's sun, else the engine's default
  float sunRadiusDegrees = 0.0f;
  uint32_t shadowRays = 8;
  Mode mode = Mode::Hybrid;
  std::string out = "out";
  bool dump = false;
  bool geometricNormals = false;
  uint32_t frames = 3;  // enough for the SDK's deferred statistics (resolved kFramesInFlight frames later)
  std::string device;
  bool validation = false;
  bool help = false;
};

// Parses argv; returns an error message naming the problem, or "" on success.
std::string parseRenderOptions(int argc, char** argv, RenderOptions& options);
const char* renderUsage();

}  // namespace rbRender
