// Camera paths: JSON parsing (nlohmann_json; its exceptions stay inside this file) and sampling.
#include "camera_path.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

namespace rbCameraPath {

namespace {

using Json = nlohmann::json;

// The shortest text that reads back as v (180, 1.5, -0.001).
std::string number(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

const char* typeName(const Json& j) {
  switch (j.type()) {
    case Json::value_t::null: return "null";
    case Json::value_t::object: return "an object";
    case Json::value_t::array: return "an array";
    case Json::value_t::string: return "a string";
    case Json::value_t::boolean: return "a boolean";
    case Json::value_t::binary: return "binary data";
    case Json::value_t::discarded: return "invalid";
    default: return "a number";
  }
}

// Reads `count` finite numbers of j[field] into out; `where` prefixes the error ("keyframe 3: ").
std::string readNumbers(const Json& j, const char* field, size_t count, const std::string& where, double* out) {
  const std::string name = where + "\"" + field + "\"";
  const Json& v = j.at(field);
  if (!v.is_array())
    return name + " is " + typeName(v) + "; it must be an array of " + std::to_string(count) + " numbers";
  if (v.size() != count)
    return name + " has " + std::to_string(v.size()) + " values; it must have " + std::to_string(count);
  for (size_t i = 0; i < count; ++i) {
    if (!v[i].is_number())
      return name + " value " + std::to_string(i) + " is " + typeName(v[i]) + "; it must be a number";
    out[i] = v[i].get<double>();
    if (!std::isfinite(out[i]))
      return name + " value " + std::to_string(i) + " is not finite (" + v[i].dump() + "); give a finite number";
  }
  return {};
}

// A single number j[field] into out.
std::string readNumber(const Json& j, const char* field, const std::string& where, double& out) {
  const Json& v = j.at(field);
  if (!v.is_number()) return where + "\"" + field + "\" is " + typeName(v) + "; it must be a number";
  out = v.get<double>();
  if (!std::isfinite(out)) return where + "\"" + field + "\" is not finite; give a finite number";
  return {};
}

std::string checkFov(double fov, const std::string& where) {
  if (fov > 0.0 && fov < 180.0) return {};
  return where + "\"fovy_degrees\" is " + number(fov) + "; it must be in (0, 180) degrees";
}

// Members other than `known` are errors, so a misspelt optional field is not silently ignored.
std::string checkMembers(const Json& j, std::initializer_list<const char*> known, const std::string& where) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (std::find_if(known.begin(), known.end(), [&](const char* k) { return it.key() == k; }) != known.end()) continue;
    std::string names;
    for (const char* k : known) names += std::string(names.empty() ? "" : ", ") + k;
    return where + "unknown field \"" + it.key() + "\" (the fields are " + names + ")";
  }
  return {};
}

std::string parseKey(const Json& k, size_t index, bool last, double pathFov, CameraKey& key) {
  const std::string where = "keyframe " + std::to_string(index) + ": ";
  if (!k.is_object()) return where + "is " + typeName(k) + "; it must be an object";
  if (std::string e = checkMembers(k, {"position", "orientation", "duration", "fovy_degrees"}, where); !e.empty())
    return e;
  for (const char* field : {"position", "orientation"})
    if (!k.contains(field)) return where + "\"" + field + "\" is missing";
  if (std::string e = readNumbers(k, "position", 3, where, key.position.data()); !e.empty()) return e;
  if (std::string e = readNumbers(k, "orientation", 4, where, key.orientation.data()); !e.empty()) return e;
  double length = 0.0;
  for (double c : key.orientation) length += c * c;
  length = std::sqrt(length);
  if (!(length > 1e-12) || !std::isfinite(length))
    return where + "\"orientation\" has zero length; give a unit quaternion x, y, z, w (identity: 0, 0, 0, 1)";
  for (double& c : key.orientation) c /= length;

  key.duration = 0.0;
  if (!k.contains("duration")) {
    if (!last) return where + "\"duration\" is missing; give the seconds to the next keyframe (> 0)";
  } else {
    if (std::string e = readNumber(k, "duration", where, key.duration); !e.empty()) return e;
    if (!last && !(key.duration > 0.0))
      return where + "\"duration\" is " + number(key.duration) +
             "; it must be greater than 0 (seconds to the next keyframe)";
    if (last && key.duration < 0.0)
      return where + "\"duration\" is " + number(key.duration) +
             "; the last keyframe's is ignored but must not be "
             "negative";
  }
  key.fovYDegrees = pathFov;
  if (k.contains("fovy_degrees")) {
    if (std::string e = readNumber(k, "fovy_degrees", where, key.fovYDegrees); !e.empty()) return e;
    if (std::string e = checkFov(key.fovYDegrees, where); !e.empty()) return e;
  }
  return {};
}

// std::lerp, not a + (b - a) * u: b - a overflows for keys far apart on either side of 0 (-1e308 and 1e308), which
// made the pose between them (and even at the first key, inf * 0) NaN. std::lerp is exact at u = 0 and 1 and finite
// for finite keys.
double lerp(double a, double b, double u) { return std::lerp(a, b, u); }

}  // namespace

std::array<double, 3> rotate(const std::array<double, 4>& q, const std::array<double, 3>& v) {
  // v' = v + 2w (u x v) + 2 u x (u x v), u = (x, y, z).
  const double ux = q[0], uy = q[1], uz = q[2], w = q[3];
  const double cx = uy * v[2] - uz * v[1], cy = uz * v[0] - ux * v[2], cz = ux * v[1] - uy * v[0];
  const double ccx = uy * cz - uz * cy, ccy = uz * cx - ux * cz, ccz = ux * cy - uy * cx;
  return {v[0] + 2.0 * (w * cx + ccx), v[1] + 2.0 * (w * cy + ccy), v[2] + 2.0 * (w * cz + ccz)};
}

std::array<double, 3> CameraPose::forward() const { return rotate(orientation, {0.0, 0.0, -1.0}); }
std::array<double, 3> CameraPose::up() const { return rotate(orientation, {0.0, 1.0, 0.0}); }

std::array<double, 4> slerpShortest(const std::array<double, 4>& a, const std::array<double, 4>& b0, double u) {
  std::array<double, 4> b = b0;
  double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  if (d < 0.0) {  // -b is the same rotation, closer to a
    for (double& c : b) c = -c;
    d = -d;
  }
  std::array<double, 4> r;
  if (d > 0.9999995) {
    // sin(theta) ~ 0: the weights below lose precision; the arc is straight to within 1e-7 here.
    double length = 0.0;
    for (int i = 0; i < 4; ++i) r[i] = lerp(a[i], b[i], u), length += r[i] * r[i];
    length = std::sqrt(length);
    for (double& c : r) c /= length;
    return r;
  }
  const double theta = std::acos(std::min(d, 1.0)), s = std::sin(theta);
  const double wa = std::sin((1.0 - u) * theta) / s, wb = std::sin(u * theta) / s;
  for (int i = 0; i < 4; ++i) r[i] = wa * a[i] + wb * b[i];
  return r;
}

double CameraPath::totalDuration() const {
  double total = 0.0;
  for (size_t i = 0; i + 1 < keys.size(); ++i) total += keys[i].duration;
  return total;
}

CameraPose CameraPath::at(double t) const {
  CameraPose pose;
  if (keys.empty()) return pose;
  if (!(t > 0.0)) t = 0.0;  // also NaN
  double start = 0.0;
  for (size_t i = 0; i + 1 < keys.size(); ++i) {
    const CameraKey &a = keys[i], &b = keys[i + 1];
    if (t < start + a.duration) {
      const double u = std::clamp((t - start) / a.duration, 0.0, 1.0);
      for (int c = 0; c < 3; ++c) pose.position[size_t(c)] = lerp(a.position[size_t(c)], b.position[size_t(c)], u);
      pose.orientation = slerpShortest(a.orientation, b.orientation, u);
      pose.fovYDegrees = lerp(a.fovYDegrees, b.fovYDegrees, u);
      return pose;
    }
    start += a.duration;
  }
  // At or past the end: exactly the last keyframe.
  pose.position = keys.back().position;
  pose.orientation = keys.back().orientation;
  pose.fovYDegrees = keys.back().fovYDegrees;
  return pose;
}

// Where the parser is, for the one error that nlohmann_json raises on valid JSON syntax: a number too large for a
// double (1e999), which is how a file spells a non-finite value. Keys at depth 1 are the top-level fields, objects
// at depth 2 the keyframes, keys at depth 3 their fields, values at depth 4 the elements of their arrays.
namespace {

struct ParsePosition {
  std::string top, field;
  long keyframe = -1;
  size_t element = 0;
  bool inArray = false;

  bool track(int depth, Json::parse_event_t event, const Json& parsed) {
    using E = Json::parse_event_t;
    if (event == E::key && depth == 1) top = parsed.get<std::string>(), field.clear(), inArray = false;
    if (event == E::object_start && depth == 2 && top == "keyframes") ++keyframe, field.clear();
    if (event == E::key && depth == 3) field = parsed.get<std::string>(), element = 0, inArray = false;
    if (event == E::array_start && depth == 3) inArray = true;
    if (event == E::array_end && depth == 3) inArray = false;
    if (event == E::value && depth == 4) ++element;
    return true;
  }

  std::string overflow(const std::string& what) const {
    const size_t open = what.find('\''), close = what.rfind('\'');
    const std::string token = open < close ? what.substr(open + 1, close - open - 1) : std::string("?");
    const std::string problem = " is not finite (" + token + " overflows a double); give a finite number";
    if (top == "keyframes" && keyframe >= 0 && !field.empty())
      return "keyframe " + std::to_string(keyframe) + ": \"" + field + "\"" +
             (inArray ? " value " + std::to_string(element) : std::string()) + problem;
    if (!top.empty()) return "\"" + top + "\"" + problem;
    return "a number" + problem;
  }
};

}  // namespace

std::string parseCameraPath(std::string_view text, CameraPath& out) {
  Json j;
  ParsePosition position;
  try {
    j = Json::parse(text.begin(), text.end(), [&position](int depth, Json::parse_event_t event, Json& parsed) {
      return position.track(depth, event, parsed);
    });
  } catch (const Json::out_of_range& e) {
    return position.overflow(e.what());
  } catch (const Json::exception& e) {
    return std::string("not JSON: ") + e.what();
  }
  if (!j.is_object()) return std::string("the file is ") + typeName(j) + "; it must be a JSON object";
  if (std::string e = checkMembers(j, {"version", "fovy_degrees", "keyframes"}, ""); !e.empty()) return e;
  if (!j.contains("version")) return "\"version\" is missing; this reader knows version 1";
  if (!j["version"].is_number_integer() || j["version"].get<int64_t>() != 1)
    return "\"version\" is " + j["version"].dump() + "; this reader knows only version 1";
  double fov = kDefaultCameraPathFovYDegrees;
  if (j.contains("fovy_degrees")) {
    if (std::string e = readNumber(j, "fovy_degrees", "", fov); !e.empty()) return e;
    if (std::string e = checkFov(fov, ""); !e.empty()) return e;
  }
  if (!j.contains("keyframes")) return "\"keyframes\" is missing; give an array of at least one keyframe";
  const Json& keys = j["keyframes"];
  if (!keys.is_array()) return std::string("\"keyframes\" is ") + typeName(keys) + "; it must be an array";
  if (keys.empty()) return "\"keyframes\" is empty; give at least one keyframe";
  CameraPath path;
  path.keys.resize(keys.size());
  for (size_t i = 0; i < keys.size(); ++i)
    if (std::string e = parseKey(keys[i], i, i + 1 == keys.size(), fov, path.keys[i]); !e.empty()) return e;
  out = std::move(path);
  return {};
}

std::string loadCameraPath(const std::string& path, CameraPath& out) {
  // Only a regular file: a folder opens and reads as empty, and /dev/zero or a FIFO would never end (or open).
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status))
    return "'" + path + "': cannot be opened: " + (ec ? ec.message() : std::string("No such file or directory"));
  if (std::filesystem::is_directory(status)) return "'" + path + "': is a folder, not a camera path file";
  if (!std::filesystem::is_regular_file(status)) return "'" + path + "': is not a regular file";
  std::ifstream file(path, std::ios::binary);
  if (!file) return "'" + path + "': cannot be opened (unreadable)";
  std::ostringstream text;
  text << file.rdbuf();
  if (!file && !file.eof()) return "'" + path + "': cannot be read";
  if (text.str().empty()) return "'" + path + "': is empty; a camera path is a JSON object (see camera_path.h)";
  if (std::string e = parseCameraPath(text.str(), out); !e.empty()) return "'" + path + "': " + e;
  return {};
}

}  // namespace rbCameraPath
