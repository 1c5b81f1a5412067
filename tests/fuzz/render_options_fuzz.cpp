// libFuzzer target: raybridge-render's command line (parseRenderOptions, then resolve() as main() does).
//
// Input: the arguments after the program name, separated by NUL bytes or newlines ("--width\n640\n--mode\nraster");
// empty pieces are kept as empty arguments. A parse either fails with a message or gives options within the
// ranges the parser promises (checked below; a breach aborts like a crash, since main() uses them unchecked).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "render_options.h"

namespace {

[[noreturn]] void breach(const std::string& what) {
  std::fprintf(stderr, "render_options_fuzz: parsed options break the parser's promise: %s\n", what.c_str());
  std::abort();
}

void check(bool ok, const char* what) {
  if (!ok) breach(what);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  rbRender::renderUsage();  // builds the help once (static), as --help does
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > 4096) return 0;  // a command line, not a file
  std::vector<std::string> args{"raybridge-render"};
  if (size > 0) {
    args.emplace_back();
    for (size_t i = 0; i < size; ++i) {
      const char c = char(data[i]);
      if (c == '\0' || c == '\n') args.emplace_back();
      else
        args.back() += c;
    }
  }
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  rbRender::RenderOptions o;
  const std::string error = rbRender::parseRenderOptions(int(args.size()), argv.data(), o);
  if (!error.empty() || o.help) return 0;
  check(o.width >= 1 && o.width <= 16384 && o.height >= 1 && o.height <= 16384, "--width/--height range");
  check(uint64_t(o.width) * o.height <= uint64_t(8192) * 8192, "at most 67 megapixels");
  check(o.frames >= 1, "--frames >= 1");
  check(std::isfinite(o.time) && o.time >= 0.0, "--time finite and >= 0");
  check(!o.fps || (std::isfinite(*o.fps) && *o.fps > 0.0), "--fps finite and > 0");
  if (o.eye) {
    check(o.target.has_value(), "--camera sets eye and target");
    check(*o.eye != *o.target, "--camera eye differs from target");
    check(o.fovYDegrees >= rbRender::kMinFovYDegrees && o.fovYDegrees < rbRender::kMaxFovYDegrees,
          "--camera fov in [kMinFovYDegrees, kMaxFovYDegrees)");
    for (int c = 0; c < 3; ++c)
      check(std::abs((*o.eye)[c]) <= rbRender::kMaxCameraCoordinate &&
                std::abs((*o.target)[c]) <= rbRender::kMaxCameraCoordinate,
            "--camera coordinates within kMaxCameraCoordinate");
    const glm::vec3 forward = *o.target - *o.eye;  // as the engine's view matrix computes it, in float
    check(std::isfinite(glm::dot(forward, forward)) && glm::dot(forward, forward) > 0.0f,
          "--camera has a view direction in float");
  }
  check(!o.sun || std::abs(glm::length(*o.sun) - 1.0f) < 1e-5f, "--sun is a unit vector");
  check(!o.sunRadiusDegrees || (*o.sunRadiusDegrees >= 0.0f && *o.sunRadiusDegrees < 45.0f), "--sun-radius range");
  check(!o.aoRange || (std::isfinite(*o.aoRange) && *o.aoRange > 0.0f), "--ao-range finite and > 0");
  check(!o.reflectionRoughness || (*o.reflectionRoughness > 0.0f && *o.reflectionRoughness <= 1.0f),
        "--reflection-roughness range");
  check(!o.shadowMapSize || *o.shadowMapSize == 0 || (*o.shadowMapSize >= 1024 && *o.shadowMapSize <= 8192),
        "--shadow-map-size range");
  check(!o.pcfKernel || (*o.pcfKernel >= 1 && *o.pcfKernel <= 9), "--pcf range");
  check(o.cameraPath.empty() || !o.eye, "--camera-path excludes --camera");

  const rbRender::ResolvedEffects r = rbRender::resolve(o);
  check(r.hybrid.shadows.raysPerPixel >= 1 && r.hybrid.ao.raysPerPixel >= 1 && r.hybrid.reflections.raysPerPixel >= 1,
        "resolved ray counts >= 1");
  check(std::isfinite(r.sunRadiusDegrees) && r.sunRadiusDegrees >= 0.0f, "resolved sun radius");
  rb::EffectSet reparsed = 0;
  check(rbRender::parseEffectSet(rbRender::effectSetToString(r.hybrid.effects), reparsed).empty() &&
            reparsed == r.hybrid.effects,
        "the resolved effect set prints as the same list");
  return 0;
}
