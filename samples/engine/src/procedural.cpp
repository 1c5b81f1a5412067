// Procedural meshes and textures. Every mesh generator emits outward-facing counter-clockwise triangles,
// per-vertex normals, UVs and tangents, and exactly the triangle count its *TriangleCount() function promises.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "sample_engine/procedural.h"

namespace sample_engine {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

struct Builder {
  MeshData mesh;
  uint32_t add(const glm::vec3& p, const glm::vec3& n, const glm::vec2& uv, const glm::vec3& tangent) {
    mesh.positions.push_back(p);
    mesh.normals.push_back(n);
    mesh.uvs.push_back(uv);
    mesh.tangents.emplace_back(tangent, 1.0f);
    return static_cast<uint32_t>(mesh.positions.size() - 1);
  }
  void tri(uint32_t a, uint32_t b, uint32_t c) { mesh.indices.insert(mesh.indices.end(), {a, b, c}); }
};

// Grid of (cols+1) x (rows+1) vertices starting at `first`, row-major; emits two triangles per cell with
// the (a, b, c), (b, d, c) pattern where a = (col, row), b = (col+1, row), c = (col, row+1).
void gridTriangles(Builder& b, uint32_t first, uint32_t cols, uint32_t rows) {
  for (uint32_t r = 0; r < rows; ++r)
    for (uint32_t c = 0; c < cols; ++c) {
      uint32_t a = first + r * (cols + 1) + c;
      uint32_t bb = a + 1, cc = a + cols + 1, d = cc + 1;
      b.tri(a, bb, cc);
      b.tri(bb, d, cc);
    }
}

// splitmix64: the same sequence on every platform and standard library (std's distributions are not).
struct Rng {
  uint64_t state;
  explicit Rng(uint64_t seed) : state(seed) {}
  uint64_t next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  float uniform() { return float(next() >> 40) * 0x1p-24f; }  // [0, 1)
  float range(float lo, float hi) { return lo + (hi - lo) * uniform(); }
};

constexpr uint32_t kMinLeafTextureSize = 16, kMaxLeafTextureSize = 4096;
constexpr float kMinOpenFraction = 0.05f, kMaxOpenFraction = 0.95f;
constexpr float kLeafEdgeTexels = 1.5f;  // width of the coverage ramp along an edge
// A leaf's half length as a share of the texture side, and its half width as a share of its half length.
constexpr float kLeafHalfLengthMin = 0.04f, kLeafHalfLengthMax = 0.07f;
constexpr float kLeafWidthMin = 0.36f, kLeafWidthMax = 0.5f;
constexpr uint32_t kMaxLeaves = 100000;  // ends the loop for any size and target
// sRGB base colours.
constexpr glm::vec3 kLeafDark{0.16f, 0.33f, 0.08f}, kLeafLight{0.46f, 0.63f, 0.2f}, kMidrib{0.6f, 0.66f, 0.32f};
constexpr glm::vec3 kStem{0.32f, 0.25f, 0.13f};

// Straight (not premultiplied) colour with coverage in w; each stroke goes over what is there. Coordinates wrap, so
// whatever is painted tiles.
struct LeafCanvas {
  int size;
  std::vector<glm::vec4> texels;
  size_t covered = 0;  // texels with coverage >= 0.5

  explicit LeafCanvas(int s) : size(s), texels(size_t(s) * size_t(s), glm::vec4(0.0f)) {}
  void paint(int x, int y, const glm::vec3& colour, float coverage) {
    if (coverage <= 0.0f) return;
    x = ((x % size) + size) % size;
    y = ((y % size) + size) % size;
    glm::vec4& t = texels[size_t(y) * size + x];
    const float a = coverage + t.w * (1.0f - coverage);
    const glm::vec3 rgb = (colour * coverage + glm::vec3(t) * t.w * (1.0f - coverage)) / a;
    covered += t.w < 0.5f && a >= 0.5f;
    t = glm::vec4(rgb, a);
  }
};

// Coverage of a signed distance (texels, positive inside) with the soft edge.
float edgeCoverage(float distance) { return std::clamp(0.5f + distance / kLeafEdgeTexels, 0.0f, 1.0f); }

// Per-texel brightness jitter in [0.94, 1.06].
float grain(int x, int y, uint32_t salt) {
  Rng r((uint64_t(uint32_t(x)) << 32 | uint32_t(y)) ^ (uint64_t(salt) * 0xD1B54A32D192ED03ull));
  return 0.94f + 0.12f * r.uniform();
}

// A stem crossing the whole tile: y = y0 + amplitude * sin(2 pi k x / size + phase) with whole k, so it
// closes on itself across the border; `vertical` swaps the axes.
void paintStem(LeafCanvas& c, Rng& rng) {
  const float size = float(c.size), halfWidth = std::max(0.75f, 0.004f * size);
  const float y0 = rng.range(0.0f, size), amplitude = rng.range(0.03f, 0.08f) * size;
  const float k = float(1 + int(rng.uniform() * 2.0f)), phase = rng.range(0.0f, 2.0f * kPi);
  const bool vertical = rng.uniform() < 0.5f;
  const int reach = int(std::ceil(halfWidth + kLeafEdgeTexels));
  for (int x = 0; x < c.size; ++x) {
    const float w = 2.0f * kPi * k / size, xc = float(x) + 0.5f;
    const float yc = y0 + amplitude * std::sin(w * xc + phase);
    const float slope = amplitude * w * std::cos(w * xc + phase);
    const float cosine = 1.0f / std::sqrt(1.0f + slope * slope);  // vertical offset -> distance to the curve
    for (int y = int(std::floor(yc)) - reach; y <= int(std::floor(yc)) + reach; ++y) {
      const float coverage = edgeCoverage(halfWidth - std::abs(float(y) + 0.5f - yc) * cosine);
      if (vertical) c.paint(y, x, kStem, coverage);
      else
        c.paint(x, y, kStem, coverage);
    }
  }
}

// A pointed leaf: along its axis u in [-1, 1] (stalk to tip) its half width is w (1 - u^2)(1 - u/4).
void paintLeaf(LeafCanvas& c, Rng& rng, uint32_t salt) {
  const float size = float(c.size);
  const float cx = rng.range(0.0f, size), cy = rng.range(0.0f, size), angle = rng.range(0.0f, 2.0f * kPi);
  const float halfLength = std::max(2.0f, rng.range(kLeafHalfLengthMin, kLeafHalfLengthMax) * size);
  const float halfWidth = halfLength * rng.range(kLeafWidthMin, kLeafWidthMax);
  glm::vec3 base = glm::mix(kLeafDark, kLeafLight, rng.uniform());
  base.r *= rng.range(0.8f, 1.2f);
  const glm::vec2 axis(std::cos(angle), std::sin(angle)), across(-axis.y, axis.x);
  const float midrib = std::max(0.5f, 0.06f * halfWidth);
  const int reach = int(std::ceil(halfLength + kLeafEdgeTexels));
  for (int y = int(cy) - reach; y <= int(cy) + reach; ++y)
    for (int x = int(cx) - reach; x <= int(cx) + reach; ++x) {
      const glm::vec2 p(float(x) + 0.5f - cx, float(y) + 0.5f - cy);
      const float u = glm::dot(p, axis) / halfLength, v = glm::dot(p, across);
      const float width = std::abs(u) < 1.0f ? halfWidth * (1.0f - u * u) * (1.0f - 0.25f * u) : 0.0f;
      const float coverage = edgeCoverage(std::min(width - std::abs(v), (1.0f - std::abs(u)) * halfLength));
      if (coverage <= 0.0f) continue;
      // One half of the blade a little brighter than the other (a folded leaf), brighter towards the tip.
      const float side = width > 0.0f ? std::clamp(v / width, -1.0f, 1.0f) : 0.0f;
      glm::vec3 colour = base * (0.9f + 0.12f * side) * (0.9f + 0.1f * u);
      if (std::abs(v) < midrib && u < 0.9f) colour = glm::mix(colour, kMidrib, 0.45f);
      c.paint(x, y, glm::clamp(colour * grain(x, y, salt), 0.0f, 1.0f), coverage);
    }
}

}  // namespace

TextureData makeLeafTexture(uint32_t size, uint32_t seed, float openFraction) {
  size = std::clamp(size, kMinLeafTextureSize, kMaxLeafTextureSize);
  openFraction = std::clamp(std::isfinite(openFraction) ? openFraction : kDefaultLeafOpenFraction, kMinOpenFraction,
                            kMaxOpenFraction);
  Rng rng(0x6C656166ull << 32 | seed);  // "leaf"
  LeafCanvas canvas{int(size)};
  const size_t texels = canvas.texels.size();
  const size_t open = size_t(double(openFraction) * double(texels));
  for (int i = 0; i < 3; ++i) paintStem(canvas, rng);
  for (uint32_t leaf = 0; texels - canvas.covered > open && leaf < kMaxLeaves; ++leaf)
    paintLeaf(canvas, rng, seed * 0x9E3779B9u + leaf);

  glm::dvec3 sum(0.0);
  for (const glm::vec4& t : canvas.texels)
    if (t.w >= 0.5f) sum += glm::dvec3(t);
  const glm::vec3 mean = canvas.covered ? glm::vec3(sum / double(canvas.covered)) : kLeafDark;
  TextureData out{.name = "leaves", .width = size, .height = size, .rgba8 = {}};
  out.rgba8.resize(texels * 4);
  auto byte = [](float v) { return uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); };
  for (size_t i = 0; i < texels; ++i) {
    const glm::vec4& t = canvas.texels[i];
    const glm::vec3 rgb = t.w > 0.0f ? glm::vec3(t) : mean;
    for (int c = 0; c < 3; ++c) out.rgba8[i * 4 + c] = byte(rgb[c]);
    out.rgba8[i * 4 + 3] = byte(t.w);
  }
  return out;
}

uint32_t planeTriangleCount(uint32_t sx, uint32_t sz) { return 2 * sx * sz; }
uint32_t boxTriangleCount(uint32_t s) { return 12 * s * s; }
uint32_t sphereTriangleCount(uint32_t slices, uint32_t stacks) { return 2 * slices * (stacks - 1); }
uint32_t cylinderTriangleCount(uint32_t slices, uint32_t h, bool capped) {
  return 2 * slices * h + (capped ? 2 * slices : 0);
}
uint32_t archTriangleCount(uint32_t a, uint32_t t) { return 2 * a * t; }

MeshData makePlane(float sizeX, float sizeZ, uint32_t segX, uint32_t segZ) {
  segX = std::max(segX, 1u);
  segZ = std::max(segZ, 1u);
  Builder b;
  b.mesh.name = "plane";
  // Rows run towards -Z so that (col+1, row) x (col, row+1) winds counter-clockwise seen from +Y.
  for (uint32_t r = 0; r <= segZ; ++r)
    for (uint32_t c = 0; c <= segX; ++c) {
      float u = float(c) / segX, v = float(r) / segZ;
      b.add({(u - 0.5f) * sizeX, 0.0f, (0.5f - v) * sizeZ}, {0, 1, 0}, {u, 1.0f - v}, {1, 0, 0});
    }
  gridTriangles(b, 0, segX, segZ);
  return b.mesh;
}

MeshData makeBox(const glm::vec3& size, uint32_t segments) {
  segments = std::max(segments, 1u);
  struct Face {
    glm::vec3 n, u, v;
  };
  // cross(u, v) = n for every face, so the grid pattern winds outward.
  const Face faces[6] = {{{1, 0, 0}, {0, 0, -1}, {0, 1, 0}}, {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
                         {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}}, {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
                         {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},  {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}}};
  Builder b;
  b.mesh.name = "box";
  const glm::vec3 half = size * 0.5f;
  for (const Face& f : faces) {
    uint32_t first = static_cast<uint32_t>(b.mesh.positions.size());
    glm::vec3 center = f.n * half, extentU = f.u * half, extentV = f.v * half;
    for (uint32_t r = 0; r <= segments; ++r)
      for (uint32_t c = 0; c <= segments; ++c) {
        float s = float(c) / segments, t = float(r) / segments;
        glm::vec3 p = center + extentU * (2.0f * s - 1.0f) + extentV * (2.0f * t - 1.0f);
        b.add(p, f.n, {s, 1.0f - t}, f.u);
      }
    gridTriangles(b, first, segments, segments);
  }
  return b.mesh;
}

MeshData makeSphere(float radius, uint32_t slices, uint32_t stacks) {
  slices = std::max(slices, 3u);
  stacks = std::max(stacks, 2u);
  Builder b;
  b.mesh.name = "sphere";
  auto dir = [](float theta, float phi) {
    return glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
  };
  auto tangent = [](float phi) { return glm::vec3(-std::sin(phi), 0.0f, std::cos(phi)); };
  // One pole vertex per slice so each cap triangle gets its own UV.
  uint32_t topPole = 0;
  for (uint32_t i = 0; i < slices; ++i) {
    float phi = (i + 0.5f) / slices * 2.0f * kPi;
    b.add({0, radius, 0}, {0, 1, 0}, {(i + 0.5f) / slices, 0.0f}, tangent(phi));
  }
  uint32_t firstRing = static_cast<uint32_t>(b.mesh.positions.size());
  for (uint32_t j = 1; j < stacks; ++j)
    for (uint32_t i = 0; i <= slices; ++i) {
      float theta = float(j) / stacks * kPi, phi = float(i) / slices * 2.0f * kPi;
      glm::vec3 n = dir(theta, phi);
      b.add(n * radius, n, {float(i) / slices, float(j) / stacks}, tangent(phi));
    }
  uint32_t bottomPole = static_cast<uint32_t>(b.mesh.positions.size());
  for (uint32_t i = 0; i < slices; ++i) {
    float phi = (i + 0.5f) / slices * 2.0f * kPi;
    b.add({0, -radius, 0}, {0, -1, 0}, {(i + 0.5f) / slices, 1.0f}, tangent(phi));
  }
  auto ring = [&](uint32_t j, uint32_t i) { return firstRing + (j - 1) * (slices + 1) + i; };
  for (uint32_t i = 0; i < slices; ++i) b.tri(topPole + i, ring(1, i + 1), ring(1, i));
  for (uint32_t j = 1; j + 1 < stacks; ++j)
    for (uint32_t i = 0; i < slices; ++i) {
      uint32_t a = ring(j, i), bb = ring(j + 1, i), c = ring(j, i + 1), d = ring(j + 1, i + 1);
      b.tri(a, c, bb);
      b.tri(c, d, bb);
    }
  for (uint32_t i = 0; i < slices; ++i) b.tri(ring(stacks - 1, i), ring(stacks - 1, i + 1), bottomPole + i);
  return b.mesh;
}

MeshData makeCylinder(float radius, float height, uint32_t slices, uint32_t heightSegments, bool capped) {
  slices = std::max(slices, 3u);
  heightSegments = std::max(heightSegments, 1u);
  Builder b;
  b.mesh.name = "cylinder";
  for (uint32_t h = 0; h <= heightSegments; ++h)
    for (uint32_t i = 0; i <= slices; ++i) {
      float phi = float(i) / slices * 2.0f * kPi, y = height * h / heightSegments;
      glm::vec3 n(std::cos(phi), 0.0f, -std::sin(phi));
      b.add({n.x * radius, y, n.z * radius}, n, {float(i) / slices, 1.0f - float(h) / heightSegments},
            {-std::sin(phi), 0.0f, -std::cos(phi)});
    }
  gridTriangles(b, 0, slices, heightSegments);
  if (capped) {
    for (int top = 1; top >= 0; --top) {
      float y = top ? height : 0.0f;
      glm::vec3 n(0, top ? 1.0f : -1.0f, 0);
      uint32_t center = b.add({0, y, 0}, n, {0.5f, 0.5f}, {1, 0, 0});
      for (uint32_t i = 0; i <= slices; ++i) {
        float phi = float(i) / slices * 2.0f * kPi;
        glm::vec2 d(std::cos(phi), -std::sin(phi));
        b.add({d.x * radius, y, d.y * radius}, n, {0.5f + 0.5f * d.x, 0.5f + 0.5f * d.y}, {1, 0, 0});
      }
      for (uint32_t i = 0; i < slices; ++i) {
        if (top) b.tri(center, center + 1 + i, center + 2 + i);
        else
          b.tri(center, center + 2 + i, center + 1 + i);
      }
    }
  }
  return b.mesh;
}

MeshData makeArch(float majorRadius, float minorRadius, float arcRadians, uint32_t arcSegments, uint32_t tubeSegments) {
  arcSegments = std::max(arcSegments, 1u);
  tubeSegments = std::max(tubeSegments, 3u);
  Builder b;
  b.mesh.name = "arch";
  // Rows are tube angles, columns are arc angles: (a, b=next arc step, c=next tube step) winds outward.
  for (uint32_t t = 0; t <= tubeSegments; ++t)
    for (uint32_t a = 0; a <= arcSegments; ++a) {
      float alpha = arcRadians * a / arcSegments, beta = 2.0f * kPi * t / tubeSegments;
      glm::vec3 radial(std::cos(alpha), std::sin(alpha), 0.0f);
      glm::vec3 n = radial * std::cos(beta) + glm::vec3(0, 0, 1) * std::sin(beta);
      b.add(radial * majorRadius + n * minorRadius, n, {float(a) / arcSegments, float(t) / tubeSegments},
            {-std::sin(alpha), std::cos(alpha), 0.0f});
    }
  gridTriangles(b, 0, arcSegments, tubeSegments);
  return b.mesh;
}

}  // namespace sample_engine
