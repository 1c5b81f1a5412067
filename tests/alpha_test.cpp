// Alpha-tested geometry in the SDK's rays against ground truth: Embree hits filtered by the same cut-out rule on
// the test's own copy of the textures (nearest texel, wrapped, after the texture transform). A fence with
// cells of alpha 0, 0.4, 0.6 and 1 and a canopy with round holes (both MASK, cutoff 0.5) over a ground; the
// same scene all opaque runs no any-hit shader; two BLEND layers let through (1 - 0.3)(1 - 0.5) in the mean.
#include <catch2/catch_test_macros.hpp>

#include <glm/glm.hpp>

#include <cmath>
#include <cstring>
#include <random>

#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

struct AlphaTexture {
  uint32_t width = 0, height = 0;
  std::vector<uint8_t> rgba;
  // The GPU's rule (shaders/alpha_any_hit.glsl): the nearest texel of mip 0, wrapped.
  float alphaAt(glm::vec2 uv) const {
    glm::vec2 f = uv - glm::floor(uv);
    int x = std::clamp(int(std::floor(f.x * float(width))), 0, int(width) - 1);
    int y = std::clamp(int(std::floor(f.y * float(height))), 0, int(height) - 1);
    return float(rgba[(size_t(y) * width + x) * 4 + 3]) / 255.0f;
  }
};

// A scene whose meshes carry texture coordinates, with materials and textures.
struct AlphaScene {
  TestScene scene;                      // meshes, instances (instance material = index into `materials`)
  std::vector<std::vector<float>> uvs;  // per mesh, 2 floats per vertex; empty = none
  std::vector<bool> nonOpaque;          // per mesh
  std::vector<rb::Material> materials;
  std::vector<AlphaTexture> textures;
};

// A quad from `corner` spanned by `edgeU` and `edgeV`, with uv (0, 0) at the corner and (1, 1) opposite.
void addQuad(AlphaScene& s, glm::vec3 corner, glm::vec3 edgeU, glm::vec3 edgeV, bool nonOpaque) {
  rbsamples::CpuMesh m;
  glm::vec3 n = glm::normalize(glm::cross(edgeU, edgeV));
  const glm::vec3 p[4] = {corner, corner + edgeU, corner + edgeU + edgeV, corner + edgeV};
  for (const glm::vec3& v : p) {
    m.positions.insert(m.positions.end(), {v.x, v.y, v.z});
    m.normals.insert(m.normals.end(), {n.x, n.y, n.z});
  }
  m.indices = {0, 1, 2, 0, 2, 3};
  s.scene.meshes.push_back(m);
  s.uvs.push_back({0, 0, 1, 0, 1, 1, 0, 1});
  s.nonOpaque.push_back(nonOpaque);
}

void addGround(AlphaScene& s) {
  s.scene.meshes.push_back(rbsamples::makeGrid(30.0f, 4));
  s.uvs.push_back({});
  s.nonOpaque.push_back(false);
}

const glm::dvec3 kToSun = glm::normalize(glm::dvec3(0.3, 1.0, 0.4));

// Ground (instance 0, material 0), a fence (1) and a canopy (2), cut out by MASK unless `opaque`.
AlphaScene fenceAndCanopy(bool opaque) {
  AlphaScene s;
  addGround(s);
  addQuad(s, {-5.0f, 0.2f, -1.0f}, {4.0f, 0.0f, 0.0f}, {0.0f, 2.0f, 0.0f}, !opaque);
  addQuad(s, {1.0f, 3.0f, -3.0f}, {4.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 4.0f}, !opaque);
  const auto identity = translation(0, 0, 0);
  for (uint32_t i = 0; i < 3; ++i) s.scene.instances.push_back({i, identity, i});
  // The fence: 8x4 cells of alpha 0, 0.4, 0.6, 1 (0.5 m each).
  AlphaTexture fence{8, 4, {}};
  const uint8_t cells[4] = {0, 102, 153, 255};
  for (uint32_t y = 0; y < 4; ++y) {
    for (uint32_t x = 0; x < 8; ++x) fence.rgba.insert(fence.rgba.end(), {200, 180, 150, cells[(x + y) % 4]});
  }
  // The canopy: round holes in a 4x4 pattern of 16-texel cells.
  AlphaTexture canopy{64, 64, {}};
  for (uint32_t y = 0; y < 64; ++y) {
    for (uint32_t x = 0; x < 64; ++x) {
      float dx = float(x % 16) + 0.5f - 8.0f, dy = float(y % 16) + 0.5f - 8.0f;
      canopy.rgba.insert(canopy.rgba.end(), {40, 120, 40, uint8_t(dx * dx + dy * dy < 30.0f ? 0 : 255)});
    }
  }
  s.textures = {fence, canopy};
  rb::Material ground;
  rb::Material fenceMaterial;
  fenceMaterial.baseColorTexture = 0;
  fenceMaterial.alphaMode = opaque ? rb::AlphaMode::Opaque : rb::AlphaMode::Mask;  // cutoff 0 = 0.5
  rb::Material canopyMaterial;
  canopyMaterial.baseColorTexture = 1;
  canopyMaterial.alphaMode = fenceMaterial.alphaMode;
  const float transform[6] = {1.5f, 0.0f, 0.25f, 0.0f, 1.5f, 0.1f};  // tiles 1.5 times: exercises the wrap
  std::copy(std::begin(transform), std::end(transform), canopyMaterial.textureTransform);
  s.materials = {ground, fenceMaterial, canopyMaterial};
  return s;
}

// Whether a reference hit stops the ray, by the material of its instance (shaders/alpha_any_hit.glsl's rule;
// BLEND is stochastic on the GPU and has no deterministic reference).
HitFilter alphaFilter(const AlphaScene& s) {
  return [&s](const ReferenceHit& h) {
    const SceneInstance& inst = s.scene.instances[h.instanceId];
    const rb::Material& m = s.materials[inst.material];
    if (m.alphaMode != rb::AlphaMode::Mask) return true;
    float alpha = m.baseColor[3];
    if (m.baseColorTexture != rb::kNoTexture) {
      const rbsamples::CpuMesh& mesh = s.scene.meshes[inst.mesh];
      const std::vector<float>& uv = s.uvs[inst.mesh];
      glm::vec2 t(0.0f);
      const float w[3] = {1.0f - h.barycentrics[0] - h.barycentrics[1], h.barycentrics[0], h.barycentrics[1]};
      for (int k = 0; k < 3; ++k) {
        uint32_t v = mesh.indices[3 * h.primitiveId + k];
        t += w[k] * glm::vec2(uv[2 * v], uv[2 * v + 1]);
      }
      const float* x = m.textureTransform;
      bool identity = std::all_of(x, x + 6, [](float f) { return f == 0.0f; });
      if (!identity) t = glm::vec2(x[0] * t.x + x[1] * t.y + x[2], x[3] * t.x + x[4] * t.y + x[5]);
      alpha *= s.textures[m.baseColorTexture].alphaAt(t);
    }
    return alpha >= (m.alphaCutoff == 0.0f ? rb::kDefaultAlphaCutoff : m.alphaCutoff);
  };
}

// The G-buffer is the ground alone, as the engine's rasterizer sees it through the cut-outs and under
// blended surfaces (drawn in a forward pass).
CpuGBuffer groundGBuffer(const SyntheticView& view) {
  AlphaScene groundOnly;
  addGround(groundOnly);
  groundOnly.scene.instances.push_back({0, translation(0, 0, 0), 0});
  EmbreeScene embree;
  addToEmbree(embree, groundOnly.scene);
  return traceGBuffer(embree, view);
}

SyntheticView alphaView() {
  SyntheticView view;
  view.eye = {0.0, 9.0, 5.0};
  view.target = {0.0, 0.0, -2.0};
  view.fovYDegrees = 40.0;
  view.width = 160;
  view.height = 120;
  return view;
}

// One GPU image for each texture: RGBA8 UNORM, sampled, in SHADER_READ_ONLY_OPTIMAL.
struct UploadedTextures {
  GpuFixture& fx;
  std::vector<SampledImage> images;
  std::vector<VkImageView> views;
  UploadedTextures(GpuFixture& f, const std::vector<AlphaTexture>& textures) : fx(f) {
    for (const AlphaTexture& t : textures) {
      images.push_back(uploadSampledImage(fx, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_ASPECT_COLOR_BIT, t.width, t.height,
                                          t.rgba.data(), t.rgba.size()));
      views.push_back(images.back().view);
    }
  }
  ~UploadedTextures() {
    for (SampledImage& image : images) destroySampledImage(fx, image);
  }
};

// `frames` frames of passes over the scene on the ground G-buffer: meshes registered with their texture
// coordinates and opacity, a camera-relative TLAS with shading records, the scene's MaterialTable. `record`
// runs inside each frame, `readback` after it.
using FrameRecorder =
    std::function<void(VkCommandBuffer, const rb::GBufferDesc&, const rb::TlasInfo&, const rb::MaterialTable&)>;
// With `frontEnd`, each frame records an rb::HybridEffects given the service, the instances and the scene's
// materials instead (it builds the TLAS itself); `record` is not called then.
struct FrontEndRun {
  rb::HybridEffects* effects = nullptr;  // created by runAlphaFrames on the scene's service
  rb::HybridEffectsDesc desc;
  rb::Light light;
};
void runAlphaFrames(GpuFixture& fx, const AlphaScene& s, const CpuGBuffer& cpu, uint32_t frames,
                    const FrameRecorder& record, const PassReadback& readback, uint32_t* nonOpaqueInstances = nullptr,
                    uint32_t* nonOpaqueMeshes = nullptr, FrontEndRun* frontEnd = nullptr) {
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  std::vector<UploadedMesh> uploads;
  std::vector<rb::HeadlessBuffer> texcoords;
  std::vector<rb::Instance> instances;
  std::vector<rb::MeshHandle> handles;
  for (size_t i = 0; i < s.scene.meshes.size(); ++i) {
    uploads.push_back(fx.upload(s.scene.meshes[i]));
    rb::MeshDesc desc = uploads.back().desc;
    desc.nonOpaque = s.nonOpaque[i];
    if (!s.uvs[i].empty()) {
      auto b = fx.device().createBuffer(s.uvs[i].size() * sizeof(float),
                                        VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                        false, s.uvs[i].data());
      RB_REQUIRE_OK(b);
      texcoords.push_back(b.value());
      desc.texcoordAddress = b->address;
    }
    auto h = service.value()->registerMesh(desc);
    RB_REQUIRE_OK(h);
    handles.push_back(h.value());
  }
  for (uint32_t i = 0; i < s.scene.instances.size(); ++i) {
    rb::Instance inst;
    inst.mesh = handles[s.scene.instances[i].mesh];
    std::copy(s.scene.instances[i].transform.begin(), s.scene.instances[i].transform.end(), inst.transform);
    inst.customIndex = i;
    inst.material = s.scene.instances[i].material;
    instances.push_back(inst);
  }
  if (nonOpaqueMeshes) *nonOpaqueMeshes = service.value()->stats().nonOpaqueMeshes;
  {
    UploadedTextures textures(fx, s.textures);
    auto table = rb::MaterialTable::create(fx.ctx());
    RB_REQUIRE_OK(table);
    RB_REQUIRE_OK(table.value()->setMaterials(s.materials, textures.views));
    GpuGBuffer gbuffer(fx, cpu);
    rb::GBufferDesc desc = gbuffer.desc();
    std::unique_ptr<rb::HybridEffects> effects;
    if (frontEnd) {
      auto created = rb::HybridEffects::create(fx.ctx(), service.value().get(), frontEnd->desc);
      RB_REQUIRE_OK(created);
      effects = std::move(created.value());
      RB_REQUIRE_OK(effects->setMaterials(s.materials, textures.views));
      frontEnd->effects = effects.get();
    }
    for (uint32_t f = 0; f < frames; ++f) {
      if (effects) {
        fx.runFrame([&](VkCommandBuffer cmd) {
          rb::HybridFrame frame;
          frame.gbuffer = desc;
          frame.instances = instances;
          frame.light = frontEnd->light;
          RB_REQUIRE_OK(effects->record(cmd, frame));
          if (nonOpaqueInstances) *nonOpaqueInstances = effects->lastTlas().nonOpaqueInstances;
        });
        readback(desc);
        continue;
      }
      fx.runFrame([&](VkCommandBuffer cmd) {
        RB_REQUIRE_OK(service.value()->recordPendingWork(cmd));
        auto tlas = service.value()->recordTlasBuild(cmd, instances, gbuffer.cameraRelativeTlas(true));
        RB_REQUIRE_OK(tlas);
        REQUIRE(tlas->skippedInstances == 0);
        if (nonOpaqueInstances) *nonOpaqueInstances = tlas->nonOpaqueInstances;
        record(cmd, desc, tlas.value(), *table.value());
      });
      readback(desc);
    }
    for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
    (void)fx.device().waitIdle();
    if (frontEnd) frontEnd->effects = nullptr;
  }
  for (UploadedMesh& m : uploads) fx.destroy(m);
  for (rb::HeadlessBuffer& b : texcoords) fx.device().destroyBuffer(b);
}

struct ShadowResult {
  std::vector<float> visibility;
  rb::PassStats stats;
  uint32_t nonOpaqueInstances = 0, nonOpaqueMeshes = 0;
};

ShadowResult runShadows(GpuFixture& fx, const AlphaScene& s, const CpuGBuffer& cpu, glm::dvec3 toSun,
                        uint32_t frames = 1, std::vector<double>* accumulated = nullptr) {
  auto pass = rb::ShadowPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  rb::Light light;
  light.direction[0] = float(toSun.x);
  light.direction[1] = float(toSun.y);
  light.direction[2] = float(toSun.z);
  ShadowResult out;
  if (accumulated) accumulated->assign(cpu.hit.size(), 0.0);
  runAlphaFrames(
      fx, s, cpu, frames,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas, const rb::MaterialTable& m) {
        rb::ShadowSettings settings;
        settings.materials = &m;
        RB_REQUIRE_OK(pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .light = light, .settings = settings}));
      },
      [&](const rb::GBufferDesc& desc) {
        out.visibility = readR16f(fx, pass.value()->outputs().visibility, desc.width, desc.height);
        if (accumulated) {
          for (size_t i = 0; i < out.visibility.size(); ++i) (*accumulated)[i] += out.visibility[i];
        }
      },
      &out.nonOpaqueInstances, &out.nonOpaqueMeshes);
  out.stats = pass.value()->stats();
  return out;
}

// 1 = lit, 0 = shadowed, for the ground pixels of the G-buffer.
std::vector<int> referenceShadow(const EmbreeScene& embree, const CpuGBuffer& g, glm::dvec3 toLight,
                                 const HitFilter& stops) {
  std::vector<int> vis(g.hit.size(), -1);
  for (size_t i = 0; i < g.hit.size(); ++i) {
    if (!g.hit[i]) continue;
    glm::dvec3 n(g.normal[i]);
    glm::dvec3 o = g.position[i] + n * 1e-4;
    float of[3] = {float(o.x), float(o.y), float(o.z)}, d[3] = {float(toLight.x), float(toLight.y), float(toLight.z)};
    vis[i] = embree.intersect(of, d, 0.0f, 1e30f, stops).hit ? 0 : 1;
  }
  return vis;
}

// Pixels whose 3x3 neighbourhood has the same reference value (shadow edges are where rasterisation of the
// cut-outs' borders may differ by a texel's rounding).
bool awayFromEdges(const std::vector<int>& ref, int x, int y, int w, int h) {
  size_t i = size_t(y) * w + x;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      int nx = std::clamp(x + dx, 0, w - 1), ny = std::clamp(y + dy, 0, h - 1);
      if (ref[size_t(ny) * w + nx] != ref[i]) return false;
    }
  }
  return true;
}

}  // namespace

TEST_CASE("shadows through MASK cut-outs match Embree passing through texels under the cutoff",
          "[alpha][shadow][embree]") {
  GpuFixture fx;
  AlphaScene s = fenceAndCanopy(false);
  EmbreeScene embree;
  addToEmbree(embree, s.scene);
  const SyntheticView view = alphaView();
  CpuGBuffer cpu = groundGBuffer(view);
  ShadowResult run = runShadows(fx, s, cpu, kToSun);
  std::vector<int> ref = referenceShadow(embree, cpu, kToSun, alphaFilter(s));
  std::vector<int> solid = referenceShadow(embree, cpu, kToSun, [](const ReferenceHit&) { return true; });
  const int W = int(view.width), H = int(view.height);
  uint32_t compared = 0, agree = 0, throughHoles = 0, shadowed = 0;
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      size_t i = size_t(y) * W + x;
      if (ref[i] < 0 || !awayFromEdges(ref, x, y, W, H)) continue;
      ++compared;
      agree += (run.visibility[i] > 0.5f) == (ref[i] == 1);
      throughHoles += ref[i] == 1 && solid[i] == 0;
      shadowed += ref[i] == 0;
    }
  }
  INFO("compared " << compared << ", agree " << agree << ", lit through cut-outs " << throughHoles << ", shadowed "
                   << shadowed);
  REQUIRE(compared > uint32_t(W * H / 2));
  REQUIRE(throughHoles > 200);  // the cut-outs matter: solid quads would shadow these pixels
  REQUIRE(shadowed > 200);
  CHECK(double(agree) / compared >= 0.995);
  CHECK(run.nonOpaqueInstances == 2);
  CHECK(run.nonOpaqueMeshes == 2);
  CHECK(run.stats.anyHitInvocations > 0);
}

TEST_CASE("an all-opaque scene runs no any-hit shader and casts solid shadows", "[alpha][shadow][counter]") {
  GpuFixture fx;
  AlphaScene s = fenceAndCanopy(true);
  EmbreeScene embree;
  addToEmbree(embree, s.scene);
  const SyntheticView view = alphaView();
  CpuGBuffer cpu = groundGBuffer(view);
  ShadowResult run = runShadows(fx, s, cpu, kToSun);
  std::vector<int> ref = referenceShadow(embree, cpu, kToSun, alphaFilter(s));
  const int W = int(view.width), H = int(view.height);
  uint32_t compared = 0, agree = 0;
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      size_t i = size_t(y) * W + x;
      if (ref[i] < 0 || !awayFromEdges(ref, x, y, W, H)) continue;
      ++compared;
      agree += (run.visibility[i] > 0.5f) == (ref[i] == 1);
    }
  }
  CHECK(double(agree) / compared >= 0.995);
  CHECK(run.nonOpaqueInstances == 0);
  CHECK(run.stats.rays > 0);
  CHECK(run.stats.anyHitInvocations == 0);
}

TEST_CASE("AO through MASK cut-outs matches Embree's filtered AO", "[alpha][ao][embree]") {
  GpuFixture fx;
  AlphaScene s = fenceAndCanopy(false);
  EmbreeScene embree;
  addToEmbree(embree, s.scene);
  SyntheticView view = alphaView();
  view.width = 64;
  view.height = 48;
  CpuGBuffer cpu = groundGBuffer(view);
  const float range = 4.0f;
  auto pass = rb::AoPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  std::vector<float> ao;
  runAlphaFrames(
      fx, s, cpu, 1,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas, const rb::MaterialTable& m) {
        rb::AoSettings settings;
        settings.raysPerPixel = 512;
        settings.range = range;
        settings.materials = &m;
        RB_REQUIRE_OK(pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = settings}));
      },
      [&](const rb::GBufferDesc& desc) { ao = readR16f(fx, pass.value()->outputs().ao, desc.width, desc.height); });
  // Embree: cosine-weighted directions around the normal, binary within range, through the cut-outs.
  auto referenceAo = [&](const HitFilter& stops) {
    std::vector<double> out(cpu.hit.size(), 1.0);
    std::mt19937 rng(99);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (size_t i = 0; i < cpu.hit.size(); ++i) {
      if (!cpu.hit[i]) continue;
      glm::dvec3 n(cpu.normal[i]);
      glm::dvec3 t = glm::normalize(std::fabs(n.x) > 0.5 ? glm::cross(n, glm::dvec3(0, 1, 0))
                                                         : glm::cross(n, glm::dvec3(1, 0, 0)));
      glm::dvec3 b = glm::cross(n, t);
      glm::dvec3 o = cpu.position[i] + n * 1e-4;
      float of[3] = {float(o.x), float(o.y), float(o.z)};
      uint32_t open = 0;
      const uint32_t rays = 1024;
      for (uint32_t k = 0; k < rays; ++k) {
        double r = std::sqrt(u(rng)), phi = 2.0 * M_PI * u(rng);
        glm::dvec3 d = r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.0, 1.0 - r * r)) * n;
        float df[3] = {float(d.x), float(d.y), float(d.z)};
        open += embree.intersect(of, df, 0.0f, range, stops).hit ? 0 : 1;
      }
      out[i] = double(open) / rays;
    }
    return out;
  };
  std::vector<double> ref = referenceAo(alphaFilter(s));
  std::vector<double> solid = referenceAo([](const ReferenceHit&) { return true; });
  double se = 0.0, seSolid = 0.0, refDifference = 0.0;
  uint32_t n = 0;
  for (size_t i = 0; i < cpu.hit.size(); ++i) {
    if (!cpu.hit[i]) continue;
    se += (ao[i] - ref[i]) * (ao[i] - ref[i]);
    seSolid += (ao[i] - solid[i]) * (ao[i] - solid[i]);
    refDifference += std::fabs(ref[i] - solid[i]);
    ++n;
  }
  REQUIRE(n > 1000);
  double rmse = std::sqrt(se / n), rmseSolid = std::sqrt(seSolid / n);
  INFO("rmse " << rmse << " (against solid quads " << rmseSolid << "), mean |cut-out - solid| " << refDifference / n);
  CHECK(rmse <= 0.03);
  CHECK(refDifference / n > 0.01);  // the cut-outs change AO visibly
  CHECK(rmse < rmseSolid);
  CHECK(pass.value()->stats().anyHitInvocations > 0);
}

namespace {

// The primary ray through each pixel of `view`, as PrimaryRayPass traces it.
rb::PrimaryRayCamera primaryCamera(const SyntheticView& view) {
  rb::PrimaryRayCamera c;
  for (int i = 0; i < 3; ++i) {
    c.eye[i] = float(view.eye[i]);
    c.target[i] = float(view.target[i]);
    c.upHint[i] = float(view.up[i]);
  }
  c.verticalFovDegrees = float(view.fovYDegrees);
  return c;
}

struct PrimaryResult {
  std::vector<float> t;            // hit distance, 0 = miss
  std::vector<uint32_t> instance;  // instance custom index (= scene instance), 0xFFFFFFFF = miss
  rb::PassStats stats;
};

// PrimaryRayPass over the scene's camera-relative TLAS, given the scene's material table.
PrimaryResult runPrimary(GpuFixture& fx, const AlphaScene& s, const SyntheticView& view) {
  auto pass = rb::PrimaryRayPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  const uint32_t w = view.width, h = view.height;
  rb::GpuImage dist = fx.makeImage(w, h, VK_FORMAT_R32_SFLOAT);
  rb::GpuImage ids = fx.makeImage(w, h, VK_FORMAT_R32G32_UINT);
  PrimaryResult out;
  runAlphaFrames(
      fx, s, groundGBuffer(view), 1,  // the pass reads no G-buffer; runAlphaFrames wants one
      [&](VkCommandBuffer cmd, const rb::GBufferDesc&, const rb::TlasInfo& tlas, const rb::MaterialTable& m) {
        fx.toGeneral(cmd, dist);
        fx.toGeneral(cmd, ids);
        rb::PrimaryRaySettings settings;
        settings.materials = &m;
        RB_REQUIRE_OK(pass.value()->record(cmd, {.tlas = tlas,
                                                 .camera = primaryCamera(view),
                                                 .targets = {dist.view, ids.view, w, h},
                                                 .settings = settings}));
      },
      [&](const rb::GBufferDesc&) {
        std::vector<uint8_t> d = fx.readImage(dist, 4), i = fx.readImage(ids, 8);
        out.t.resize(size_t(w) * h);
        std::memcpy(out.t.data(), d.data(), out.t.size() * sizeof(float));
        out.instance.resize(out.t.size());
        for (size_t k = 0; k < out.t.size(); ++k) std::memcpy(&out.instance[k], &i[8 * k + 4], sizeof(uint32_t));
      });
  out.stats = pass.value()->stats();
  fx.destroyImage(dist);
  fx.destroyImage(ids);
  return out;
}

// Embree's nearest hit per pixel that `stops` accepts: the instance (-1 = miss) and distance.
void referencePrimary(const EmbreeScene& embree, const SyntheticView& view, const HitFilter& stops,
                      std::vector<int>& instance, std::vector<float>& t) {
  auto basis = rb::computeCameraBasis(primaryCamera(view), view.width, view.height);
  RB_REQUIRE_OK(basis);
  instance.assign(size_t(view.width) * view.height, -1);
  t.assign(instance.size(), 0.0f);
  for (uint32_t y = 0; y < view.height; ++y) {
    for (uint32_t x = 0; x < view.width; ++x) {
      PixelRay r = rayThrough(basis.value(), float(x) + 0.5f, float(y) + 0.5f, view.width, view.height);
      ReferenceHit hit = embree.intersect(r.origin, r.dir, 0.0f, 1e30f, stops);
      size_t i = size_t(y) * view.width + x;
      if (hit.hit) instance[i] = int(hit.instanceId), t[i] = hit.t;
    }
  }
}

}  // namespace

TEST_CASE("primary rays through MASK cut-outs match Embree's depth; BLEND surfaces are invisible to them",
          "[alpha][primary][embree]") {
  GpuFixture fx;
  const SyntheticView view = alphaView();
  AlphaScene s = fenceAndCanopy(false);
  EmbreeScene embree;
  addToEmbree(embree, s.scene);
  std::vector<int> refInstance, solidInstance;
  std::vector<float> refT, solidT;
  referencePrimary(embree, view, alphaFilter(s), refInstance, refT);
  referencePrimary(
      embree, view, [](const ReferenceHit&) { return true; }, solidInstance, solidT);
  PrimaryResult gpu = runPrimary(fx, s, view);
  const int w = int(view.width), h = int(view.height);
  uint32_t compared = 0, agree = 0, cutOut = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!awayFromEdges(refInstance, x, y, w, h)) continue;
      size_t i = size_t(y) * w + x;
      ++compared;
      cutOut += refInstance[i] != solidInstance[i];
      bool gpuHit = gpu.instance[i] != 0xFFFFFFFFu, refHit = refInstance[i] >= 0;
      if (gpuHit != refHit) continue;
      if (!refHit || (int(gpu.instance[i]) == refInstance[i] && std::fabs(gpu.t[i] - refT[i]) <= 1e-4f * refT[i]))
        ++agree;
    }
  }
  INFO("compared " << compared << " pixels, agree " << agree << ", seen through cut-outs " << cutOut);
  REQUIRE(compared > uint32_t(w * h / 2));
  CHECK(double(agree) >= 0.995 * compared);
  CHECK(double(cutOut) > 0.02 * compared);  // the cut-outs change what primary rays see
  CHECK(gpu.stats.rays == uint64_t(w) * h);
  CHECK(gpu.stats.anyHitInvocations > 0);

  SECTION("the all-opaque scene takes the opaque fast path") {
    PrimaryResult opaque = runPrimary(fx, fenceAndCanopy(true), view);
    CHECK(opaque.stats.anyHitInvocations == 0);
    uint32_t same = 0;
    for (size_t i = 0; i < opaque.instance.size(); ++i)
      same += int(opaque.instance[i] == 0xFFFFFFFFu ? -1 : int(opaque.instance[i])) == solidInstance[i];
    CHECK(double(same) >= 0.995 * opaque.instance.size());
  }
  SECTION("a BLEND canopy is invisible to primary rays, as to the G-buffer") {
    AlphaScene blend = fenceAndCanopy(false);
    blend.materials[2].alphaMode = rb::AlphaMode::Blend;
    blend.materials[2].baseColor[3] = 0.9f;
    uint32_t canopyBefore = 0, canopyAfter = 0;
    for (uint32_t id : gpu.instance) canopyBefore += id == 2;
    for (uint32_t id : runPrimary(fx, blend, view).instance) canopyAfter += id == 2;
    CHECK(canopyBefore > 100);
    CHECK(canopyAfter == 0);
  }
}

TEST_CASE("stochastic shadows through two BLEND layers converge to the product of their transmittances",
          "[alpha][shadow][blend]") {
  GpuFixture fx;
  AlphaScene s;
  addGround(s);
  // Layer A (alpha 0.3) over x in [-4, 2], layer B (alpha 0.5) over x in [-1, 5], both z in [-4, 2].
  addQuad(s, {-4.0f, 3.0f, -4.0f}, {6.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 6.0f}, true);
  addQuad(s, {-1.0f, 4.0f, -4.0f}, {6.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 6.0f}, true);
  const auto identity = translation(0, 0, 0);
  for (uint32_t i = 0; i < 3; ++i) s.scene.instances.push_back({i, identity, i});
  rb::Material ground, a, b;
  a.alphaMode = b.alphaMode = rb::AlphaMode::Blend;
  a.baseColor[3] = 0.3f;
  b.baseColor[3] = 0.5f;
  s.materials = {ground, a, b};
  SyntheticView view = alphaView();
  view.width = 64;
  view.height = 48;
  CpuGBuffer cpu = groundGBuffer(view);
  const uint32_t frames = 64;
  std::vector<double> sum;
  const glm::dvec3 up(0.0, 1.0, 0.0);  // straight down: a ground point under x is under the layers over x
  ShadowResult run = runShadows(fx, s, cpu, up, frames, &sum);
  // Ground pixels under A alone, under both, under B alone (a margin from the layers' borders).
  double sumA = 0, sumAB = 0, sumB = 0;
  uint32_t nA = 0, nAB = 0, nB = 0;
  for (size_t i = 0; i < cpu.hit.size(); ++i) {
    if (!cpu.hit[i]) continue;
    glm::dvec3 p = cpu.position[i];
    if (p.z < -3.8 || p.z > 1.8) continue;
    double v = sum[i] / frames;
    if (p.x > -3.8 && p.x < -1.2) sumA += v, ++nA;
    if (p.x > -0.8 && p.x < 1.8) sumAB += v, ++nAB;
    if (p.x > 2.2 && p.x < 4.8) sumB += v, ++nB;
  }
  REQUIRE(nA > 100);
  REQUIRE(nAB > 100);
  REQUIRE(nB > 100);
  // Each pixel and frame is a Bernoulli trial of mean p (variance p(1 - p)), independent across pixels and
  // frames: the mean over n pixels and the frames has sigma sqrt(p(1 - p) / (n frames)). Allow 5 sigma.
  auto within = [&](double mean, uint32_t n, double p) {
    double sigma = std::sqrt(p * (1.0 - p) / (double(n) * frames));
    INFO("mean " << mean << " expected " << p << " sigma " << sigma << " over " << n << " pixels");
    CHECK(std::fabs(mean - p) <= 5.0 * sigma);
  };
  within(sumA / nA, nA, 0.7);
  within(sumAB / nAB, nAB, 0.7 * 0.5);
  within(sumB / nB, nB, 0.5);
  CHECK(run.stats.anyHitInvocations > 0);
}

TEST_CASE("the effects front end alpha-tests its shadows exactly like the shadow pass given the table",
          "[alpha][hybrid_effects]") {
  GpuFixture fx;
  AlphaScene s = fenceAndCanopy(false);
  const SyntheticView view = alphaView();
  CpuGBuffer cpu = groundGBuffer(view);
  ShadowResult direct = runShadows(fx, s, cpu, kToSun);
  FrontEndRun frontEnd;
  frontEnd.desc = rb::withPreset({}, rb::Preset::HardShadows);
  frontEnd.light.direction[0] = float(kToSun.x);
  frontEnd.light.direction[1] = float(kToSun.y);
  frontEnd.light.direction[2] = float(kToSun.z);
  std::vector<float> visibility;
  uint32_t nonOpaqueInstances = 0;
  runAlphaFrames(
      fx, s, cpu, 1, {},
      [&](const rb::GBufferDesc& desc) {
        const rb::HybridOutputs& out = frontEnd.effects->outputs();
        visibility = readR16f(fx, out.shadow.image, desc.width, desc.height);
        CHECK(out.shadow.image == out.shadowRaw.image);  // hard shadows: no denoiser
      },
      &nonOpaqueInstances, nullptr, &frontEnd);
  // The front end wrote shading records on its own (no reflections: only because meshes are non-opaque) and
  // handed its material table to the shadow pass: the same rays, the same cut-outs.
  CHECK(nonOpaqueInstances == 2);
  REQUIRE(visibility.size() == direct.visibility.size());
  CHECK(visibility == direct.visibility);
  uint32_t lit = 0;
  for (float v : visibility) lit += v > 0.5f;
  CHECK(lit > 0);
  CHECK(lit < visibility.size());
}
