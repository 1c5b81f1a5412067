// The alpha scenario's scene on the CPU: a canopy of leaf cards (textured quads cut out by a leaf-shaped alpha
// texture) over a ground plane, split into interleaved chunks, and the analytic G-buffer of a camera under the
// canopy looking down at the ground (so every pixel is ground, at a depth known in closed form).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace rbbench {

// Where the leaves are and how the ground is seen: the camera sits under the canopy, so primary rays never
// reach a card and the G-buffer is the ground alone; shadow rays towards the sun cross the canopy.
struct FoliageView {
  uint32_t width = 0, height = 0;
  std::array<double, 3> eye = {0.0, 2.0, 0.0};
  double pitchDownDegrees = 65.0;  // below the horizon, looking towards -z
  double fovYDegrees = 60.0;
  float nearPlane = 0.05f, farPlane = 100.0f;
  std::array<double, 3> toSun = {0.344, 0.819, -0.459};  // about 55 degrees above the horizon
  double canopyBottom = 3.0, canopyTop = 9.0;            // heights of the leaf layer (above the eye)
};

// Hardware depth (Standard convention, D32) and world normals of the ground as the camera sees it.
struct AnalyticGBuffer {
  float view[16] = {};        // column-major, camera-relative (rotation only)
  float projection[16] = {};  // column-major, Vulkan clip space (+Y down), depth 0..1
  std::vector<float> depth;   // width * height
  std::vector<float> normal;  // 4 floats per pixel: (0, 1, 0, 0)
  // The ground seen, in XZ: its bounding box (every pixel's ground point lies in it).
  double groundMin[2] = {0.0, 0.0}, groundMax[2] = {0.0, 0.0};
};
AnalyticGBuffer makeGroundGBuffer(const FoliageView& view);

// All cards in one vertex, texcoord and index stream, chunk after chunk: chunk c is triangles
// [chunkFirstTriangle[c], chunkFirstTriangle[c + 1]). Each chunk's cards are spread over the whole canopy, so a
// fraction of the chunks is the same fraction of the cards any ray meets.
struct FoliageCards {
  std::vector<float> positions;              // xyz per vertex, 4 vertices per card
  std::vector<float> texcoords;              // uv per vertex: (0, 0), (1, 0), (1, 1), (0, 1)
  std::vector<uint32_t> indices;             // 2 triangles per card, global vertex indices
  std::vector<uint32_t> chunkFirstTriangle;  // chunks + 1 entries
  double cardSide = 0.0;                     // metres
  double boxMin[3] = {0, 0, 0}, boxMax[3] = {0, 0, 0};
  uint32_t vertexCount() const { return uint32_t(positions.size() / 3); }
  uint32_t triangleCount() const { return uint32_t(indices.size() / 3); }
};

// `cards` randomly placed and oriented square cards in a box over the G-buffer's ground that holds every
// shadow ray's path through the canopy (2 m margin), sized so that a ray crosses `meanCardsCrossed` cards on
// average (as if they were opaque), whatever the card count. Deterministic.
FoliageCards makeFoliageCards(const FoliageView& view, const AnalyticGBuffer& gbuffer, uint32_t cards, uint32_t chunks,
                              double meanCardsCrossed);

// RGBA8 leaf texture: an ellipse of alpha 255 on alpha 0 (about half the texels open).
struct LeafTexture {
  uint32_t width = 64, height = 64;
  std::vector<uint8_t> rgba;
  double openFraction = 0.0;  // texels with alpha < 128: cut out by a 0.5 cutoff
};
LeafTexture makeLeafTexture();

// IEEE half (R16_SFLOAT) to float.
float halfToFloat(uint16_t h);

}  // namespace rbbench
