// The minimal integration end to end: the program runs as a subprocess under validation, then its reversed-Z
// depth, hard shadows, AO and motion vectors are checked against Embree tracing the same scene
// (minimal_scene.h) through the camera the program wrote.
#include <catch2/catch_test_macros.hpp>

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "embree_reference.h"
#include "minimal_scene.h"

namespace fs = std::filesystem;

namespace {

// A PFM with `channels` floats per pixel, rows from the top.
std::vector<float> readPfm(const fs::path& path, int channels, int& w, int& h) {
  std::ifstream in(path, std::ios::binary);
  REQUIRE(in.good());
  std::string magic;
  double scale = 0.0;
  in >> magic >> w >> h >> scale;
  in.get();
  REQUIRE(magic == (channels == 3 ? "PF" : "Pf"));
  REQUIRE(scale < 0.0);  // little-endian
  std::vector<float> rows(size_t(w) * h * channels), px(rows.size());
  in.read(reinterpret_cast<char*>(rows.data()), std::streamsize(rows.size() * sizeof(float)));
  REQUIRE(in.good());
  const size_t row = size_t(w) * channels;
  for (int y = 0; y < h; ++y) std::copy_n(&rows[size_t(h - 1 - y) * row], row, &px[size_t(y) * row]);
  return px;
}

// camera.txt: one "key v0 v1 ..." line per entry.
std::map<std::string, std::vector<double>> readCamera(const fs::path& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  std::map<std::string, std::vector<double>> out;
  for (std::string line; std::getline(in, line);) {
    std::istringstream s(line);
    std::string key;
    s >> key;
    for (double v; s >> v;) out[key].push_back(v);
  }
  return out;
}

glm::dmat4 matrix(const std::vector<double>& columnMajor) {
  REQUIRE(columnMajor.size() == 16);
  glm::dmat4 m;
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) m[c][r] = columnMajor[size_t(c) * 4 + r];
  }
  return m;
}

struct Pixel {
  bool sky = true;
  uint32_t instance = ~0u;
  glm::dvec3 position{0.0};  // reconstructed from the program's depth
  glm::dvec3 normal{0.0};    // Embree's geometric normal, facing the viewer
  double distance = 0.0;     // Embree's primary hit distance
  int visible = -1;          // Embree's hard shadow at `position`: 1 lit, 0 shadowed, -1 sky
};

// XZ distance from a point to the footprint (bounding rectangle) of a mesh.
double footprintDistance(const minimal::Mesh& m, const glm::dvec3& p) {
  double x0 = 1e30, x1 = -1e30, z0 = 1e30, z1 = -1e30;
  for (size_t i = 0; i < m.positions.size(); i += 3) {
    x0 = std::min(x0, double(m.positions[i])), x1 = std::max(x1, double(m.positions[i]));
    z0 = std::min(z0, double(m.positions[i + 2])), z1 = std::max(z1, double(m.positions[i + 2]));
  }
  const double dx = std::max({x0 - p.x, 0.0, p.x - x1}), dz = std::max({z0 - p.z, 0.0, p.z - z1});
  return std::sqrt(dx * dx + dz * dz);
}

}  // namespace

TEST_CASE("minimal integration: hard shadows match Embree, AO and motion vectors hold", "[minimal][embree]") {
  const int W = 192, H = 128;
  const fs::path dir = fs::temp_directory_path() / "raybridge_minimal_integration";
  fs::remove_all(dir);
  // RAYBRIDGE_MINIMAL_INTEGRATION overrides the program built with this test (the GPU machine runs a carried copy).
  const char* overridden = std::getenv("RAYBRIDGE_MINIMAL_INTEGRATION");
  const std::string exe = overridden && *overridden ? overridden : MINIMAL_INTEGRATION_EXE;
  const std::string command = std::string("\"") + exe + "\" --validate --frames 4 --width " + std::to_string(W) +
                              " --height " + std::to_string(H) + " --out \"" + dir.string() + "\"";
  // Non-zero on any Vulkan or Raybridge error and on any validation error (synchronization validation
  // included).
  REQUIRE(std::system(command.c_str()) == 0);

  int w = 0, h = 0;
  const std::vector<float> depth = readPfm(dir / "depth.pfm", 1, w, h);
  REQUIRE((w == W && h == H));
  const std::vector<float> shadow = readPfm(dir / "shadow.pfm", 1, w, h);
  const std::vector<float> ao = readPfm(dir / "ao.pfm", 1, w, h);
  const std::vector<float> motion = readPfm(dir / "motion.pfm", 3, w, h);
  REQUIRE(fs::file_size(dir / "composite.png") > 0);
  auto camera = readCamera(dir / "camera.txt");
  const glm::dvec3 eye(camera["eye"].at(0), camera["eye"].at(1), camera["eye"].at(2));
  const glm::dmat4 projection = matrix(camera["projection"]);
  const glm::dmat4 inverseViewProjection = glm::inverse(projection * matrix(camera["view"]));
  const glm::dmat4 previousViewProjection = projection * matrix(camera["previousView"]);

  // Embree over the same world-space triangles.
  const std::vector<minimal::Mesh> scene = minimal::makeScene();
  rbtest::EmbreeScene embree;
  const float identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  for (uint32_t i = 0; i < scene.size(); ++i) {
    rbsamples::CpuMesh mesh;
    mesh.positions = scene[i].positions;
    mesh.indices = scene[i].indices;
    embree.addInstance(mesh, identity, i);
  }
  embree.commit();
  const glm::dvec3 toSun = glm::normalize(glm::dvec3(minimal::kToSun[0], minimal::kToSun[1], minimal::kToSun[2]));
  const glm::vec3 toSunF(toSun);

  auto unproject = [&](int x, int y, double z) {
    glm::dvec4 p = inverseViewProjection * glm::dvec4((x + 0.5) / W * 2.0 - 1.0, (y + 0.5) / H * 2.0 - 1.0, z, 1.0);
    return glm::dvec3(p) / p.w;
  };
  std::vector<Pixel> px(size_t(W) * H);
  uint32_t skyMismatch = 0;
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      Pixel& p = px[size_t(y) * W + x];
      const glm::vec3 origin(eye), direction(glm::normalize(unproject(x, y, 1.0) - eye));  // depth 1 = near plane
      const rbtest::ReferenceHit hit = embree.intersect(&origin.x, &direction.x, 0.0f, 1e30f);
      const float d = depth[size_t(y) * W + x];
      skyMismatch += hit.hit != (d != 0.0f);
      if (!hit.hit || d == 0.0f) continue;
      p.sky = false;
      p.instance = hit.instanceId;
      p.distance = hit.t;
      p.position = unproject(x, y, d);  // the program's reversed-Z depth, through its own camera
      p.normal = glm::normalize(glm::dvec3(hit.geometricNormal[0], hit.geometricNormal[1], hit.geometricNormal[2]));
      if (glm::dot(p.normal, glm::dvec3(direction)) > 0.0) p.normal = -p.normal;
      if (glm::dot(p.normal, toSun) <= 0.0) {
        p.visible = 0;
        continue;
      }
      const glm::vec3 o(p.position + p.normal * (1e-4 * std::max(1.0, p.distance)));
      p.visible = embree.intersect(&o.x, &toSunF.x, 0.0f, 1e30f).hit ? 0 : 1;
    }
  }
  CHECK(skyMismatch <= uint32_t(W + H));  // sky agrees but for the horizon's pixels

  // Compared: geometry pixels whose 3x3 neighbourhood is neither sky, another object, another face (a box
  // edge), another distance (a silhouette) nor another reference visibility (a shadow edge): a 1-pixel band.
  uint32_t compared = 0, shadowAgree = 0, shadowed = 0, depthAgree = 0, motionAgree = 0, moving = 0;
  double nearAo = 0, openAo = 0;
  uint32_t nearCount = 0, openCount = 0;
  for (int y = 1; y + 1 < H; ++y) {
    for (int x = 1; x + 1 < W; ++x) {
      const size_t i = size_t(y) * W + x;
      const Pixel& p = px[i];
      if (p.sky) continue;
      bool edge = false;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const Pixel& n = px[size_t(y + dy) * W + size_t(x + dx)];
          edge |= n.sky || n.instance != p.instance || n.visible != p.visible || glm::dot(n.normal, p.normal) < 0.9 ||
                  std::fabs(n.distance - p.distance) > 0.1 * p.distance;
        }
      }
      if (edge) continue;
      ++compared;
      shadowed += p.visible == 0;
      shadowAgree += (shadow[i] > 0.5f) == (p.visible == 1);
      depthAgree += glm::length(p.position - (eye + glm::normalize(unproject(x, y, 1.0) - eye) * p.distance)) <=
                    2e-3 * p.distance;
      // Motion: this pixel's centre minus where its surface point was in the previous frame, in pixels.
      const glm::dvec4 prev = previousViewProjection * glm::dvec4(p.position, 1.0);
      const glm::dvec2 expected = glm::dvec2(x + 0.5, y + 0.5) -
                                  (glm::dvec2(prev) / prev.w * 0.5 + 0.5) * glm::dvec2(W, H);
      const glm::dvec2 got(motion[3 * i], motion[3 * i + 1]);
      motionAgree += glm::length(got - expected) <= 0.02 + 0.005 * glm::length(expected);
      moving += glm::length(got) > 0.25;
      // AO on the ground: right beside the box against far from every object.
      if (p.instance == 0) {
        const double nearBox = footprintDistance(scene[1], p.position);
        double nearest = 1e30;
        for (size_t m = 1; m < scene.size(); ++m) nearest = std::min(nearest, footprintDistance(scene[m], p.position));
        if (nearBox > 0.0 && nearBox < 0.25) nearAo += ao[i], ++nearCount;
        if (nearest > 2.5) openAo += ao[i], ++openCount;
      }
    }
  }
  INFO("compared " << compared << " pixels (" << shadowed << " shadowed): shadow agrees on " << shadowAgree
                   << ", depth on " << depthAgree << ", motion on " << motionAgree << " (" << moving << " moving)");
  REQUIRE(compared > uint32_t(W * H / 3));
  REQUIRE(shadowed > 300);  // the boxes, the sphere and the floating slab really cast shadows in view
  CHECK(double(shadowAgree) / compared >= 0.99);
  CHECK(double(depthAgree) / compared >= 0.99);
  CHECK(double(motionAgree) / compared >= 0.99);
  CHECK(double(moving) / compared >= 0.99);  // the camera moved: every surface pixel has motion

  // AO: an open fraction, darker beside the box than on open ground.
  CHECK(std::all_of(ao.begin(), ao.end(), [](float v) { return v >= 0.0f && v <= 1.0f; }));
  REQUIRE(nearCount > 20);
  REQUIRE(openCount > 200);
  INFO("AO beside the box " << nearAo / nearCount << " over " << nearCount << " pixels, open ground "
                            << openAo / openCount << " over " << openCount);
  CHECK(nearAo / nearCount < openAo / openCount - 0.1);
  CHECK(openAo / openCount > 0.9);
}
