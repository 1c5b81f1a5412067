#include "cluster_bounds.h"

#include <algorithm>

#include "context_impl.h"
#include "raybridge_shaders.h"

namespace rb {

namespace {

// Below the minimum maxComputeWorkGroupCount[0] every device supports.
constexpr uint32_t kMaxGroupsPerDispatch = 65535;

// ClusterBoundsConstants::positionFormat (RB_POSITION_* in shaders/raybridge_shader_interface.glsl).
enum ClusterPositionFormat : uint32_t {
  kPositionRgb32f = RB_POSITION_RGB32F,
  kPositionRg32f = RB_POSITION_RG32F,
  kPositionRgba32f = RB_POSITION_RGBA32F,
  kPositionRgba16f = RB_POSITION_RGBA16F,
  kPositionRg16f = RB_POSITION_RG16F,
  kPositionRgba16Snorm = RB_POSITION_RGBA16_SNORM,
  kPositionRg16Snorm = RB_POSITION_RG16_SNORM,
  kPositionRgba8Snorm = RB_POSITION_RGBA8_SNORM,
  kPositionUnknown,  // not measurable: such meshes are rebuilt by refit count
};

ClusterPositionFormat positionFormat(VkFormat format) {
  switch (format) {
    case VK_FORMAT_R32G32B32_SFLOAT: return kPositionRgb32f;
    case VK_FORMAT_R32G32_SFLOAT: return kPositionRg32f;
    case VK_FORMAT_R32G32B32A32_SFLOAT: return kPositionRgba32f;
    case VK_FORMAT_R16G16B16A16_SFLOAT: return kPositionRgba16f;
    case VK_FORMAT_R16G16_SFLOAT: return kPositionRg16f;
    case VK_FORMAT_R16G16B16A16_SNORM: return kPositionRgba16Snorm;
    case VK_FORMAT_R16G16_SNORM: return kPositionRg16Snorm;
    case VK_FORMAT_R8G8B8A8_SNORM: return kPositionRgba8Snorm;
    default: return kPositionUnknown;
  }
}

}  // namespace

Status ClusterBoundsPass::create(Context& ctx) {
  Result<ComputePipeline> p = ComputePipeline::create(ctx, SpirvModule::of(spirv::blas_cluster_bounds_comp), {},
                                                      sizeof(ClusterBoundsConstants), "BLAS cluster bounds");
  if (!p) return p.error();
  pipeline_ = p.value();
  return {};
}

void ClusterBoundsPass::destroy(Context& ctx) { pipeline_.destroy(ctx); }

bool ClusterBoundsPass::canMeasure(const MeshDesc& m) {
  if (positionFormat(m.vertexFormat) == kPositionUnknown) return false;
  if (m.vertexAddress % 4 != 0 || m.vertexStride % 4 != 0) return false;
  // The shader indexes words in 32 bits, which SPIR-V's access chains take as signed: corner k of triangle t is
  // index t * 3 + k, and a position is read from words vertex * stride / 4 to 2 past it. Both stay <= INT32_MAX.
  if (uint64_t(m.triangleCount) * 3 > uint64_t(INT32_MAX) + 1) return false;
  if (uint64_t(std::max(m.vertexCount, 1u) - 1) * (m.vertexStride / 4) + 2 > uint64_t(INT32_MAX)) return false;
  if (m.indexType == IndexType::None) return true;
  if (m.indexAddress % 4 != 0) return false;
  // 16-bit indices are read a 32-bit word at a time.
  const VkDeviceSize indexBytes = VkDeviceSize(m.triangleCount) * 3 * (m.indexType == IndexType::Uint16 ? 2 : 4);
  return (indexBytes + 3) / 4 * 4 <= m.indexBufferBytes;
}

uint32_t ClusterBoundsPass::clusterCount(uint32_t triangleCount) {
  return (triangleCount + kRefitClusterTriangles - 1) / kRefitClusterTriangles;
}

void ClusterBoundsPass::record(Context& ctx, VkCommandBuffer cmd, const MeshDesc& m,
                               VkDeviceAddress clusterAreas) const {
  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  vk.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_.pipeline);
  ClusterBoundsConstants pc{};
  pc.positions = m.vertexAddress;
  pc.indices = m.indexAddress;
  pc.positionStride = m.vertexStride;
  pc.positionFormat = positionFormat(m.vertexFormat);
  pc.indexType = m.indexType == IndexType::Uint32   ? RB_INDEX_U32
                 : m.indexType == IndexType::Uint16 ? RB_INDEX_U16
                                                    : RB_INDEX_NONE;
  pc.triangleCount = m.triangleCount;
  const uint32_t clusters = clusterCount(m.triangleCount);
  for (uint32_t first = 0; first < clusters; first += kMaxGroupsPerDispatch) {
    pc.firstCluster = first;
    pc.clusterAreas = clusterAreas + VkDeviceAddress(first) * sizeof(float);
    vk.vkCmdPushConstants(cmd, pipeline_.layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(pc), &pc);
    vk.vkCmdDispatch(cmd, std::min(kMaxGroupsPerDispatch, clusters - first), 1, 1);
  }
}

}  // namespace rb
