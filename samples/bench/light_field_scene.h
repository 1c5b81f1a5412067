// The lights scenario's scene on the CPU: a "light field", a large finely tessellated floor with a lattice of
// pillars and low boxes on it, seen from above at an angle, lit by N seeded point and spot lights scattered
// just above the floor. Also turns the primary rays' hits into the G-buffer the many-light pass reads.
//
// Light rule (makeLightField): the lights are spread uniformly over the floor, so that about kLightCoverage of
// them reach any floor point whatever N, each light's range is
//     range(N) = floorSide * sqrt(kLightCoverage / (pi * N))        (every light reaches everything below 24)
// and its intensity is set so that, unshadowed over an unbounded floor, it adds kMeanIrradiance / N times its
// colour (a saturated hue, brightest channel 1) to the floor's mean irradiance:
//     intensity = kMeanIrradiance * floorSide^2 / (N * G),  G = integral over the floor of falloff * cos
//               = 2 pi * integral over theta in [0, pi/2) of sin(theta) * window(h / cos theta) * cone(theta)
// (theta from the vertical, h the light's height, window and cone those of many_light_pass.h). The images of
// every N then have about the same mean irradiance (less the shadows and what falls off the floor's edges),
// and the per-pixel light count, hence the exact mode's cost, is bounded.
//
// Thread safety: plain data and pure functions of their arguments.
#pragma once

#include <raybridge/many_light_pass.h>
#include <raybridge/primary_ray_pass.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "procedural_meshes.h"

namespace rbbench {

inline constexpr double kLightCoverage = 24.0;  // lights reaching a floor point, on average (N >= 24)
inline constexpr double kMeanIrradiance = 1.0;  // lux, the unshadowed floor mean every N aims at
inline constexpr uint32_t kLightFieldSeed = 0x11647u;

struct LightFieldDesc {
  float floorSide = 96.0f;       // metres, centred at the origin in XZ
  uint32_t floorCells = 512;     // per side: 2 * cells^2 floor triangles
  uint32_t pillarsPerSide = 14;  // a jittered lattice of pillars and boxes
  uint32_t boxCells = 8;         // per face side: 12 * cells^2 triangles per pillar
  uint64_t seed = kLightFieldSeed;
};

// An axis-aligned pillar or box standing on the floor.
struct Pillar {
  float min[3], max[3];
};

struct LightFieldScene {
  LightFieldDesc desc;
  rbsamples::CpuMesh floor;  // y = 0
  rbsamples::CpuMesh box;    // the unit cube [0, 1]^3, scaled and moved per pillar
  std::vector<Pillar> pillars;
  // Instance 0 is the floor (identity), instance k >= 1 is pillars[k - 1]; customIndex = instance index.
  std::vector<std::array<float, 12>> instanceTransforms;  // row-major 3x4
  uint64_t instancedTriangles() const { return floor.triangleCount() + uint64_t(box.triangleCount()) * pillars.size(); }
};
LightFieldScene makeLightFieldScene(const LightFieldDesc& desc);

// The camera 40 m above the floor, 30 m in from its near edge, looking down at 60 degrees: it sees the floor
// from 3.5 m to 57 m ahead of it, all but the far corners (which are sky).
struct LightFieldCamera {
  double eye[3] = {0.0, 40.0, 30.0};
  double target[3] = {0.0, 0.0, 6.906};  // 40 m below the eye, 40 / tan(60 degrees) ahead
  double fovYDegrees = 50.0;
  double nearPlane = 0.1;  // reversed-Z, infinite far
};
rb::PrimaryRayCamera primaryCamera(const LightFieldCamera& camera);

// The G-buffer an engine would rasterise, built from primary-ray hits: D32 reversed-Z depth (0 = sky), world
// normals facing the viewer, and the camera-relative view (rotation only) and projection that reconstruct the
// hit points from depth.
struct LightFieldGBuffer {
  uint32_t width = 0, height = 0;
  float view[16] = {};
  float projection[16] = {};
  std::vector<float> depth;        // width * height
  std::vector<float> normal;       // 4 floats per pixel
  std::vector<float> position;     // world-space hit point, 3 floats per pixel (0 for sky)
  std::vector<uint32_t> instance;  // instance hit (0 = floor, k = pillars[k - 1]); ~0u for sky
  std::vector<uint8_t> surface;    // 1 where the pixel sees the scene
  uint64_t surfacePixels = 0;
};
// `hitDistance` and `hitIds` are PrimaryRayPass's targets read back (distance 0 on a miss; primitive id and
// instance custom index). Fails (returns false with `error`) on an id that names no triangle.
bool makeLightFieldGBuffer(const LightFieldScene& scene, const LightFieldCamera& camera, uint32_t width,
                           uint32_t height, const std::vector<float>& hitDistance, const std::vector<uint32_t>& hitIds,
                           LightFieldGBuffer& out, std::string& error);

struct LightField {
  std::vector<rb::LightSource> lights;
  float range = 0.0f;                             // metres, every light's
  uint32_t spotLights = 0;                        // every 4th light shines straight down
  double minIntensity = 0.0, maxIntensity = 0.0;  // candela
};
// `count` lights by the rule at the top of this file, deterministic for a seed; none inside a pillar.
LightField makeLightField(const LightFieldScene& scene, uint32_t count);

// The shadowed irradiance of many_light_pass.h at every surface pixel of a G-buffer, computed on the CPU (shadow
// rays against the pillars' boxes, in double): an independent check of the G-buffer, the light conversion and
// the pass; costs pixels * lights * pillars.
struct CpuIrradiance {
  std::vector<float> rgba;  // like ManyLightOutputs::irradiance: a = 1 on surfaces; sky all 0
  // Per pixel, bit k: light k reaches the point before shadows (lit) / and its shadow ray is free (visible).
  // Filled for up to 32 lights.
  std::vector<uint32_t> lit, visible;
  // 1 where the 3x3 neighbourhood sees the same surface with the same lit and visible lights: away from shadow and
  // silhouette edges, where a pixel centre may fall on either side in float and in double.
  std::vector<uint8_t> interior;
};
CpuIrradiance referenceIrradiance(const LightFieldScene& scene, const LightFieldGBuffer& gbuffer,
                                  const std::vector<rb::LightSource>& lights);

}  // namespace rbbench
