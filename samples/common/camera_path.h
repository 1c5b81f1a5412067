// Camera paths (the thesis's .trk fly-throughs) as JSON keyframes: parsing with errors that name the keyframe and
// the field, and sampling at a time. Knows neither Vulkan nor Raybridge.
//
// The file format (version 1):
//
//   {"version": 1, "fovy_degrees": 50,
//    "keyframes": [{"position": [x, y, z], "orientation": [x, y, z, w], "duration": 1.5, "fovy_degrees": 40},
//                  ...]}
//
// - version: required, must be 1.
// - fovy_degrees: optional vertical field of view in degrees, in (0, 180); kDefaultCameraPathFovYDegrees if absent.
// - keyframes: required, at least one. Each keyframe:
//   - position: required, 3 finite numbers, world units.
//   - orientation: required unit quaternion, glTF order x, y, z, w, rotating the camera's local frame (looking
//     down -Z, up +Y, right +X) into world space. A quaternion that is not unit length is normalised (a hand-
//     edited file rarely has exact unit quaternions); a zero-length one is an error.
//   - duration: seconds from this keyframe to the next, finite and > 0; required except on the last keyframe,
//     where it is optional, must be finite and >= 0 if given, and is ignored (the path ends there).
//   - fovy_degrees: optional, in (0, 180); else the path's.
// Any other member (at the top or in a keyframe) is an error, so a misspelt field does not silently fall back.
//
// Sampling (CameraPath::at): position and field of view are interpolated linearly between the two keyframes
// around t (piecewise linear, so the camera passes exactly through every keyframe and never overshoots), the
// orientation by spherical linear interpolation along the shorter arc (q and -q are the same rotation: the
// second key's sign is flipped when the dot product is negative, so no keyframe pair makes the camera spin the
// long way round). t is clamped to [0, totalDuration()].
//
// Thread safety: plain data and free functions; a CameraPath may be read from any number of threads at once.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

namespace rbCameraPath {

// The field of view when the file gives none (the sample engine's camera default).
inline constexpr double kDefaultCameraPathFovYDegrees = 60.0;

// One keyframe, as parsed (orientation already normalised).
struct CameraKey {
  std::array<double, 3> position{0.0, 0.0, 0.0};
  std::array<double, 4> orientation{0.0, 0.0, 0.0, 1.0};  // x, y, z, w; unit length; identity looks down -Z
  double duration = 0.0;                                  // seconds to the next keyframe; ignored on the last
  double fovYDegrees = kDefaultCameraPathFovYDegrees;     // the keyframe's, else the path's
};

// Where the camera is at one time.
struct CameraPose {
  std::array<double, 3> position{0.0, 0.0, 0.0};
  std::array<double, 4> orientation{0.0, 0.0, 0.0, 1.0};  // x, y, z, w; unit length
  double fovYDegrees = kDefaultCameraPathFovYDegrees;
  // The view direction: the orientation applied to the local -Z axis (unit length).
  std::array<double, 3> forward() const;
  // The camera's up: the orientation applied to the local +Y axis (unit length).
  std::array<double, 3> up() const;
};

struct CameraPath {
  std::vector<CameraKey> keys;  // empty = no path (at() returns a default pose)
  // Sum of the durations of every keyframe but the last; 0 for a single keyframe.
  double totalDuration() const;
  // The pose at time t seconds from the first keyframe, t clamped to [0, totalDuration()] (NaN reads as 0).
  CameraPose at(double t) const;
};

// Spherical linear interpolation from a to b (unit quaternions x, y, z, w) at u in [0, 1], along the shorter
// arc; u = 0 gives a exactly. Falls back to normalised linear interpolation when the two are nearly equal.
std::array<double, 4> slerpShortest(const std::array<double, 4>& a, const std::array<double, 4>& b, double u);
// v rotated by the unit quaternion q (x, y, z, w).
std::array<double, 3> rotate(const std::array<double, 4>& q, const std::array<double, 3>& v);

// Parses the JSON text of a camera path into `out`. Returns "" on success, else an error naming the problem, the
// keyframe index and the field ("keyframe 2: \"duration\" is -1; it must be greater than 0 (seconds to the next
// keyframe)"); `out` is left unchanged on error.
std::string parseCameraPath(std::string_view json, CameraPath& out);
// Reads the file and parses it; errors name the file ("'a.json': cannot be opened", "'a.json': keyframe 0: ...").
std::string loadCameraPath(const std::string& path, CameraPath& out);

}  // namespace rbCameraPath
