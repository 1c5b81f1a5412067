// Camera paths (samples/common/camera_path.h): sampling against an independent double-precision slerp written here
// from the formula, the errors of bad files, and raybridge-render --camera-path end to end.
#include <catch2/catch_test_macros.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "camera_path.h"
#include "render_command_support.h"

namespace fs = std::filesystem;
using rbCameraPath::CameraPath;
using rbCameraPath::CameraPose;
using Quat = std::array<double, 4>;  // x, y, z, w
using Vec3 = std::array<double, 3>;

namespace {

constexpr double kPi = 3.14159265358979323846;

Quat axisAngle(Vec3 axis, double degrees) {
  const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  const double h = degrees * kPi / 360.0, s = std::sin(h) / n;
  return {axis[0] * s, axis[1] * s, axis[2] * s, std::cos(h)};
}

double dot(const Quat& a, const Quat& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]; }

// The reference: slerp(a, b, u) = sin((1-u)θ)/sinθ a + sin(uθ)/sinθ b, cosθ = a·b, with b negated first when a·b < 0.
Quat referenceSlerp(const Quat& a, Quat b, double u) {
  double d = dot(a, b);
  if (d < 0.0) {
    for (double& c : b) c = -c;
    d = -d;
  }
  const double theta = std::acos(std::min(1.0, d));
  Quat r;
  if (theta < 1e-9) return a;
  for (int i = 0; i < 4; ++i)
    r[size_t(i)] = std::sin((1.0 - u) * theta) / std::sin(theta) * a[size_t(i)] +
                   std::sin(u * theta) / std::sin(theta) * b[size_t(i)];
  return r;
}

// -Z through the rotation matrix of q (the textbook matrix, not the library's rotate()).
Vec3 referenceForward(const Quat& q) {
  const double x = q[0], y = q[1], z = q[2], w = q[3];
  // Third column of R, negated.
  return {-(2 * (x * z + w * y)), -(2 * (y * z - w * x)), -(1 - 2 * (x * x + y * y))};
}

std::string keyJson(Vec3 p, Quat q, double duration) {
  nlohmann::json k = {{"position", {p[0], p[1], p[2]}}, {"orientation", {q[0], q[1], q[2], q[3]}}};
  if (duration >= 0.0) k["duration"] = duration;
  return k.dump();
}

bool samePose(const CameraPose& a, const CameraPose& b) {
  return a.position == b.position && a.orientation == b.orientation && a.fovYDegrees == b.fovYDegrees;
}

fs::path tempDir(const std::string& name) { return fs::temp_directory_path() / ("raybridge_camera_path_" + name); }

}  // namespace

TEST_CASE("camera path: linear position and shortest-arc slerp match the reference", "[camera_path]") {
  const Vec3 p0{0, 1, 5}, p1{2, 1.5, 3}, p2{-4, 3, -1};
  const Quat q0 = axisAngle({0, 1, 0}, 10), q1 = axisAngle({1, 2, 0.5}, 95), q2 = axisAngle({0.3, -1, 0.2}, 170);
  // Key 1 is written at twice unit length and with the sign that puts it on the far hemisphere of key 0: the
  // reader normalises it, and sampling must still take the short way.
  Quat q1File = q1;
  for (double& c : q1File) c *= -2.0;
  const std::string json = std::string(R"({"version": 1, "fovy_degrees": 50, "keyframes": [)") + keyJson(p0, q0, 1.5) +
                           "," + keyJson(p1, q1File, 2.5) + "," + keyJson(p2, q2, -1) + "]}";
  CameraPath path;
  REQUIRE(rbCameraPath::parseCameraPath(json, path) == "");
  REQUIRE(path.keys.size() == 3);
  CHECK(path.totalDuration() == 4.0);
  for (int i = 0; i < 4; ++i) CHECK(std::abs(path.keys[1].orientation[size_t(i)] + q1[size_t(i)]) < 1e-15);

  const Vec3 ps[3] = {p0, p1, p2};
  const Quat qs[3] = {q0, path.keys[1].orientation, q2};
  const double starts[3] = {0.0, 1.5, 4.0};
  for (int step = 0; step <= 400; ++step) {
    const double t = 4.0 * step / 400.0;
    const int seg = t < 1.5 ? 0 : 1;
    const double u = (t - starts[seg]) / (starts[seg + 1] - starts[seg]);
    const CameraPose pose = path.at(t);
    INFO("t = " << t);
    for (int c = 0; c < 3; ++c)
      CHECK(std::abs(pose.position[size_t(c)] -
                     (ps[seg][size_t(c)] + (ps[seg + 1][size_t(c)] - ps[seg][size_t(c)]) * u)) < 1e-5);
    const Quat expected = referenceSlerp(qs[seg], qs[seg + 1], u);
    // The sign of a quaternion is not a rotation: compare up to it, and compare the view direction too.
    CHECK(std::abs(std::abs(dot(pose.orientation, expected)) - 1.0) < 1e-10);
    const double sign = dot(pose.orientation, expected) < 0 ? -1.0 : 1.0;
    for (int i = 0; i < 4; ++i) CHECK(std::abs(pose.orientation[size_t(i)] - sign * expected[size_t(i)]) < 1e-5);
    const Vec3 f = pose.forward(), g = referenceForward(expected);
    for (int c = 0; c < 3; ++c) CHECK(std::abs(f[size_t(c)] - g[size_t(c)]) < 1e-5);
    CHECK(pose.fovYDegrees == 50.0);
  }
  // Keyframe times give the keyframes exactly.
  for (int k = 0; k < 3; ++k) {
    const CameraPose pose = path.at(starts[k]);
    CHECK(pose.position == path.keys[size_t(k)].position);
    CHECK(std::abs(std::abs(dot(pose.orientation, path.keys[size_t(k)].orientation)) - 1.0) < 1e-15);
  }
  CHECK(path.at(0.0).orientation == path.keys[0].orientation);
  CHECK(path.at(4.0).orientation == path.keys[2].orientation);
  // Clamped before the start and after the end.
  CHECK(samePose(path.at(-3.0), path.at(0.0)));
  CHECK(samePose(path.at(1e9), path.at(4.0)));
  CHECK(samePose(path.at(std::nan("")), path.at(0.0)));
}

TEST_CASE("camera path: q and -q keyframes do not spin; half a 90-degree turn is 45 degrees", "[camera_path]") {
  const Quat q = axisAngle({0.2, 1, 0.1}, 60);
  const Quat minusQ{-q[0], -q[1], -q[2], -q[3]};
  CameraPath same;
  REQUIRE(rbCameraPath::parseCameraPath(std::string(R"({"version":1,"keyframes":[)") + keyJson({0, 0, 0}, q, 2) + "," +
                                            keyJson({0, 0, 0}, minusQ, 0) + "]}",
                                        same) == "");
  for (int s = 0; s <= 20; ++s) {
    const CameraPose pose = same.at(0.1 * s);
    CHECK(std::abs(std::abs(dot(pose.orientation, q)) - 1.0) < 1e-12);  // the same rotation throughout
  }
  // 0 and -(90 degrees about Y): the long way would pass through 135 degrees at the middle.
  const Quat turn = axisAngle({0, 1, 0}, 90);
  CameraPath quarter;
  REQUIRE(rbCameraPath::parseCameraPath(std::string(R"({"version":1,"keyframes":[)") +
                                            keyJson({0, 0, 0}, {0, 0, 0, 1}, 1) + "," +
                                            keyJson({0, 0, 0}, {-turn[0], -turn[1], -turn[2], -turn[3]}, -1) + "]}",
                                        quarter) == "");
  const Vec3 f = quarter.at(0.5).forward();
  // Rotating -Z by +45 degrees about Y gives (-sin 45, 0, -cos 45).
  CHECK(std::abs(f[0] + std::sqrt(0.5)) < 1e-12);
  CHECK(std::abs(f[1]) < 1e-12);
  CHECK(std::abs(f[2] + std::sqrt(0.5)) < 1e-12);
  CHECK(quarter.at(0.5).fovYDegrees == rbCameraPath::kDefaultCameraPathFovYDegrees);
}

TEST_CASE("camera path: per-keyframe fov interpolates; one keyframe is a still camera", "[camera_path]") {
  CameraPath path;
  REQUIRE(rbCameraPath::parseCameraPath(
              R"({"version":1,"fovy_degrees":70,"keyframes":[
                 {"position":[0,0,0],"orientation":[0,0,0,1],"duration":2,"fovy_degrees":30},
                 {"position":[0,0,0],"orientation":[0,0,0,1]}]})",
              path) == "");
  CHECK(path.at(0.0).fovYDegrees == 30.0);
  CHECK(std::abs(path.at(1.0).fovYDegrees - 50.0) < 1e-12);
  CHECK(path.at(2.0).fovYDegrees == 70.0);
  CameraPath still;
  REQUIRE(rbCameraPath::parseCameraPath(R"({"version":1,"keyframes":[{"position":[1,2,3],"orientation":[0,0,0,3]}]})",
                                        still) == "");
  CHECK(still.totalDuration() == 0.0);
  CHECK(still.at(5.0).position == Vec3{1, 2, 3});
  CHECK(still.at(5.0).orientation == Quat{0, 0, 0, 1});  // normalised
}

TEST_CASE("camera path: every bad file names the problem, the keyframe and the field", "[camera_path]") {
  const std::string good0 = R"({"position":[0,0,0],"orientation":[0,0,0,1],"duration":1})";
  const std::string good1 = R"({"position":[1,0,0],"orientation":[0,0,0,1]})";
  auto file = [](const std::string& keys) { return R"({"version":1,"keyframes":[)" + keys + "]}"; };
  struct Case {
    std::string json;
    std::vector<std::string> words;
  };
  const std::vector<Case> cases = {
      {"{\"version\": 1,", {"not JSON"}},
      {"[1, 2]", {"must be a JSON object"}},
      {R"({"keyframes":[)" + good0 + "]}", {"\"version\"", "missing"}},
      {R"({"version":2,"keyframes":[)" + good0 + "]}", {"\"version\" is 2", "only version 1"}},
      {R"({"version":"1","keyframes":[)" + good0 + "]}", {"\"version\"", "only version 1"}},
      {R"({"version":1})", {"\"keyframes\" is missing"}},
      {R"({"version":1,"keyframes":{}})", {"\"keyframes\"", "must be an array"}},
      {R"({"version":1,"keyframes":[]})", {"\"keyframes\" is empty", "at least one"}},
      {R"({"version":1,"keyframes":[)" + good0 + "],\"speed\":2}", {"unknown field \"speed\""}},
      {R"({"version":1,"fovy_degrees":180,"keyframes":[)" + good0 + "]}", {"\"fovy_degrees\" is 180", "(0, 180)"}},
      {R"({"version":1,"fovy_degrees":"wide","keyframes":[)" + good0 + "]}", {"\"fovy_degrees\"", "a number"}},
      {file(good0 + ",7"), {"keyframe 1", "must be an object"}},
      {file(good0 + R"(,{"orientation":[0,0,0,1]})"), {"keyframe 1", "\"position\" is missing"}},
      {file(R"({"position":[0,0,0],"duration":1},)" + good1), {"keyframe 0", "\"orientation\" is missing"}},
      {file(good0 + R"(,{"position":[1,0],"orientation":[0,0,0,1]})"), {"keyframe 1", "\"position\"", "has 2 values"}},
      {file(good0 + R"(,{"position":[1,"a",0],"orientation":[0,0,0,1]})"),
       {"keyframe 1", "\"position\" value 1", "a string"}},
      {file(good0 + R"(,{"position":[1,1e999,0],"orientation":[0,0,0,1]})"),
       {"keyframe 1", "\"position\" value 1", "not finite"}},
      {file(good0 + R"(,{"position":3,"orientation":[0,0,0,1]})"), {"keyframe 1", "\"position\" is a number"}},
      {file(R"({"position":[0,0,0],"orientation":[0,0,1],"duration":1},)" + good1),
       {"keyframe 0", "\"orientation\"", "has 3 values", "4"}},
      {file(R"({"position":[0,0,0],"orientation":[0,0,0,0],"duration":1},)" + good1),
       {"keyframe 0", "\"orientation\" has zero length"}},
      {file(R"({"position":[0,0,0],"orientation":[0,-1e999,0,1],"duration":1},)" + good1),
       {"keyframe 0", "\"orientation\" value 1", "not finite"}},
      {file(R"({"position":[0,0,0],"orientation":[0,0,0,1]},)" + good1), {"keyframe 0", "\"duration\" is missing"}},
      {file(good0 + "," + R"({"position":[0,0,0],"orientation":[0,0,0,1],"duration":0},)" + good1),
       {"keyframe 1", "\"duration\" is 0", "greater than 0"}},
      {file(R"({"position":[0,0,0],"orientation":[0,0,0,1],"duration":-1.5},)" + good1),
       {"keyframe 0", "\"duration\" is -1.5"}},
      {file(R"({"position":[0,0,0],"orientation":[0,0,0,1],"duration":1e999},)" + good1),
       {"keyframe 0", "\"duration\" is not finite"}},
      {file(R"({"position":[0,0,0],"orientation":[0,0,0,1],"duration":"2"},)" + good1),
       {"keyframe 0", "\"duration\" is a string"}},
      {file(good0 + R"(,{"position":[1,0,0],"orientation":[0,0,0,1],"duration":-1})"),
       {"keyframe 1", "\"duration\" is -1", "last"}},
      {file(good0 + R"(,{"position":[1,0,0],"orientation":[0,0,0,1],"fovy_degrees":0})"),
       {"keyframe 1", "\"fovy_degrees\" is 0", "(0, 180)"}},
      {file(good0 + R"(,{"position":[1,0,0],"orientaton":[0,0,0,1]})"), {"keyframe 1", "unknown field \"orientaton\""}},
  };
  for (const Case& c : cases) {
    CameraPath path;
    path.keys.resize(5);  // left unchanged on error
    const std::string error = rbCameraPath::parseCameraPath(c.json, path);
    INFO(c.json << "\n-> " << error);
    CHECK(path.keys.size() == 5);
    for (const std::string& w : c.words) CHECK(error.find(w) != std::string::npos);
  }
  // The same keyframes are fine: the cases fail for what they change, not for the base.
  CameraPath ok;
  CHECK(rbCameraPath::parseCameraPath(file(good0 + "," + good1), ok) == "");
  CHECK(rbCameraPath::parseCameraPath(file(good0 + R"(,{"position":[1,0,0],"orientation":[0,0,0,1],"duration":0})"),
                                      ok) == "");
  const std::string missing = (tempDir("none") / "no_such_path.json").string();
  const std::string error = rbCameraPath::loadCameraPath(missing, ok);
  INFO(error);
  CHECK(error.find(missing) != std::string::npos);
  CHECK(error.find("cannot be opened") != std::string::npos);
}

TEST_CASE("camera path: keys far apart on either side of 0 give finite poses, exact at the keys",
          "[camera_path][fuzz]") {
  // tests/fuzz/corpus/camera_path/crash-far-apart-keys.json (camera_path_fuzz): the interpolation computed
  // b - a = 2e308 = inf, so every pose of the path (even at t = 0: -1e308 + inf * 0) had a NaN position.
  const std::string input =
      R"({"version":1,"keyframes":[{"position":[-1e308,0,0],"orientation":[0,0,0,1],"duration":1},)"
      R"({"position":[1e308,0,0],"orientation":[0,0,0,1]}]})";
  CameraPath path;
  REQUIRE(rbCameraPath::parseCameraPath(input, path) == "");
  CHECK(path.at(0.0).position == Vec3{-1e308, 0, 0});
  CHECK(path.at(1.0).position == Vec3{1e308, 0, 0});
  for (double t : {0.25, 0.5, 0.75}) {
    INFO("t = " << t);
    const double x = path.at(t).position[0];
    CHECK(std::isfinite(x));
    CHECK(std::abs(x - (2.0 * t - 1.0) * 1e308) <= 1e293);
  }
}

using rbRenderTest::readJson;
using rbRenderTest::renderOutput;

TEST_CASE("raybridge-render --camera-path renders the path's end and reports it", "[camera_path][render]") {
  const fs::path dir = tempDir("render");
  fs::create_directories(dir);
  // The demo scene from in front and above, turning 20 degrees to the left and pitching down on the way.
  const Quat q0 = axisAngle({1, 0, 0}, -15);
  const Quat yaw = axisAngle({0, 1, 0}, 20), pitch = axisAngle({1, 0, 0}, -25);
  // q1 = yaw * pitch (Hamilton product): pitch in the camera's frame, then yaw in the world.
  const Quat q1{yaw[3] * pitch[0] + yaw[0] * pitch[3] + yaw[1] * pitch[2] - yaw[2] * pitch[1],
                yaw[3] * pitch[1] - yaw[0] * pitch[2] + yaw[1] * pitch[3] + yaw[2] * pitch[0],
                yaw[3] * pitch[2] + yaw[0] * pitch[1] - yaw[1] * pitch[0] + yaw[2] * pitch[3],
                yaw[3] * pitch[3] - yaw[0] * pitch[0] - yaw[1] * pitch[1] - yaw[2] * pitch[2]};
  const Vec3 p1{1.5, 4.0, 9.0};
  const fs::path pathFile = dir / "fly.json";
  {
    std::ofstream(pathFile) << R"({"version": 1, "fovy_degrees": 50, "keyframes": [)" << keyJson({0, 3, 12}, q0, 1.25)
                            << "," << keyJson(p1, q1, 0) << "]}";
  }
  const std::string common = " --width 64 --height 40 --frames 2 --mode raster --preset none --dump";
  int status = 0;
  {
    const std::string out = renderOutput(
        "--camera-path \"" + pathFile.string() + "\" --out \"" + (dir / "path").string() + "\"" + common, status);
    INFO(out);
    REQUIRE(status == 0);
  }
  const nlohmann::json stats = readJson(dir / "path" / "stats.json");
  REQUIRE(stats.is_object());
  INFO(stats.dump(2));
  CHECK(stats["camera_path"]["file"] == pathFile.string());
  CHECK(stats["camera_path"]["keyframes"] == 2);
  CHECK(stats["camera_path"]["duration_s"] == 1.25);
  CHECK(stats["camera_path"]["time_s"] == 1.25);  // frame 1 of 2 is the path's end
  CHECK(stats["camera"]["source"] == "path");
  CHECK(stats["camera"]["fovy_degrees"] == 50.0);
  CHECK(stats["validation"]["errors"] == 0);
  const Vec3 f = referenceForward(q1);
  Vec3 eye, target;
  for (int c = 0; c < 3; ++c) {
    eye[size_t(c)] = stats["camera"]["eye"][size_t(c)].get<double>();
    target[size_t(c)] = stats["camera"]["target"][size_t(c)].get<double>();
    CHECK(std::abs(eye[size_t(c)] - p1[size_t(c)]) < 1e-5);
  }
  Vec3 d{target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
  const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  for (int c = 0; c < 3; ++c) CHECK(std::abs(d[size_t(c)] / length - f[size_t(c)]) < 1e-5);

  // The same image as --camera with that eye and target: the path placed the camera, nothing else changed.
  std::string camera = "--camera ";
  for (int c = 0; c < 3; ++c) camera += std::to_string(p1[size_t(c)]) + ",";
  for (int c = 0; c < 3; ++c) camera += std::to_string(p1[size_t(c)] + f[size_t(c)] * 10.0) + ",";
  camera += "50";
  {
    const std::string out = renderOutput(camera + " --out \"" + (dir / "camera").string() + "\"" + common, status);
    INFO(out);
    REQUIRE(status == 0);
  }
  int w = 0, h = 0, w2 = 0, h2 = 0;
  const std::vector<float> a = rbRenderTest::readExrRgb(dir / "path" / "final.exr", w, h);
  const std::vector<float> b = rbRenderTest::readExrRgb(dir / "camera" / "final.exr", w2, h2);
  REQUIRE((w == 64 && h == 40 && w2 == 64 && h2 == 40));
  size_t differing = 0;
  for (size_t i = 0; i < a.size(); ++i) differing += std::abs(a[i] - b[i]) > 1e-2f * (1.0f + std::abs(b[i]));
  CHECK(differing <= a.size() / 200);  // edge pixels may move by float rounding of the target
  // ...and not the image of the path's start.
  {
    const std::string out = renderOutput("--camera-path \"" + pathFile.string() + "\" --out \"" +
                                             (dir / "start").string() + "\" --fps 1000" + common,
                                         status);
    INFO(out);
    REQUIRE(status == 0);
  }
  const nlohmann::json startStats = readJson(dir / "start" / "stats.json");
  CHECK(startStats["camera_path"]["time_s"] == 0.001);  // frame 1 at 1/1000 s
  const std::vector<float> s = rbRenderTest::readExrRgb(dir / "start" / "final.exr", w, h);
  size_t moved = 0;
  for (size_t i = 0; i < a.size(); ++i) moved += std::abs(a[i] - s[i]) > 1e-2f * (1.0f + std::abs(a[i]));
  CHECK(moved > a.size() / 10);
  // --fps past the path's end: frame 1 at 1 / 0.5 = 2 s is clamped to the end, 1.25 s.
  {
    const std::string out = renderOutput("--camera-path \"" + pathFile.string() + "\" --out \"" +
                                             (dir / "clamped").string() +
                                             "\" --fps 0.5 --width 16 --height 16 --frames 2 --mode raster "
                                             "--preset none --dump",
                                         status);
    INFO(out);
    REQUIRE(status == 0);
  }
  CHECK(readJson(dir / "clamped" / "stats.json")["camera_path"]["time_s"] == 1.25);
}

TEST_CASE("raybridge-render --camera-path: bad uses name the option and the file", "[camera_path][render][bad-input]") {
  const fs::path dir = tempDir("bad");
  fs::create_directories(dir);
  const fs::path pathFile = dir / "ok.json";
  std::ofstream(pathFile) << R"({"version":1,"keyframes":[{"position":[0,2,8],"orientation":[0,0,0,1]}]})";
  const std::string common = " --width 16 --height 16 --out \"" + (dir / "out").string() + "\"";
  int status = 0;
  {
    const std::string out = renderOutput("--camera-path \"" + pathFile.string() + "\" --camera 0,2,8,0,0,0,45" + common,
                                         status);
    INFO(out);
    CHECK(status != 0);
    CHECK(out.find("--camera-path and --camera both") != std::string::npos);
  }
  {
    const std::string missing = (dir / "missing.json").string();
    const std::string out = renderOutput("--camera-path \"" + missing + "\"" + common, status);
    INFO(out);
    CHECK(status != 0);
    CHECK(out.find("--camera-path") != std::string::npos);
    CHECK(out.find(missing) != std::string::npos);
  }
  {
    const fs::path bad = dir / "bad.json";
    std::ofstream(bad) << R"({"version":1,"keyframes":[{"position":[0,2,8],"orientation":[0,0,0,0]}]})";
    const std::string out = renderOutput("--camera-path \"" + bad.string() + "\"" + common, status);
    INFO(out);
    CHECK(status != 0);
    CHECK(out.find("keyframe 0: \"orientation\" has zero length") != std::string::npos);
  }
  {
    // Looking straight down (-90 degrees about X): no up vector for the engine's +Y-up camera.
    const fs::path down = dir / "down.json";
    std::ofstream(down) << R"({"version":1,"keyframes":[{"position":[0,8,0],"orientation":[-0.7071067811865476,0,0,)"
                        << R"(0.7071067811865476]}]})";
    const std::string out = renderOutput("--camera-path \"" + down.string() + "\"" + common, status);
    INFO(out);
    CHECK(status != 0);
    CHECK(out.find("--camera-path: at t = 0") != std::string::npos);
    CHECK(out.find("straight up or down") != std::string::npos);
  }
}
