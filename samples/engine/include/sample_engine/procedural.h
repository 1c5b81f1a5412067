// Procedural meshes with exactly known triangle counts (tests and benchmarks rely on them), generated
// textures, and the default demo scene built from them.
#pragma once

#include <cstdint>

#include "sample_engine/scene.h"

namespace sample_engine {

// XZ plane centred at the origin, normal +Y: 2 * segmentsX * segmentsZ triangles.
MeshData makePlane(float sizeX, float sizeZ, uint32_t segmentsX, uint32_t segmentsZ);
uint32_t planeTriangleCount(uint32_t segmentsX, uint32_t segmentsZ);

// Axis-aligned box centred at the origin, each face split in segments x segments quads:
// 12 * segments^2 triangles. Faces have their own vertices (hard edges).
MeshData makeBox(const glm::vec3& size, uint32_t segments = 1);
uint32_t boxTriangleCount(uint32_t segments);

// UV sphere centred at the origin: 2 * slices * (stacks - 1) triangles (one triangle per slice at each pole).
MeshData makeSphere(float radius, uint32_t slices, uint32_t stacks);
uint32_t sphereTriangleCount(uint32_t slices, uint32_t stacks);

// Cylinder along +Y from y = 0 to y = height: 2 * slices * heightSegments side triangles, plus
// slices triangles per cap when capped.
MeshData makeCylinder(float radius, float height, uint32_t slices, uint32_t heightSegments, bool capped);
uint32_t cylinderTriangleCount(uint32_t slices, uint32_t heightSegments, bool capped);

// Torus segment (an arch) in the XY plane, centred at the origin, sweeping `arcRadians` from +X counter-
// clockwise (pi gives a half ring standing on y = 0 from x = +majorRadius to x = -majorRadius). Tube ends
// are open: 2 * arcSegments * tubeSegments triangles.
MeshData makeArch(float majorRadius, float minorRadius, float arcRadians, uint32_t arcSegments, uint32_t tubeSegments);
uint32_t archTriangleCount(uint32_t arcSegments, uint32_t tubeSegments);

// The share of texels makeLeafTexture() leaves open (alpha below 0.5) by default: enough holes for a dappled
// shadow, enough leaves to read as a canopy.
constexpr float kDefaultLeafOpenFraction = 0.4f;

// A tileable RGBA8 texture of overlapping leaves and a few stems for alpha-tested cards (AlphaMode::Mask with
// the glTF cutoff 0.5, double-sided): RGB is the base colour (sRGB, varied greens with a darker midrib), alpha
// the coverage: 1 inside a leaf, 0 in the holes, a ramp about 1.5 texels wide along the leaf edges (soft
// edges under filtering). Leaves are added until at most `openFraction` of the texels (clamped to
// [0.05, 0.95]) have alpha < 0.5, so the open share ends within one leaf's area below it. Open texels carry
// the mean leaf colour, so filtering and mip-mapping do not darken the edges. Leaves wrap around the borders:
// the texture repeats without a seam. `size` (width = height) is clamped to [16, 4096]. Deterministic: the
// same arguments give the same bytes on every call; another seed gives another layout.
TextureData makeLeafTexture(uint32_t size, uint32_t seed, float openFraction = kDefaultLeafOpenFraction);

// Ground plane with a checker texture, six columns, two arches, spheres and boxes with varied materials:
// a low-roughness gold sphere, a mirror box and a mirror floor patch among them. Left of the colonnade stands
// a wooden pergola under a leaf canopy (alpha-tested cards textured by makeLeafTexture(), AlphaMode::Mask),
// whose dappled shadow falls on the ground in the camera's view. Five coloured KHR lights (Scene::lights: a
// lantern under the pergola, a spot under each arch, two small glows) light the shade modestly. Has a camera
// and a sun.
Scene makeDefaultDemoScene();

}  // namespace sample_engine
