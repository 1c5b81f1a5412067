#include "light_field_scene.h"

#include <algorithm>
#include <cmath>

#include "scene_math.h"

namespace rbbench {

namespace {

constexpr double kLightMinHeight = 0.8, kLightMaxHeight = 3.0;  // metres: under most pillar tops
constexpr double kLightClearance = 0.5;                         // metres kept from any pillar
constexpr float kSpotOuterDegrees = 55.0f, kSpotInnerDegrees = 35.0f;
constexpr uint32_t kSpotEvery = 4;
constexpr uint32_t kNormalisationSteps = 2048;  // midpoint rule over theta

// Integral over an unbounded floor of falloff * cos for unit intensity (see the header), in square metres.
double floorIntegral(double height, double range, bool spot) {
  const double cosOuter = std::cos(kSpotOuterDegrees * kPi / 180.0);
  const double cosInner = std::cos(kSpotInnerDegrees * kPi / 180.0);
  double sum = 0.0;
  const double step = (kPi / 2) / kNormalisationSteps;
  for (uint32_t i = 0; i < kNormalisationSteps; ++i) {
    const double theta = (i + 0.5) * step;
    const double d = height / std::cos(theta);
    double f = std::clamp(1.0 - std::pow(d / range, 4.0), 0.0, 1.0);
    if (spot) {
      const double c = std::clamp((std::cos(theta) - cosOuter) / (cosInner - cosOuter), 0.0, 1.0);
      f *= c * c;
    }
    sum += std::sin(theta) * f * step;
  }
  return 2.0 * kPi * sum;
}

void hsvToRgb(double h, double s, double v, float rgb[3]) {
  const double c = v * s, hp = h * 6.0, x = c * (1.0 - std::fabs(std::fmod(hp, 2.0) - 1.0));
  double r = 0, g = 0, b = 0;
  if (hp < 1) r = c, g = x;
  else if (hp < 2)
    r = x, g = c;
  else if (hp < 3)
    g = c, b = x;
  else if (hp < 4)
    g = x, b = c;
  else if (hp < 5)
    r = x, b = c;
  else
    r = c, b = x;
  const double m = v - c;
  rgb[0] = float(r + m), rgb[1] = float(g + m), rgb[2] = float(b + m);
}

}  // namespace

LightFieldScene makeLightFieldScene(const LightFieldDesc& desc) {
  LightFieldScene s;
  s.desc = desc;
  s.floor = rbsamples::makeGrid(desc.floorSide, desc.floorCells);
  const float unitMin[3] = {0, 0, 0}, unitMax[3] = {1, 1, 1};
  s.box = rbsamples::makeBox(unitMin, unitMax, desc.boxCells);
  s.instanceTransforms.push_back({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0});
  SplitMix64 rng{desc.seed};
  const double cell = double(desc.floorSide) / desc.pillarsPerSide;
  for (uint32_t r = 0; r < desc.pillarsPerSide; ++r) {
    for (uint32_t c = 0; c < desc.pillarsPerSide; ++c) {
      // Mostly slender pillars taller than the lights (long shadows), one in five a low wide box the lights
      // may stand over.
      const bool lowBox = rng.next() < 0.2;
      const double sx = lowBox ? rng.in(2.0, 3.5) : rng.in(0.8, 2.0);
      const double sz = lowBox ? rng.in(2.0, 3.5) : rng.in(0.8, 2.0);
      const double sy = lowBox ? rng.in(0.6, 1.2) : rng.in(2.5, 6.0);
      const double cx = -desc.floorSide / 2 + (c + 0.5) * cell + rng.in(-0.25, 0.25) * (cell - sx);
      const double cz = -desc.floorSide / 2 + (r + 0.5) * cell + rng.in(-0.25, 0.25) * (cell - sz);
      Pillar p{{float(cx - sx / 2), 0.0f, float(cz - sz / 2)}, {float(cx + sx / 2), float(sy), float(cz + sz / 2)}};
      s.pillars.push_back(p);
      const float dx = p.max[0] - p.min[0], dy = p.max[1] - p.min[1], dz = p.max[2] - p.min[2];
      s.instanceTransforms.push_back({dx, 0, 0, p.min[0], 0, dy, 0, p.min[1], 0, 0, dz, p.min[2]});
    }
  }
  return s;
}

rb::PrimaryRayCamera primaryCamera(const LightFieldCamera& camera) {
  rb::PrimaryRayCamera c;
  for (int i = 0; i < 3; ++i) c.eye[i] = float(camera.eye[i]), c.target[i] = float(camera.target[i]);
  c.verticalFovDegrees = float(camera.fovYDegrees);
  return c;
}

bool makeLightFieldGBuffer(const LightFieldScene& scene, const LightFieldCamera& camera, uint32_t width,
                           uint32_t height, const std::vector<float>& hitDistance, const std::vector<uint32_t>& hitIds,
                           LightFieldGBuffer& g, std::string& error) {
  rb::Result<rb::CameraBasis> basisResult = rb::computeCameraBasis(primaryCamera(camera), width, height);
  if (!basisResult) {
    error = basisResult.error().message;
    return false;
  }
  // The rays exactly as the raygen shader forms them (basis pre-scaled by tan(fovY/2) and the aspect ratio).
  const rb::CameraBasis& b = basisResult.value();
  const Vec3 F = {b.forward[0], b.forward[1], b.forward[2]}, R = {b.right[0], b.right[1], b.right[2]},
             U = {b.up[0], b.up[1], b.up[2]};
  const Vec3 forward = normalized(F), side = normalized(R), up = normalized(U);
  g = {};
  g.width = width;
  g.height = height;
  // glm::lookAtRH without translation, and a reversed-Z infinite-far perspective with Y flipped for Vulkan:
  // depth = near / viewDistance, 0 at infinity (the sky's clear value).
  for (int i = 0; i < 3; ++i) {
    g.view[i * 4 + 0] = float(side[i]);
    g.view[i * 4 + 1] = float(up[i]);
    g.view[i * 4 + 2] = float(-forward[i]);
  }
  g.view[15] = 1.0f;
  const double tanHalf = std::tan(camera.fovYDegrees * kPi / 360.0);
  const double aspect = double(width) / double(height);
  g.projection[0] = float(1.0 / (aspect * tanHalf));
  g.projection[5] = float(-1.0 / tanHalf);
  g.projection[11] = -1.0f;
  g.projection[14] = float(camera.nearPlane);

  const size_t pixels = size_t(width) * height;
  if (hitDistance.size() != pixels || hitIds.size() != 2 * pixels) {
    error = "hit images of the wrong size";
    return false;
  }
  g.depth.assign(pixels, 0.0f);
  g.normal.assign(4 * pixels, 0.0f);
  g.surface.assign(pixels, 0);
  g.position.assign(3 * pixels, 0.0f);
  g.instance.assign(pixels, ~0u);
  for (uint32_t y = 0; y < height; ++y) {
    for (uint32_t x = 0; x < width; ++x) {
      const size_t i = size_t(y) * width + x;
      const double t = hitDistance[i];
      if (!(t > 0.0)) continue;
      const double ndcX = (x + 0.5) / width * 2.0 - 1.0, ndcY = (y + 0.5) / height * 2.0 - 1.0;
      Vec3 dir;
      for (int k = 0; k < 3; ++k) dir[k] = F[k] + ndcX * R[k] - ndcY * U[k];
      dir = normalized(dir);
      const double viewDistance = t * dot(dir, forward);
      g.depth[i] = float(camera.nearPlane / viewDistance);

      const uint32_t primitive = hitIds[2 * i], instance = hitIds[2 * i + 1];
      const rbsamples::CpuMesh& mesh = instance == 0 ? scene.floor : scene.box;
      if (instance >= scene.instanceTransforms.size() || primitive >= mesh.triangleCount()) {
        error = "pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") hit primitive " +
                std::to_string(primitive) + " of instance " + std::to_string(instance) + ", which does not exist";
        return false;
      }
      const std::array<float, 12>& m = scene.instanceTransforms[instance];
      Vec3 v[3];
      for (int k = 0; k < 3; ++k) {
        const float* p = &mesh.positions[3 * size_t(mesh.indices[3 * size_t(primitive) + k])];
        for (int r = 0; r < 3; ++r)
          v[k][r] = m[r * 4] * p[0] + m[r * 4 + 1] * p[1] + m[r * 4 + 2] * p[2] + m[r * 4 + 3];
      }
      Vec3 n = normalized(cross({v[1][0] - v[0][0], v[1][1] - v[0][1], v[1][2] - v[0][2]},
                                {v[2][0] - v[0][0], v[2][1] - v[0][1], v[2][2] - v[0][2]}));
      if (dot(n, dir) > 0.0) n = {-n[0], -n[1], -n[2]};  // facing the viewer, as rasterised
      for (int k = 0; k < 3; ++k) {
        g.normal[4 * i + k] = float(n[k]);
        g.position[3 * i + k] = float(camera.eye[k] + t * dir[k]);
      }
      g.surface[i] = 1;
      g.instance[i] = instance;
      ++g.surfacePixels;
    }
  }
  return true;
}

LightField makeLightField(const LightFieldScene& scene, uint32_t count) {
  LightField f;
  const double side = scene.desc.floorSide;
  f.range = float(side * std::sqrt(kLightCoverage / (kPi * std::max(count, 1u))));
  SplitMix64 rng{scene.desc.seed ^ (0x9e3779b97f4a7c15ull * (uint64_t(count) + 1))};
  auto insidePillar = [&](double x, double y, double z) {
    for (const Pillar& p : scene.pillars) {
      if (x > p.min[0] - kLightClearance && x < p.max[0] + kLightClearance && z > p.min[2] - kLightClearance &&
          z < p.max[2] + kLightClearance && y < p.max[1] + kLightClearance)
        return true;
    }
    return false;
  };
  f.minIntensity = 1e30;
  for (uint32_t i = 0; i < count; ++i) {
    double x = 0, y = 0, z = 0;
    do {
      x = rng.in(-side / 2, side / 2);
      z = rng.in(-side / 2, side / 2);
      y = rng.in(kLightMinHeight, kLightMaxHeight);
    } while (insidePillar(x, y, z));
    rb::LightSource l;
    const bool spot = i % kSpotEvery == kSpotEvery - 1;
    l.light.type = spot ? rb::LightType::Spot : rb::LightType::Point;
    l.light.position[0] = float(x), l.light.position[1] = float(y), l.light.position[2] = float(z);
    l.light.range = f.range;
    if (spot) {
      l.light.direction[0] = 0.0f, l.light.direction[1] = -1.0f, l.light.direction[2] = 0.0f;
      l.light.spotOuterAngleDegrees = kSpotOuterDegrees;
      l.spotInnerAngleDegrees = kSpotInnerDegrees;
      ++f.spotLights;
    }
    hsvToRgb(rng.next(), 0.65, 1.0, l.color);
    const double intensity = kMeanIrradiance * side * side / (double(count) * floorIntegral(y, f.range, spot));
    l.intensity = float(intensity);
    f.minIntensity = std::min(f.minIntensity, intensity);
    f.maxIntensity = std::max(f.maxIntensity, intensity);
    f.lights.push_back(l);
  }
  return f;
}

CpuIrradiance referenceIrradiance(const LightFieldScene& scene, const LightFieldGBuffer& g,
                                  const std::vector<rb::LightSource>& lights) {
  constexpr double kOriginOffset = 1e-3;  // metres along the normal: clear of the surface the point lies on
  const size_t pixels = g.surface.size();
  CpuIrradiance r;
  r.rgba.assign(4 * pixels, 0.0f);
  r.lit.assign(pixels, 0);
  r.visible.assign(pixels, 0);
  r.interior.assign(pixels, 0);
  std::vector<float>& out = r.rgba;
  // Whether the segment from o along unit d up to tMax crosses a pillar (slab test). The floor cannot occlude:
  // lights and surface points are at or above it.
  auto occluded = [&](const Vec3& o, const Vec3& d, double tMax) {
    for (const Pillar& p : scene.pillars) {
      double t0 = 0.0, t1 = tMax;
      for (int k = 0; k < 3 && t0 <= t1; ++k) {
        if (std::fabs(d[k]) < 1e-12) {
          if (o[k] < p.min[k] || o[k] > p.max[k]) t0 = t1 + 1.0;
          continue;
        }
        double a = (p.min[k] - o[k]) / d[k], b = (p.max[k] - o[k]) / d[k];
        if (a > b) std::swap(a, b);
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
      }
      if (t0 <= t1) return true;
    }
    return false;
  };
  for (size_t i = 0; i < pixels; ++i) {
    if (!g.surface[i]) continue;
    out[4 * i + 3] = 1.0f;
    const Vec3 n = {g.normal[4 * i], g.normal[4 * i + 1], g.normal[4 * i + 2]};
    const Vec3 p = {g.position[3 * i], g.position[3 * i + 1], g.position[3 * i + 2]};
    const Vec3 o = {p[0] + n[0] * kOriginOffset, p[1] + n[1] * kOriginOffset, p[2] + n[2] * kOriginOffset};
    double e[3] = {0, 0, 0};
    for (size_t k = 0; k < lights.size(); ++k) {
      const rb::LightSource& s = lights[k];
      const uint32_t bit = k < 32 ? 1u << k : 0u;
      const rb::Light& l = s.light;
      Vec3 toLight = {l.position[0] - p[0], l.position[1] - p[1], l.position[2] - p[2]};
      const double distance = std::sqrt(dot(toLight, toLight));
      toLight = {toLight[0] / distance, toLight[1] / distance, toLight[2] / distance};
      const double cosine = dot(n, toLight);
      if (cosine <= 0.0) continue;
      double falloff = 1.0 / (distance * distance);
      if (l.range > 0.0f) falloff *= std::clamp(1.0 - std::pow(distance / l.range, 4.0), 0.0, 1.0);
      if (l.type == rb::LightType::Spot) {
        const double cosOuter = std::cos(double(l.spotOuterAngleDegrees) * kPi / 180.0);
        const double cosInner = std::cos(double(s.spotInnerAngleDegrees) * kPi / 180.0);
        const Vec3 axis = normalized({l.direction[0], l.direction[1], l.direction[2]});
        const double c = std::clamp((-dot(toLight, axis) - cosOuter) / std::max(1e-3, cosInner - cosOuter), 0.0, 1.0);
        falloff *= c * c;
      }
      if (falloff <= 0.0) continue;
      r.lit[i] |= bit;
      Vec3 d = {l.position[0] - o[0], l.position[1] - o[1], l.position[2] - o[2]};
      const double reach = std::sqrt(dot(d, d));
      d = {d[0] / reach, d[1] / reach, d[2] / reach};
      if (occluded(o, d, reach)) continue;
      r.visible[i] |= bit;
      for (int c = 0; c < 3; ++c) e[c] += double(s.color[c]) * s.intensity * cosine * falloff;
    }
    for (int c = 0; c < 3; ++c) out[4 * i + c] = float(e[c]);
  }
  const int w = int(g.width), h = int(g.height);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      bool same = g.surface[i] != 0;
      for (int dy = -1; dy <= 1 && same; ++dy) {
        for (int dx = -1; dx <= 1 && same; ++dx) {
          const size_t j = size_t(std::clamp(y + dy, 0, h - 1)) * w + size_t(std::clamp(x + dx, 0, w - 1));
          same = g.instance[j] == g.instance[i] && r.lit[j] == r.lit[i] && r.visible[j] == r.visible[i];
        }
      }
      r.interior[i] = same;
    }
  }
  return r;
}

}  // namespace rbbench
