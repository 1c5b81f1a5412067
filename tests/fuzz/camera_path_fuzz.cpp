// libFuzzer target: camera-path files (samples/common/camera_path.h), parsed and then sampled as
// raybridge-render --camera-path does.
//
// Input: the file's text. A path that parses must keep the header's promises (checked below; a breach aborts like
// a crash): at least one keyframe, finite positions, unit orientations, durations > 0 but the last, fields of view
// in (0, 180); and every pose sampled from it, at any time, is finite with a unit orientation. A failed parse must
// leave the output unchanged and say why.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <string_view>

#include "camera_path.h"

namespace {

using namespace rbCameraPath;

[[noreturn]] void breach(const std::string& what) {
  std::fprintf(stderr, "camera_path_fuzz: %s\n", what.c_str());
  std::abort();
}

bool unit(const std::array<double, 4>& q) {
  const double length = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  return std::abs(length - 1.0) < 1e-9;
}

bool finite(const std::array<double, 3>& v) {
  return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

bool goodFov(double fov) { return fov > 0.0 && fov < 180.0; }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  CameraPath path;
  path.keys.resize(1);
  path.keys[0].duration = 42.0;  // a marker: an error must leave `path` as it was
  const std::string error = parseCameraPath(std::string_view(reinterpret_cast<const char*>(data), size), path);
  if (!error.empty()) {
    if (path.keys.size() != 1 || path.keys[0].duration != 42.0) breach("a failed parse changed its output");
    return 0;
  }
  if (path.keys.empty()) breach("a parsed path has no keyframe");
  for (size_t i = 0; i < path.keys.size(); ++i) {
    const CameraKey& k = path.keys[i];
    const std::string at = "keyframe " + std::to_string(i) + ": ";
    if (!finite(k.position)) breach(at + "position is not finite");
    if (!unit(k.orientation)) breach(at + "orientation is not a unit quaternion");
    if (i + 1 < path.keys.size() && !(k.duration > 0.0 && std::isfinite(k.duration)))
      breach(at + "duration is not finite and > 0");
    if (!goodFov(k.fovYDegrees)) breach(at + "fov outside (0, 180)");
  }
  const double total = path.totalDuration();
  if (!(total >= 0.0)) breach("totalDuration() is " + std::to_string(total));
  const double inf = std::numeric_limits<double>::infinity();
  for (double t : {-1.0, 0.0, total * 0.25, total * 0.5, total * 0.999, total, total + 1.0, inf,
                   std::numeric_limits<double>::quiet_NaN()}) {
    const CameraPose pose = path.at(t);
    const std::string at = "pose at t = " + std::to_string(t) + " of " + std::to_string(total) + " s: ";
    if (!finite(pose.position)) breach(at + "position is not finite");
    if (!unit(pose.orientation)) breach(at + "orientation is not a unit quaternion");
    if (!goodFov(pose.fovYDegrees)) breach(at + "fov outside (0, 180)");
    if (!finite(pose.forward()) || !finite(pose.up())) breach(at + "forward or up is not finite");
  }
  return 0;
}
