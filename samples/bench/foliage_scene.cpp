#include "foliage_scene.h"

#include <algorithm>
#include <cmath>

#include "scene_math.h"

namespace rbbench {

namespace {

constexpr double kCanopyMargin = 2.0;  // metres of leaves beyond the outermost shadow ray path

}  // namespace

AnalyticGBuffer makeGroundGBuffer(const FoliageView& v) {
  AnalyticGBuffer g;
  const double pitch = v.pitchDownDegrees * kPi / 180.0;
  const Vec3 forward = {0.0, -std::sin(pitch), -std::cos(pitch)};
  const Vec3 side = normalized(cross(forward, {0.0, 1.0, 0.0}));
  const Vec3 up = cross(side, forward);
  // glm::lookAtRH from the origin (camera-relative) and glm::perspectiveRH_ZO with Y flipped for Vulkan.
  for (int i = 0; i < 3; ++i) {
    g.view[i * 4 + 0] = float(side[i]);
    g.view[i * 4 + 1] = float(up[i]);
    g.view[i * 4 + 2] = float(-forward[i]);
  }
  g.view[15] = 1.0f;
  const double tanHalf = std::tan(v.fovYDegrees * kPi / 360.0);
  const double aspect = double(v.width) / double(v.height);
  const double n = v.nearPlane, f = v.farPlane;
  const double p22 = f / (n - f), p32 = -(f * n) / (f - n);
  g.projection[0] = float(1.0 / (aspect * tanHalf));
  g.projection[5] = float(-1.0 / tanHalf);
  g.projection[10] = float(p22);
  g.projection[11] = -1.0f;
  g.projection[14] = float(p32);

  g.depth.resize(size_t(v.width) * v.height);
  g.normal.assign(size_t(v.width) * v.height * 4, 0.0f);
  g.groundMin[0] = g.groundMin[1] = 1e30;
  g.groundMax[0] = g.groundMax[1] = -1e30;
  for (uint32_t y = 0; y < v.height; ++y) {
    for (uint32_t x = 0; x < v.width; ++x) {
      // The pixel centre's ray at view-space z = -1 (NDC +y is down), in world axes.
      const double ndcX = (x + 0.5) / v.width * 2.0 - 1.0, ndcY = (y + 0.5) / v.height * 2.0 - 1.0;
      const double vx = ndcX * aspect * tanHalf, vy = -ndcY * tanHalf;
      Vec3 d;
      for (int i = 0; i < 3; ++i) d[i] = side[i] * vx + up[i] * vy + forward[i];
      // The view looks down steeply enough that every ray falls (d.y < 0); the ground is y = 0.
      const double t = v.eye[1] / -d[1];  // = -z_view of the hit
      const size_t i = size_t(y) * v.width + x;
      g.depth[i] = float((p22 * -t + p32) / t);
      g.normal[4 * i + 1] = 1.0f;
      const double gx = v.eye[0] + t * d[0], gz = v.eye[2] + t * d[2];
      g.groundMin[0] = std::min(g.groundMin[0], gx);
      g.groundMin[1] = std::min(g.groundMin[1], gz);
      g.groundMax[0] = std::max(g.groundMax[0], gx);
      g.groundMax[1] = std::max(g.groundMax[1], gz);
    }
  }
  return g;
}

FoliageCards makeFoliageCards(const FoliageView& v, const AnalyticGBuffer& g, uint32_t cards, uint32_t chunks,
                              double meanCardsCrossed) {
  FoliageCards out;
  const Vec3 sun = normalized(v.toSun);
  // Shadow rays leave the ground box and climb along `sun`: over the canopy they sweep the ground box shifted
  // by the sun's horizontal run at the bottom and at the top of the leaf layer.
  for (int a = 0; a < 2; ++a) {
    const int axis = a == 0 ? 0 : 2;
    double lo = 1e30, hi = -1e30;
    for (double h : {v.canopyBottom, v.canopyTop}) {
      const double run = sun[axis] / sun[1] * h;
      lo = std::min(lo, g.groundMin[a] + run);
      hi = std::max(hi, g.groundMax[a] + run);
    }
    out.boxMin[axis] = lo - kCanopyMargin;
    out.boxMax[axis] = hi + kCanopyMargin;
  }
  out.boxMin[1] = v.canopyBottom;
  out.boxMax[1] = v.canopyTop;
  // Randomly oriented cards of area A, n per unit volume: a ray crosses n A / 2 of them per unit length (mean
  // |cos| over the sphere is 1/2), and its path through the layer is thickness / sun.y long.
  const double volume = (out.boxMax[0] - out.boxMin[0]) * (out.boxMax[1] - out.boxMin[1]) *
                        (out.boxMax[2] - out.boxMin[2]);
  const double path = (v.canopyTop - v.canopyBottom) / sun[1];
  out.cardSide = std::sqrt(2.0 * meanCardsCrossed * volume / (double(cards) * path));

  out.positions.reserve(size_t(cards) * 12);
  out.texcoords.reserve(size_t(cards) * 8);
  out.indices.reserve(size_t(cards) * 6);
  SplitMix64 rng{0x5eed1eafull};
  const double half = 0.5 * out.cardSide;
  struct Card {
    uint64_t morton;
    float corners[12];
  };
  std::vector<Card> chunk;
  for (uint32_t c = 0; c < chunks; ++c) {
    out.chunkFirstTriangle.push_back(out.triangleCount());
    const uint32_t inChunk = cards / chunks + (c < cards % chunks ? 1u : 0u);
    chunk.resize(inChunk);
    for (Card& card : chunk) {
      Vec3 centre;
      for (int i = 0; i < 3; ++i) centre[i] = out.boxMin[i] + rng.next() * (out.boxMax[i] - out.boxMin[i]);
      const double z = 2.0 * rng.next() - 1.0, phi = 2.0 * kPi * rng.next(), r = std::sqrt(1.0 - z * z);
      const Vec3 n = {r * std::cos(phi), z, r * std::sin(phi)};
      const Vec3 t0 = normalized(std::fabs(n[1]) < 0.9 ? cross(n, {0.0, 1.0, 0.0}) : cross(n, {1.0, 0.0, 0.0}));
      const Vec3 b0 = cross(n, t0);
      const double spin = 2.0 * kPi * rng.next(), cs = std::cos(spin), sn = std::sin(spin);
      Vec3 t, b;
      for (int i = 0; i < 3; ++i) {
        t[i] = cs * t0[i] + sn * b0[i];
        b[i] = -sn * t0[i] + cs * b0[i];
      }
      const double corner[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
      for (int q = 0; q < 4; ++q) {
        for (int i = 0; i < 3; ++i) {
          card.corners[3 * q + i] = float(centre[i] + half * (corner[q][0] * t[i] + corner[q][1] * b[i]));
        }
      }
      card.morton = 0;
      for (int i = 0; i < 3; ++i) {
        const double unit = (centre[i] - out.boxMin[i]) / (out.boxMax[i] - out.boxMin[i]);
        const uint64_t cell = std::min<uint64_t>(uint64_t(unit * 1048576.0), 1048575);
        for (int bit = 0; bit < 20; ++bit) card.morton |= ((cell >> bit) & 1) << (3 * bit + i);
      }
    }
    // In space-filling-curve order, as the triangles of an engine's (vertex-cache optimised) meshes are spatially
    // coherent. In random order lavapipe's BVH degrades: its shadow rays got slower in proportion to the count.
    std::sort(chunk.begin(), chunk.end(), [](const Card& a, const Card& b) { return a.morton < b.morton; });
    for (const Card& card : chunk) {
      const uint32_t base = out.vertexCount();
      out.positions.insert(out.positions.end(), std::begin(card.corners), std::end(card.corners));
      out.texcoords.insert(out.texcoords.end(), {0.0f, 0.0f, 1.0f, 0.0f, 1.0f, 1.0f, 0.0f, 1.0f});
      out.indices.insert(out.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
  }
  out.chunkFirstTriangle.push_back(out.triangleCount());
  return out;
}

LeafTexture makeLeafTexture() {
  LeafTexture tex;
  tex.rgba.resize(size_t(tex.width) * tex.height * 4);
  uint32_t open = 0;
  for (uint32_t y = 0; y < tex.height; ++y) {
    for (uint32_t x = 0; x < tex.width; ++x) {
      // An ellipse of semi-axes 0.5 and 0.32 covers pi * 0.16 = 50.3% of the card.
      const double u = (x + 0.5) / tex.width - 0.5, w = (y + 0.5) / tex.height - 0.5;
      const bool leaf = (u / 0.5) * (u / 0.5) + (w / 0.32) * (w / 0.32) < 1.0;
      uint8_t* p = &tex.rgba[(size_t(y) * tex.width + x) * 4];
      p[0] = 60;
      p[1] = 140;
      p[2] = 50;
      p[3] = leaf ? 255 : 0;
      open += leaf ? 0 : 1;
    }
  }
  tex.openFraction = double(open) / double(tex.width * tex.height);
  return tex;
}

float halfToFloat(uint16_t h) {
  const uint32_t sign = (h >> 15) & 1, exponent = (h >> 10) & 31, mantissa = h & 1023;
  float v;
  if (exponent == 0) {
    v = std::ldexp(float(mantissa), -24);
  } else if (exponent == 31) {
    v = mantissa ? NAN : INFINITY;
  } else {
    v = std::ldexp(float(mantissa | 1024), int(exponent) - 25);
  }
  return sign ? -v : v;
}

}  // namespace rbbench
