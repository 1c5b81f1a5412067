// Scene bounds and the "finalize" step that makes every mesh complete enough to upload.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "sample_engine/scene.h"

namespace sample_engine {

glm::vec2 UvMapping::apply(const glm::vec2& uv) const {
  const glm::vec2 s = scale * uv;
  const float c = std::cos(rotation), n = std::sin(rotation);
  return offset + glm::vec2(c * s.x + n * s.y, -n * s.x + c * s.y);
}

Bounds Scene::bounds() const {
  Bounds b;
  for (const Instance& inst : instances) {
    if (inst.mesh >= meshes.size()) continue;
    Bounds local;
    for (const glm::vec3& p : meshes[inst.mesh].positions) local.extend(p);
    if (!local.valid()) continue;
    for (int corner = 0; corner < 8; ++corner) {
      glm::vec3 c((corner & 1) ? local.max.x : local.min.x, (corner & 2) ? local.max.y : local.min.y,
                  (corner & 4) ? local.max.z : local.min.z);
      b.extend(glm::vec3(inst.transform * glm::vec4(c, 1.0f)));
    }
  }
  return b;
}

namespace {

uint32_t vertexIndex(const MeshData& m, size_t corner) {
  return m.indices.empty() ? static_cast<uint32_t>(corner) : m.indices[corner];
}

void computeNormals(MeshData& m) {
  m.normals.assign(m.positions.size(), glm::vec3(0.0f));
  const size_t corners = m.indices.empty() ? m.positions.size() : m.indices.size();
  for (size_t t = 0; t + 2 < corners; t += 3) {
    uint32_t i0 = vertexIndex(m, t), i1 = vertexIndex(m, t + 1), i2 = vertexIndex(m, t + 2);
    // Unnormalized cross product: weights each face by its area.
    glm::vec3 n = glm::cross(m.positions[i1] - m.positions[i0], m.positions[i2] - m.positions[i0]);
    m.normals[i0] += n;
    m.normals[i1] += n;
    m.normals[i2] += n;
  }
  for (glm::vec3& n : m.normals) {
    float len = glm::length(n);
    n = len > 0.0f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
  }
}

glm::vec3 anyPerpendicular(const glm::vec3& n) {
  glm::vec3 a = std::abs(n.y) < 0.99f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  return glm::normalize(glm::cross(a, n));
}

// Per-vertex tangents from UV derivatives (Lengyel), Gram-Schmidt against the normal.
void computeTangents(MeshData& m) {
  std::vector<glm::vec3> tan(m.positions.size(), glm::vec3(0.0f));
  std::vector<glm::vec3> bit(m.positions.size(), glm::vec3(0.0f));
  const size_t corners = m.indices.empty() ? m.positions.size() : m.indices.size();
  for (size_t t = 0; t + 2 < corners; t += 3) {
    uint32_t i0 = vertexIndex(m, t), i1 = vertexIndex(m, t + 1), i2 = vertexIndex(m, t + 2);
    glm::vec3 e1 = m.positions[i1] - m.positions[i0], e2 = m.positions[i2] - m.positions[i0];
    glm::vec2 d1 = m.uvs[i1] - m.uvs[i0], d2 = m.uvs[i2] - m.uvs[i0];
    float det = d1.x * d2.y - d2.x * d1.y;
    if (std::abs(det) < 1e-12f) continue;
    float r = 1.0f / det;
    glm::vec3 t3 = (e1 * d2.y - e2 * d1.y) * r;
    glm::vec3 b3 = (e2 * d1.x - e1 * d2.x) * r;
    for (uint32_t i : {i0, i1, i2}) {
      tan[i] += t3;
      bit[i] += b3;
    }
  }
  m.tangents.resize(m.positions.size());
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const glm::vec3& n = m.normals[i];
    glm::vec3 t = tan[i] - n * glm::dot(n, tan[i]);
    float len = glm::length(t);
    t = len > 1e-8f ? t / len : anyPerpendicular(n);
    float w = glm::dot(glm::cross(n, t), bit[i]) < 0.0f ? -1.0f : 1.0f;
    m.tangents[i] = glm::vec4(t, w);
  }
}

}  // namespace

void finalizeMesh(MeshData& m) {
  if (m.normals.size() != m.positions.size()) computeNormals(m);
  if (m.uvs.size() != m.positions.size()) m.uvs.assign(m.positions.size(), glm::vec2(0.0f));
  if (m.tangents.size() != m.positions.size()) computeTangents(m);
  // Drop a trailing partial triangle so index/vertex counts stay multiples of 3.
  if (m.indices.empty()) {
    size_t n = m.positions.size() / 3 * 3;
    if (n != m.positions.size()) {
      m.positions.resize(n);
      m.normals.resize(n);
      m.uvs.resize(n);
      m.tangents.resize(n);
      if (!m.uvs1.empty()) m.uvs1.resize(n);
      // Per-vertex skin and morph arrays follow (empty ones stay empty).
      for (auto* j : {&m.joints0, &m.joints1})
        if (!j->empty()) j->resize(n);
      for (auto* w : {&m.weights0, &m.weights1})
        if (!w->empty()) w->resize(n);
      for (MorphTarget& t : m.morphTargets)
        for (auto* d : {&t.positionDeltas, &t.normalDeltas})
          if (!d->empty()) d->resize(n);
    }
  } else {
    m.indices.resize(m.indices.size() / 3 * 3);
  }
}

void finalizeScene(Scene& scene) {
  if (scene.materials.empty()) scene.materials.push_back(Material{.name = "default"});
  const int textureCount = static_cast<int>(scene.textures.size());
  for (Material& mat : scene.materials) {
    for (int* t : {&mat.baseColorTexture, &mat.metallicRoughnessTexture, &mat.normalTexture, &mat.emissiveTexture,
                   &mat.occlusionTexture})
      if (*t >= textureCount) *t = -1;
    // As the glTF loader reads an unknown alphaMode and a bad cutoff (glTF's default 0.5).
    if (mat.alphaMode != AlphaMode::Mask && mat.alphaMode != AlphaMode::Blend) mat.alphaMode = AlphaMode::Opaque;
    if (!std::isfinite(mat.alphaCutoff)) mat.alphaCutoff = 0.5f;
  }
  for (MeshData& m : scene.meshes) {
    if (m.material >= scene.materials.size()) m.material = 0;
    finalizeMesh(m);
  }
  std::erase_if(scene.instances, [&](const Instance& i) { return i.mesh >= scene.meshes.size(); });
}

namespace {

std::string lightNumber(float v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", double(v));
  return buf;
}

bool finiteNonNegative(float v) { return std::isfinite(v) && v >= 0.0f; }

}  // namespace

Status checkLight(const PunctualLight& light, size_t index) {
  const std::string where = "light " + std::to_string(index) + (light.name.empty() ? "" : " '" + light.name + "'");
  using T = PunctualLight::Type;
  if (light.type != T::Directional && light.type != T::Point && light.type != T::Spot)
    return Status::failure(where + ": type = " + std::to_string(uint32_t(light.type)) +
                           ": unknown (directional, point or spot)");
  for (int c = 0; c < 3; ++c)
    if (!finiteNonNegative(light.color[c]))
      return Status::failure(where + ": color[" + std::to_string(c) + "] = " + lightNumber(light.color[c]) +
                             ": it must be finite and >= 0 (linear RGB)");
  if (!finiteNonNegative(light.intensity))
    return Status::failure(where + ": intensity = " + lightNumber(light.intensity) +
                           ": it must be finite and >= 0 (candela or lux)");
  if (!(light.range == 0.0f || (std::isfinite(light.range) && light.range > 0.0f)))
    return Status::failure(where + ": range = " + lightNumber(light.range) +
                           ": it must be > 0 (or 0 / absent for an unlimited range)");
  if (light.type == T::Spot) {
    constexpr float kHalfPi = 1.57079632679f;
    if (!(std::isfinite(light.outerConeAngle) && light.outerConeAngle > 0.0f && light.outerConeAngle <= kHalfPi))
      return Status::failure(where + ": spot.outerConeAngle = " + lightNumber(light.outerConeAngle) +
                             ": it must be in (0, pi/2] radians");
    if (!(std::isfinite(light.innerConeAngle) && light.innerConeAngle >= 0.0f &&
          light.innerConeAngle < light.outerConeAngle))
      return Status::failure(where + ": spot.innerConeAngle = " + lightNumber(light.innerConeAngle) +
                             ": it must be in [0, outerConeAngle = " + lightNumber(light.outerConeAngle) + ") radians");
  }
  return Status::success();
}

Status checkLights(const Scene& scene) {
  if (scene.lights.size() > kMaxPunctualLights)
    return Status::failure("lights: " + std::to_string(scene.lights.size()) +
                           " lights, more than kMaxPunctualLights = " + std::to_string(kMaxPunctualLights) +
                           "; merge or drop some");
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    if (Status s = checkLight(scene.lights[i], i); !s) return s;
    const PunctualLight& l = scene.lights[i];
    if (l.node >= 0 && size_t(l.node) >= scene.nodes.size())
      return Status::failure("light " + std::to_string(i) + ": node = " + std::to_string(l.node) +
                             " is out of range (the scene has " + std::to_string(scene.nodes.size()) + " nodes)");
  }
  return Status::success();
}

}  // namespace sample_engine
