#include <raybridge/light_list.h>

#include <string>

#include "context_impl.h"
#include "light_list_buffer.h"

namespace rb {

struct LightList::Impl {
  Context& ctx;
  LightListBuffer buffer;
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl() { buffer.retire(ctx); }  // frames in flight may still read it
};

LightList::LightList(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
LightList::~LightList() = default;

Result<std::unique_ptr<LightList>> LightList::create(Context& context) {
  // The buffers grow with the first record(): an empty list allocates nothing.
  return std::unique_ptr<LightList>(new LightList(std::make_unique<Impl>(context)));
}

Status LightList::record(VkCommandBuffer cmd, const TlasInfo& tlas, std::span<const LightSource> lights) {
  Impl& s = *impl_;
  auto invalid = [](const std::string& m) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "LightList::record: " + m};
  };
  if (!cmd) return invalid("cmd is VK_NULL_HANDLE");
  if (s.buffer.info().frame == s.ctx.frameIndex()) {
    return invalid("already recorded in frame " + std::to_string(s.ctx.frameIndex()) +
                   ": its ring slot would be overwritten before the first copy runs; record each frame's list once");
  }
  if (Status st = s.buffer.stage(s.ctx, lights, tlas, "LightList::record: "); !st) return st;
  s.buffer.recordUpload(s.ctx, cmd);
  return {};
}

LightListInfo LightList::info() const { return impl_->buffer.info(); }

}  // namespace rb
