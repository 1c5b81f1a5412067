#include "embree_reference.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rbtest {

struct EmbreeScene::State {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<uint32_t> geometryToInstance;
};

EmbreeScene::EmbreeScene() : state_(new State) {
  state_->device = rtcNewDevice("threads=2");
  if (!state_->device) throw std::runtime_error("rtcNewDevice failed");
  state_->scene = rtcNewScene(state_->device);
  // Robust mode: watertight edges, so shared edges between triangles are not missed.
  rtcSetSceneFlags(state_->scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(state_->scene, RTC_BUILD_QUALITY_HIGH);
}

EmbreeScene::~EmbreeScene() {
  rtcReleaseScene(state_->scene);
  rtcReleaseDevice(state_->device);
  delete state_;
}

void EmbreeScene::addInstance(const rbsamples::CpuMesh& mesh, const float m[12], uint32_t instanceId) {
  RTCGeometry geom = rtcNewGeometry(state_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                        3 * sizeof(float), mesh.vertexCount()));
  for (uint32_t i = 0; i < mesh.vertexCount(); ++i) {
    double x = mesh.positions[3 * i], y = mesh.positions[3 * i + 1], z = mesh.positions[3 * i + 2];
    for (int r = 0; r < 3; ++r) {
      v[3 * i + r] = static_cast<float>(double(m[4 * r]) * x + double(m[4 * r + 1]) * y + double(m[4 * r + 2]) * z +
                                        double(m[4 * r + 3]));
    }
  }
  auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(uint32_t), mesh.triangleCount()));
  for (size_t i = 0; i < mesh.indices.size(); ++i) idx[i] = mesh.indices[i];
  rtcCommitGeometry(geom);
  uint32_t geomId = rtcAttachGeometry(state_->scene, geom);
  rtcReleaseGeometry(geom);
  if (state_->geometryToInstance.size() <= geomId) state_->geometryToInstance.resize(geomId + 1);
  state_->geometryToInstance[geomId] = instanceId;
}

void EmbreeScene::commit() { rtcCommitScene(state_->scene); }

ReferenceHit EmbreeScene::intersect(const float o[3], const float d[3], float tMin, float tMax) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh{};
  rh.ray.org_x = o[0];
  rh.ray.org_y = o[1];
  rh.ray.org_z = o[2];
  rh.ray.dir_x = d[0];
  rh.ray.dir_y = d[1];
  rh.ray.dir_z = d[2];
  rh.ray.tnear = tMin;
  rh.ray.tfar = tMax;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(state_->scene, &context, &rh);
  ReferenceHit out;
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return out;
  out.hit = true;
  out.t = rh.ray.tfar;
  out.primitiveId = rh.hit.primID;
  out.instanceId = state_->geometryToInstance[rh.hit.geomID];
  out.geometricNormal[0] = rh.hit.Ng_x;
  out.geometricNormal[1] = rh.hit.Ng_y;
  out.geometricNormal[2] = rh.hit.Ng_z;
  out.barycentrics[0] = rh.hit.u;
  out.barycentrics[1] = rh.hit.v;
  return out;
}

ReferenceHit EmbreeScene::intersect(const float o[3], const float d[3], float tMin, float tMax,
                                    const HitFilter& stops) const {
  for (int passes = 0; passes < 1000; ++passes) {
    ReferenceHit h = intersect(o, d, tMin, tMax);
    if (!h.hit || stops(h)) return h;
    // Past the rejected hit: a few ulps on, so the same triangle is not found again.
    tMin = h.t + std::max(1e-6f * h.t, 1e-7f);
  }
  return {};
}

}  // namespace rbtest
