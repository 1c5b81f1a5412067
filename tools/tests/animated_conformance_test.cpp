// raybridge-render on animated glTF models against an independent tracer: the render command poses the model at
// --time on the GPU (the engine's skinning and morphing), builds a dynamic BLAS over the deformed buffers and
// traces hard shadows; the test poses the same file at the same time on the CPU (pose_reference, double
// precision, written from the glTF spec) and traces those triangles with Embree. Depth (distance along each
// pixel-centre ray) and sun visibility must agree.
#include <catch2/catch_test_macros.hpp>


#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "embree_reference.h"
#include "gltf_fixtures.h"
#include "gltf_pose_reference.h"
#include "render_command_support.h"

namespace fs = std::filesystem;
using rbRenderTest::readExrRed;

namespace {


struct Agreement {
  uint32_t pixels = 0, hitMissAgree = 0, depthAgree = 0, bothHit = 0;
  uint32_t shadowCompared = 0, shadowAgree = 0, shadowed = 0;
};

// Renders `model` at `time` (animation 0) and compares it with Embree on the CPU-posed triangles.
Agreement compareAt(const std::string& model, double time, const std::string& extraArgs, const fs::path& dir) {
  std::string error;
  auto posed = pose_reference::poseGltf(model, 0, time, &error);
  INFO(error);
  REQUIRE(posed.has_value());
  rbtest::EmbreeScene embree;
  glm::dvec3 lo(1e300), hi(-1e300);
  uint32_t id = 0;
  for (const pose_reference::PosedPrimitive& p : *posed) {
    rbsamples::CpuMesh cpu;
    for (const glm::dvec3& v : p.worldPositions) {
      cpu.positions.insert(cpu.positions.end(), {float(v.x), float(v.y), float(v.z)});
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
    cpu.indices = p.indices;
    const float identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    embree.addInstance(cpu, identity, id++);
  }
  embree.commit();

  // A 3/4 view that frames the posed model, and a low side sun so that limbs shadow the body.
  const uint32_t W = 160, H = 160;
  const glm::vec3 centre = glm::vec3((lo + hi) * 0.5), extent = glm::vec3(hi - lo);
  const float radius = 0.5f * glm::length(extent);
  const glm::vec3 eye = centre + glm::normalize(glm::vec3(0.8f, 0.35f, 1.0f)) * radius * 2.6f;
  const float fovy = 45.0f;
  const glm::vec3 toSun = glm::normalize(glm::vec3(-0.7f, 0.5f, 0.35f));
  char camera[256], sun[128], timeText[64];
  std::snprintf(camera, sizeof camera, "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%g", eye.x, eye.y, eye.z, centre.x, centre.y,
                centre.z, fovy);
  std::snprintf(sun, sizeof sun, "%g,%g,%g", toSun.x, toSun.y, toSun.z);
  std::snprintf(timeText, sizeof timeText, "%.9g", time);
  fs::remove_all(dir);
  REQUIRE(rbRenderTest::runRender("--scene \"" + model + "\" --time " + timeText + " --mode hybrid --effects shadows " +
                                  "--gbuffer-normals geometric --sun-radius 0 --dump --width " + std::to_string(W) +
                                  " --height " + std::to_string(H) + " --camera " + camera + " --sun " + sun +
                                  " --out \"" + dir.string() + "\" " + extraArgs) == 0);
  int w = 0, h = 0;
  const std::vector<float> depth = readExrRed(dir / "depth.exr", w, h);
  REQUIRE((w == int(W) && h == int(H)));
  const std::vector<float> shadow = readExrRed(dir / "shadow.exr", w, h);

  const glm::vec3 forward = glm::normalize(centre - eye);
  const glm::vec3 right = glm::normalize(glm::cross(forward, glm::vec3(0, 1, 0)));
  const glm::vec3 up = glm::cross(right, forward);
  const float tanHalf = std::tan(glm::radians(fovy) * 0.5f), aspect = float(W) / float(H);
  std::vector<rbtest::ReferenceHit> hits(size_t(W) * H);
  std::vector<int> visible(size_t(W) * H, -1);
  for (uint32_t y = 0; y < H; ++y) {
    for (uint32_t x = 0; x < W; ++x) {
      const float nx = (x + 0.5f) / W * 2 - 1, ny = (y + 0.5f) / H * 2 - 1;
      const glm::vec3 d = glm::normalize(forward + nx * tanHalf * aspect * right - ny * tanHalf * up);
      const size_t i = size_t(y) * W + x;
      hits[i] = embree.intersect(&eye.x, &d.x, 0.0f, 1e30f);
      if (!hits[i].hit) continue;
      glm::vec3 n = glm::normalize(
          glm::vec3(hits[i].geometricNormal[0], hits[i].geometricNormal[1], hits[i].geometricNormal[2]));
      if (glm::dot(n, d) > 0) n = -n;
      if (glm::dot(n, toSun) <= 0.0f) {
        visible[i] = 0;
        continue;
      }
      const glm::vec3 o = eye + d * hits[i].t + n * 1e-4f * std::max(1.0f, hits[i].t);
      visible[i] = embree.intersect(&o.x, &toSun.x, 0.0f, 1e30f).hit ? 0 : 1;
    }
  }
  Agreement a;
  for (int y = 0; y < int(H); ++y) {
    for (int x = 0; x < int(W); ++x) {
      const size_t i = size_t(y) * W + x;
      const bool refHit = hits[i].hit, renderHit = depth[i] > 0.0f;
      ++a.pixels;
      a.hitMissAgree += refHit == renderHit;
      if (refHit && renderHit) {
        ++a.bothHit;
        a.depthAgree += std::fabs(depth[i] - hits[i].t) <= 1e-3f * hits[i].t;
      }
      // Shadows away from shadow edges and silhouettes (a 3x3 neighbourhood of one kind).
      if (!refHit || x == 0 || y == 0 || x + 1 == int(W) || y + 1 == int(H)) continue;
      bool edge = false;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const size_t j = size_t(y + dy) * W + size_t(x + dx);
          edge |= !hits[j].hit || visible[j] != visible[i];
        }
      if (edge) continue;
      ++a.shadowCompared;
      a.shadowAgree += (shadow[i] > 0.5f) == (visible[i] == 1);
      a.shadowed += visible[i] == 0;
    }
  }
  return a;
}

void check(const Agreement& a) {
  INFO("pixels " << a.pixels << ", hit/miss agree " << a.hitMissAgree << ", both hit " << a.bothHit << ", depth agree "
                 << a.depthAgree << ", shadow compared " << a.shadowCompared << " (shadowed " << a.shadowed
                 << "), agree " << a.shadowAgree);
  REQUIRE(a.bothHit > a.pixels / 20);  // the model covers a good part of the image
  REQUIRE(a.shadowCompared > 100);
  CHECK(double(a.hitMissAgree) / a.pixels >= 0.995);
  CHECK(double(a.depthAgree) / a.bothHit >= 0.995);
  CHECK(double(a.shadowAgree) / a.shadowCompared >= 0.995);
}

fs::path tempDir(const std::string& name) { return fs::temp_directory_path() / ("raybridge_animated_" + name); }

}  // namespace

TEST_CASE("animated render: the skinned strip at two times matches Embree on the CPU pose",
          "[render][animation][embree]") {
  const fs::path model = tempDir("strip_model") / "strip.gltf";
  fs::create_directories(model.parent_path());
  REQUIRE(pose_reference::writeSkinnedStrip(model.string()).empty());
  for (double t : {0.4, 1.3}) {
    INFO("time " << t);
    check(compareAt(model.string(), t, "", tempDir("strip")));
  }
}

TEST_CASE("animated render: CesiumMan at --time matches Embree on the CPU pose, in the frame and one frame late",
          "[render][animation][embree]") {
  const fs::path model = fs::path(RAYBRIDGE_SOURCE_DIR) / ".." / "shared" / "scenes" / "CesiumMan" / "CesiumMan.gltf";
  if (!fs::is_regular_file(model)) SKIP("CesiumMan is not in ../shared/scenes; the test needs it");
  check(compareAt(model.string(), 0.75, "", tempDir("cesium")));
  // One frame late with every frame at the same time: the TLAS's (previous-frame) BLAS has the same pose.
  check(compareAt(model.string(), 0.75, "--dynamic-builds async-late --frames 4", tempDir("cesium_late")));
}

TEST_CASE("raybridge-render rejects bad animation options, naming the value", "[render][animation][bad-input]") {
  const fs::path model = tempDir("strip_model") / "strip.gltf";
  fs::create_directories(model.parent_path());
  REQUIRE(pose_reference::writeSkinnedStrip(model.string()).empty());
  const std::string scene = " --scene \"" + model.string() + "\" --width 16 --height 16 --out \"" +
                            tempDir("bad").string() + "\" 2>&1";
  auto output = [&](const std::string& args, int& status) {
    const std::string command = rbRenderTest::renderCommand() + " " + args + scene;
    std::string text;
    if (FILE* p = popen(command.c_str(), "r")) {
      char buf[512];
      while (fgets(buf, sizeof buf, p)) text += buf;
      status = pclose(p);
    }
    return text;
  };
  int status = 0;
  for (const char* t : {"-1", "nan", "inf", "-inf"}) {
    const std::string out = output(std::string("--time ") + t, status);
    INFO(out);
    CHECK(status != 0);
    CHECK(out.find("--time") != std::string::npos);
    CHECK(out.find(t) != std::string::npos);
  }
  {
    const std::string out = output("--animation 7", status);
    INFO(out);
    CHECK(status != 0);
    CHECK(out.find("no animation 7") != std::string::npos);
    CHECK(out.find("bend") != std::string::npos);  // lists the animations the scene has
  }
  {
    const std::string out = output("--animation walk", status);
    INFO(out);
    CHECK(status != 0);
    CHECK(out.find("walk") != std::string::npos);
  }
  {
    const std::string out = output("--characters 2", status);  // with --scene: characters go on the demo scene
    INFO(out);
    CHECK(status != 0);
    CHECK(out.find("--characters") != std::string::npos);
  }
  {
    const std::string out = output("--fps 0", status);
    INFO(out);
    CHECK(status != 0);
    CHECK(out.find("--fps") != std::string::npos);
  }
}

TEST_CASE("raybridge-render's stats.json reports the dynamic BLAS work of an animated scene",
          "[render][animation][stats]") {
  const fs::path model = tempDir("strip_model") / "strip.gltf";
  fs::create_directories(model.parent_path());
  REQUIRE(pose_reference::writeSkinnedStrip(model.string()).empty());
  auto statsOf = [&](const std::string& mode) {
    const fs::path dir = tempDir("stats_" + mode);
    fs::remove_all(dir);
    REQUIRE(rbRenderTest::runRender(
                "--scene \"" + model.string() + "\" --time 0.6 --fps 30 --frames 4 --effects shadows " +
                "--width 48 --height 48 --dump --dynamic-builds " + mode + " --out \"" + dir.string() + "\"") == 0);
    std::ifstream in(dir / "stats.json");
    return nlohmann::json::parse(in);
  };
  for (const std::string mode : {"in-frame", "async-late"}) {
    INFO(mode);
    const nlohmann::json s = statsOf(mode);
    const nlohmann::json& as = s["raybridge"]["acceleration_structures"];
    CHECK(s["animation"]["name"] == "bend");
    CHECK(s["animation"]["deformed_instances"] == 1);
    CHECK(as["dynamic_builds"] == mode);
    // Every frame after the first build updates the strip: refit or rebuilt by the policy.
    CHECK(as["refits"].get<uint64_t>() + as["rebuilds"].get<uint64_t>() >= 3);
    // One frame late traces the previous frame's pose (also without a second queue, as on lavapipe).
    CHECK(as["stale_blas"] == (mode == "async-late" ? 1 : 0));
    if (!as["async"].get<bool>()) {
      CHECK(as["async_queue_family"].is_null());
      if (mode != "in-frame") CHECK(!as["async_fallback_reason"].get<std::string>().empty());
    }
  }
}
