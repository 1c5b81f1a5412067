// The default demo scene's alpha-tested leaf canopy, on the CPU: the generated leaf texture (open share, soft
// edges, determinism, seamless tiling) and, with a small ray caster, that the canopy throws a dappled shadow
// (partly blocked, partly through its holes) onto ground the camera sees, without hiding the other objects.
#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include <catch2/catch_test_macros.hpp>

#include "sample_engine/procedural.h"

using namespace sample_engine;

namespace {

// Coverage of texel (x, y) in [0, 1].
float alphaAt(const TextureData& t, uint32_t x, uint32_t y) {
  return t.rgba8[(size_t(y) * t.width + x) * 4 + 3] / 255.0f;
}

// Share of the texels a Mask material with this cutoff discards.
double openFraction(const TextureData& t, float factorAlpha, float cutoff) {
  size_t open = 0;
  for (uint32_t y = 0; y < t.height; ++y)
    for (uint32_t x = 0; x < t.width; ++x) open += factorAlpha * alphaAt(t, x, y) < cutoff;
  return double(open) / (double(t.width) * t.height);
}

// Mean |alpha difference| between column x and the next one (wrapping): across the border for x = width - 1.
double columnStep(const TextureData& t, uint32_t x) {
  double sum = 0;
  for (uint32_t y = 0; y < t.height; ++y) sum += std::abs(alphaAt(t, x, y) - alphaAt(t, (x + 1) % t.width, y));
  return sum / t.height;
}

// The scene flattened to world-space triangles, with a box per instance to skip most of them per ray.
struct Triangle {
  glm::vec3 p[3];
  glm::vec2 uv[3];
};
struct FlatInstance {
  std::vector<Triangle> triangles;
  glm::vec3 lo{1e30f}, hi{-1e30f};
  const Material* material = nullptr;
  const TextureData* texture = nullptr;  // base colour, when the material has one
  bool mask() const { return material->alphaMode == AlphaMode::Mask; }
};

std::vector<FlatInstance> flatten(const Scene& s) {
  std::vector<FlatInstance> out;
  for (const Instance& inst : s.instances) {
    const MeshData& m = s.meshes[inst.mesh];
    FlatInstance f;
    f.material = &s.materials[m.material];
    if (f.material->baseColorTexture >= 0) f.texture = &s.textures[size_t(f.material->baseColorTexture)];
    const uint32_t n = m.triangleCount();
    for (uint32_t t = 0; t < n; ++t) {
      Triangle tri;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = m.indices.empty() ? 3 * t + k : m.indices[3 * t + k];
        tri.p[k] = glm::vec3(inst.transform * glm::vec4(m.positions[v], 1.0f));
        tri.uv[k] = m.uvs.empty() ? glm::vec2(0.0f) : m.uvs[v];
        f.lo = glm::min(f.lo, tri.p[k]);
        f.hi = glm::max(f.hi, tri.p[k]);
      }
      f.triangles.push_back(tri);
    }
    out.push_back(std::move(f));
  }
  return out;
}

bool rayHitsBox(const glm::vec3& o, const glm::vec3& d, const glm::vec3& lo, const glm::vec3& hi, float tMax) {
  float t0 = 0.0f, t1 = tMax;
  for (int a = 0; a < 3; ++a) {
    const float inv = 1.0f / d[a];
    float ta = (lo[a] - 1e-4f - o[a]) * inv, tb = (hi[a] + 1e-4f - o[a]) * inv;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

struct Hit {
  float t;
  glm::vec2 uv;
};

// Möller-Trumbore, both faces.
std::optional<Hit> intersect(const Triangle& tri, const glm::vec3& o, const glm::vec3& d, float tMin, float tMax) {
  const glm::vec3 e1 = tri.p[1] - tri.p[0], e2 = tri.p[2] - tri.p[0], pv = glm::cross(d, e2);
  const float det = glm::dot(e1, pv);
  if (std::abs(det) < 1e-12f) return std::nullopt;
  const glm::vec3 tv = o - tri.p[0];
  const float u = glm::dot(tv, pv) / det;
  if (u < 0.0f || u > 1.0f) return std::nullopt;
  const glm::vec3 qv = glm::cross(tv, e1);
  const float v = glm::dot(d, qv) / det;
  if (v < 0.0f || u + v > 1.0f) return std::nullopt;
  const float t = glm::dot(e2, qv) / det;
  if (t <= tMin || t >= tMax) return std::nullopt;
  return Hit{t, tri.uv[0] * (1.0f - u - v) + tri.uv[1] * u + tri.uv[2] * v};
}

// Whether a Mask material keeps the surface at `uv` (nearest texel, repeating, rows from the top).
bool covers(const FlatInstance& f, glm::vec2 uv) {
  if (!f.mask()) return true;
  float alpha = f.material->baseColorFactor.a;
  if (f.texture) {
    const glm::vec2 wrapped = uv - glm::floor(uv);
    const uint32_t x = std::min(uint32_t(wrapped.x * f.texture->width), f.texture->width - 1);
    const uint32_t y = std::min(uint32_t(wrapped.y * f.texture->height), f.texture->height - 1);
    alpha *= alphaAt(*f.texture, x, y);
  }
  return alpha >= f.material->alphaCutoff;
}

struct Trace {
  float t = 1e30f;
  int instance = -1;         // nearest surface kept by the alpha test
  bool crossesMask = false;  // the ray meets a Mask triangle no farther than that (kept or not)
};

Trace trace(const std::vector<FlatInstance>& scene, const glm::vec3& o, const glm::vec3& d, float tMin = 0.0f) {
  Trace r;
  std::vector<float> maskHits;
  for (size_t i = 0; i < scene.size(); ++i) {
    const FlatInstance& f = scene[i];
    if (!rayHitsBox(o, d, f.lo, f.hi, r.t)) continue;
    for (const Triangle& tri : f.triangles) {
      std::optional<Hit> h = intersect(tri, o, d, tMin, r.t);
      if (!h) continue;
      const bool kept = covers(f, h->uv);
      if (f.mask()) maskHits.push_back(h->t);
      if (kept) {
        r.t = h->t;
        r.instance = int(i);
      }
    }
  }
  r.crossesMask = std::any_of(maskHits.begin(), maskHits.end(), [&](float t) { return t <= r.t; });
  return r;
}

// The ray through the centre of pixel (x, y) of a w x h image, with the engine's matrices.
glm::vec3 pixelRay(const Camera& camera, const glm::mat4& invViewProj, uint32_t x, uint32_t y, uint32_t w, uint32_t h) {
  const glm::vec2 ndc((x + 0.5f) / float(w) * 2.0f - 1.0f, (y + 0.5f) / float(h) * 2.0f - 1.0f);
  const glm::vec4 far = invViewProj * glm::vec4(ndc, 1.0f, 1.0f);
  return glm::normalize(glm::vec3(far) / far.w - camera.eye);
}

}  // namespace

TEST_CASE("makeLeafTexture: open share near the request, soft edges, deterministic, seamless", "[demo]") {
  const TextureData a = makeLeafTexture(256, 1);
  REQUIRE(a.width == 256);
  REQUIRE(a.height == 256);
  REQUIRE(a.rgba8.size() == size_t(256) * 256 * 4);
  const double open = openFraction(a, 1.0f, 0.5f);
  INFO("open " << open);
  // Leaves are added until the open share drops to the request; the last one covers < 2% of this texture.
  CHECK(open <= kDefaultLeafOpenFraction + 1e-6);
  CHECK(open > kDefaultLeafOpenFraction - 0.03);
  for (float request : {0.2f, 0.6f}) {
    const double got = openFraction(makeLeafTexture(128, 3, request), 1.0f, 0.5f);
    INFO("requested " << request << ", got " << got);
    CHECK(got <= request + 1e-6);
    CHECK(got > request - 0.05);
  }

  size_t soft = 0, greener = 0, covered = 0;
  for (size_t i = 0; i < a.rgba8.size(); i += 4) {
    soft += a.rgba8[i + 3] > 0 && a.rgba8[i + 3] < 255;
    if (a.rgba8[i + 3] >= 128) {
      ++covered;
      greener += a.rgba8[i + 1] > a.rgba8[i] && a.rgba8[i + 1] > a.rgba8[i + 2];
    }
  }
  CHECK(soft > a.rgba8.size() / 4 / 50);  // edge ramps, not a hard 0/1 mask
  CHECK(soft < a.rgba8.size() / 4 / 3);
  CHECK(greener > covered * 9 / 10);  // leaves are green (stems are the rest)

  CHECK((makeLeafTexture(256, 1).rgba8 == a.rgba8));
  const TextureData b = makeLeafTexture(256, 2);
  size_t differ = 0;
  for (size_t i = 3; i < a.rgba8.size(); i += 4) differ += (a.rgba8[i] >= 128) != (b.rgba8[i] >= 128);
  CHECK(differ > a.rgba8.size() / 4 / 5);  // another seed, another layout (independent layouts: ~48%)

  // Leaves cut at the border would make the step across it much larger than between inner columns.
  double inner = 0;
  for (uint32_t x = 0; x + 1 < a.width; ++x) inner += columnStep(a, x);
  inner /= a.width - 1;
  INFO("mean column step " << inner << ", across the border " << columnStep(a, a.width - 1));
  CHECK(columnStep(a, a.width - 1) < 2.0 * inner);
  CHECK(makeLeafTexture(1, 0).width == 16);  // clamped
}

TEST_CASE("the demo scene's leaf canopy throws a dappled shadow on ground in view", "[demo]") {
  const Scene scene = makeDefaultDemoScene();
  REQUIRE(scene.camera);
  REQUIRE(scene.sun);

  // A Mask material with a base colour texture that has holes and leaves in a sensible ratio.
  bool found = false;
  for (const Material& m : scene.materials) {
    if (m.alphaMode != AlphaMode::Mask) continue;
    CHECK(m.alphaCutoff == 0.5f);
    CHECK(m.doubleSided);
    REQUIRE(m.baseColorTexture >= 0);
    REQUIRE(size_t(m.baseColorTexture) < scene.textures.size());
    const double open = openFraction(scene.textures[size_t(m.baseColorTexture)], m.baseColorFactor.a, m.alphaCutoff);
    INFO(m.name << ": open " << open);
    CHECK(open > 0.15);
    CHECK(open < 0.70);
    found = true;
  }
  REQUIRE(found);

  const std::vector<FlatInstance> flat = flatten(scene);
  size_t maskTriangles = 0;
  glm::vec3 maskLo(1e30f), maskHi(-1e30f);
  for (const FlatInstance& f : flat)
    if (f.mask()) {
      maskTriangles += f.triangles.size();
      maskLo = glm::min(maskLo, f.lo);
      maskHi = glm::max(maskHi, f.hi);
    }
  REQUIRE(maskTriangles > 0);
  CHECK(maskTriangles < 1000);  // cards, not modelled leaves

  // The default render size's aspect (1280x720), a coarse grid of pixels.
  const uint32_t w = 192, h = 108;
  const Camera& camera = *scene.camera;
  const glm::mat4 inv = glm::inverse(projectionMatrix(camera, float(w) / float(h)) * viewMatrix(camera));
  const glm::vec3 toSun = glm::normalize(scene.sun->direction);
  uint32_t ground = 0, canopyPixels = 0, underCanopy = 0, lit = 0, leafShadow = 0;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const glm::vec3 d = pixelRay(camera, inv, x, y, w, h);
      const Trace view = trace(flat, camera.eye, d);
      if (view.instance < 0) continue;
      if (flat[size_t(view.instance)].mask()) ++canopyPixels;
      const glm::vec3 p = camera.eye + d * view.t;
      if (std::abs(p.y) > 1e-3f) continue;  // not the ground (the mirror patch is 2 cm thick)
      ++ground;
      const Trace sun = trace(flat, p, toSun, 1e-3f);
      if (!sun.crossesMask) continue;
      ++underCanopy;
      lit += sun.instance < 0;
      leafShadow += sun.instance >= 0 && flat[size_t(sun.instance)].mask();
    }
  INFO("ground pixels " << ground << ", canopy pixels " << canopyPixels << ", ground whose sun ray crosses the "
                        << "canopy " << underCanopy << ": lit through holes " << lit << ", shadowed by leaves "
                        << leafShadow);
  REQUIRE(ground > w * h / 3);
  CHECK(canopyPixels > w * h / 400);  // the canopy itself is in view
  CHECK(underCanopy > ground / 30);   // and so is its shadow, not a sliver of it
  // Dappled: part of the sun rays get through the holes, most of the rest stop on leaves.
  CHECK(lit > underCanopy / 8);
  CHECK(lit < underCanopy * 4 / 5);
  CHECK(leafShadow > underCanopy / 4);

  // Nothing else hides behind the canopy: sight lines from the eye to points of every object that stands
  // outside the pergola's footprint cross no canopy triangle. And nothing but the pergola's own parts (inside
  // the footprint) reaches into the canopy's box: no column or object pierces it.
  uint32_t objects = 0;
  for (const FlatInstance& f : flat) {
    const bool withinFootprint = f.lo.x >= maskLo.x && f.hi.x <= maskHi.x && f.lo.z >= maskLo.z && f.hi.z <= maskHi.z;
    if (f.mask() || withinFootprint) continue;
    CHECK_FALSE((glm::all(glm::lessThan(f.lo, maskHi)) && glm::all(glm::greaterThan(f.hi, maskLo))));
    const bool overlapsFootprint = f.lo.x < maskHi.x && f.hi.x > maskLo.x && f.lo.z < maskHi.z && f.hi.z > maskLo.z;
    if (overlapsFootprint) continue;  // the ground
    ++objects;
    const glm::vec3 mid = (f.lo + f.hi) * 0.5f, half = (f.hi - f.lo) * 0.45f;
    for (int corner = 0; corner < 9; ++corner) {
      const glm::vec3 sign = corner == 8 ? glm::vec3(0.0f)
                                         : glm::vec3(corner & 1 ? 1 : -1, corner & 2 ? 1 : -1, corner & 4 ? 1 : -1);
      const glm::vec3 d = mid + sign * half - camera.eye;
      const float length = glm::length(d);
      bool hidden = false;
      for (const FlatInstance& m : flat) {
        if (!m.mask()) continue;
        for (const Triangle& tri : m.triangles)
          hidden |= intersect(tri, camera.eye, d / length, 0.0f, length).has_value();
      }
      CHECK_FALSE(hidden);
    }
  }
  CHECK(objects > 10);
}
