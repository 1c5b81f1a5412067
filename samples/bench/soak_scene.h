// The soak scenario's engine side, made once before the soak so the soak itself allocates no engine memory: static
// mesh variants (opaque solids and alpha-tested leaf cards), deforming cloth variants and the vertex buffers the
// deforming meshes live in (rewritten every frame through per-frame-slot staging), G-buffers of the ground at
// several resolutions, the leaf texture and two material sets.
//
// Thread safety: what takes a BenchEnv submits to its queue; use it from the thread that drives the BenchEnv.
#pragma once

#include <raybridge/raybridge.h>

#include <span>
#include <string>
#include <utility>
#include <vector>

#include "bench_env.h"
#include "bench_images.h"
#include "foliage_scene.h"

namespace rbbench {

struct SoakSizes {
  std::vector<std::pair<uint32_t, uint32_t>> resolutions;  // the G-buffers the soak switches between
  std::vector<uint32_t> sphereSlices;                      // static UV spheres (stacks = slices / 2)
  std::vector<uint32_t> boxCells;                          // static boxes
  std::vector<uint32_t> bumpCells;                         // static bumpy tiles
  std::vector<uint32_t> cardCells;                         // static non-opaque leaf cards
  std::vector<uint32_t> clothCells;                        // deforming cloth variants (a resize switches them)
  uint32_t crowdCells = 0;                                 // the shared (MeshDesc::contentKey) deforming meshes
  uint32_t dynamicSlots = 0;                               // deforming meshes registered at once, at most
  uint32_t crowdKeys = 0;                                  // contentKeys of shared deforming meshes
  uint32_t maxStaticMeshes = 0;                            // static registrations alive at once, at most
  uint32_t maxInstances = 0;                               // TLAS instances, at most
  // Scales the rates of the operations that create passes or denoisers (effect toggles, presets, settings, light
  // changes): lavapipe compiles their pipelines on the CPU, 5-40 s each on two shared cores, and often compiles a
  // re-created pass's pipeline again; a GPU takes milliseconds.
  double effectChurn = 1.0;
};
// --quick, or a CPU device without --full: tiny meshes and images. Else the GPU sizes.
SoakSizes pickSoakSizes(const BenchOptions& options, bool isCpu);

struct SoakStaticVariant {
  std::string name;
  UploadedMesh mesh;
  rb::HeadlessBuffer normals;
  rb::HeadlessBuffer texcoords;  // leaf cards only
  bool nonOpaque = false;
  uint32_t material = 0;  // index into the material sets
  rb::MeshDesc desc;      // buffers and attributes (debugName left to the caller)
};

struct SoakClothVariant {
  uint32_t cells = 0;
  std::vector<float> rest;  // xyz per vertex: a unit grid in XZ
  rb::HeadlessBuffer indices;
  uint32_t vertexCount = 0;
  uint32_t triangleCount = 0;
};

struct SoakGBuffer {
  SampledImage depth, normal;  // D32 Standard depth; world normal with the roughness in .w
  rb::GBufferDesc desc;
};

// `g` (made by makeGroundGBuffer(view), roughness in the normal's w) uploaded as a G-buffer the passes read; `what`
// names its images.
SoakGBuffer uploadGroundGBuffer(BenchEnv& env, const FoliageView& view, const AnalyticGBuffer& g,
                                const std::string& what);

// Targets of deformation: dynamicSlots cloth slots, then crowdKeys crowd meshes.
struct DeformRequest {
  uint32_t target = 0;
  const SoakClothVariant* variant = nullptr;
  float phase = 0.0f;
};

class SoakScene {
 public:
  SoakScene(BenchEnv& env, const SoakSizes& sizes);  // uploads everything; throws BenchFailure
  ~SoakScene();
  SoakScene(const SoakScene&) = delete;
  SoakScene& operator=(const SoakScene&) = delete;

  const std::vector<SoakStaticVariant>& staticVariants() const { return statics_; }
  const std::vector<SoakClothVariant>& clothVariants() const { return cloths_; }
  const SoakClothVariant& crowdVariant() const { return crowd_; }
  const std::vector<SoakGBuffer>& gbuffers() const { return gbuffers_; }
  const FoliageView& view() const { return view_; }
  // Where instances go: over the ground the camera sees, under the sun's shadow rays.
  const double* placementMin() const { return placeMin_; }
  const double* placementMax() const { return placeMax_; }

  // A deforming mesh in deform target `target` with the cloth variant's counts and indices.
  rb::MeshDesc dynamicDesc(uint32_t target, const SoakClothVariant& variant) const;
  // Writes each request's pose at time `t` into frame slot `frameSlot`'s staging and records the copies into the
  // targets, between barriers that order them after earlier frames' reads (BLAS builds and refits, the refit
  // measure, hit shading) and before this frame's.
  void recordDeform(VkCommandBuffer cmd, uint32_t frameSlot, std::span<const DeformRequest> requests, float t);

  // Material set 0 or 1 (the soak switches between them) and the texture views they index.
  std::span<const rb::Material> materials(uint32_t set) const { return materialSets_[set & 1]; }
  std::span<const VkImageView> textures() const { return textureViews_; }

 private:
  BenchEnv& env_;
  FoliageView view_;
  std::vector<SoakStaticVariant> statics_;
  std::vector<SoakClothVariant> cloths_;
  SoakClothVariant crowd_;
  std::vector<rb::HeadlessBuffer> targets_;  // device-local vertex buffers of the deforming meshes
  std::vector<rb::HeadlessBuffer> staging_;  // host-visible, one per frame slot, a region per target
  VkDeviceSize targetBytes_ = 0;             // bytes of the largest variant's vertices
  std::vector<SoakGBuffer> gbuffers_;
  SampledImage leaf_;
  std::vector<VkImageView> textureViews_;
  std::vector<rb::Material> materialSets_[2];
  double placeMin_[3] = {0, 0, 0}, placeMax_[3] = {0, 0, 0};
};

}  // namespace rbbench
