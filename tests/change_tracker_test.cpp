// HybridEffects' change tracker (sdk/src/frontend/change_tracker.h), on the host: which boxes a frame's instance and
// light lists give against the previous frame's. The masks those boxes make are checked on the GPU by
// change_reset_test.cpp.
#include <catch2/catch_test_macros.hpp>

#include <cmath>
#include <vector>

#include "change_tracker.h"

namespace {

using MeshChange = rb::AccelerationStructureService::MeshChange;

rb::Instance at(float x, uint32_t mesh = 1) {
  rb::Instance i;
  i.mesh = {mesh, 1};
  i.transform[3] = x;
  return i;
}

MeshChange unitBox(uint64_t poses = 0, bool poseBounds = false, float size = 1.0f) {
  MeshChange c;
  for (int k = 0; k < 3; ++k) c.bounds.min[k] = -size, c.bounds.max[k] = size;
  c.poses = poses;
  c.poseBounds = poseBounds;
  return c;
}

rb::LightSource pointLight(double x, float range) {
  rb::LightSource l;
  l.light.type = rb::LightType::Point;
  l.light.position[0] = x;
  l.light.range = range;
  return l;
}

}  // namespace

TEST_CASE("the change tracker reports moved, appeared and vanished instances by their old and new boxes", "[changes]") {
  rb::ChangeTracker t;
  std::vector<rb::Instance> a = {at(0.0f), at(10.0f)};
  std::vector<MeshChange> m = {unitBox(), unitBox()};
  t.update(a, m, {}, {});
  CHECK(t.boxes().empty());  // the first frame compares against nothing
  t.update(a, m, {}, {});
  CHECK(t.boxes().empty());  // nothing changed

  a[1] = at(12.0f);  // instance 1 moves 2 units along x
  t.update(a, m, {}, {});
  REQUIRE(t.boxes().size() == 2);
  CHECK(t.boxes()[0].lo[0] == 9.0);   // where it was
  CHECK(t.boxes()[1].lo[0] == 11.0);  // where it is
  CHECK(t.boxes()[1].hi[0] == 13.0);
  // Where it was reveals what it hid (RB_CHANGE_REVEALS); where it is does not.
  CHECK(t.boxes()[0].effects == (rb::kChangeAllEffects | RB_CHANGE_REVEALS));
  CHECK(t.boxes()[1].effects == rb::kChangeAllEffects);

  a.push_back(at(20.0f));  // appears
  m.push_back(unitBox());
  t.update(a, m, {}, {});
  REQUIRE(t.boxes().size() == 1);
  CHECK(t.boxes()[0].lo[0] == 19.0);
  CHECK(t.boxes()[0].effects == rb::kChangeAllEffects);  // appeared: it hid nothing before

  a.resize(1), m.resize(1);  // instances 1 and 2 vanish
  t.update(a, m, {}, {});
  REQUIRE(t.boxes().size() == 2);
  CHECK(t.boxes()[0].lo[0] == 11.0);
  CHECK(t.boxes()[1].lo[0] == 19.0);
  for (const rb::WorldChangeBox& b : t.boxes()) CHECK(b.effects == (rb::kChangeAllEffects | RB_CHANGE_REVEALS));

  // A rotated transform's box holds the rotated box: 45 degrees about y widens x and z by sqrt(2).
  std::vector<rb::Instance> r = {at(0.0f)};
  const float c = std::sqrt(0.5f);
  r[0].transform[0] = c, r[0].transform[2] = c, r[0].transform[8] = -c, r[0].transform[10] = c;
  t.update(r, m, {}, {});
  REQUIRE(t.boxes().size() == 2);
  CHECK(std::abs(t.boxes()[1].hi[0] - 2.0 * c) < 1e-6);
  CHECK(std::abs(t.boxes()[1].hi[2] - 2.0 * c) < 1e-6);
  CHECK(t.boxes()[1].hi[1] == 1.0);

  t.forget();  // after a history reset: nothing to compare against
  t.update(a, m, {}, {});
  CHECK(t.boxes().empty());
}

TEST_CASE("the change tracker reads deformations by their pose boxes, and skips meshes without a box", "[changes]") {
  rb::ChangeTracker t;
  std::vector<rb::Instance> a = {at(0.0f)};
  t.update(a, std::vector<MeshChange>{unitBox(1, true)}, {}, {});
  // Updated again with the same pose box: a paused character the engine still updates every frame.
  t.update(a, std::vector<MeshChange>{unitBox(2, true)}, {}, {});
  CHECK(t.boxes().empty());
  // A new pose box: a change in the old and the new box.
  t.update(a, std::vector<MeshChange>{unitBox(3, true, 2.0f)}, {}, {});
  REQUIRE(t.boxes().size() == 2);
  CHECK(t.boxes()[0].hi[0] == 1.0);
  CHECK(t.boxes()[1].hi[0] == 2.0);
  // An update without a pose box of its own (the registered box) is a deformation as such.
  t.update(a, std::vector<MeshChange>{unitBox(4, false, 2.0f)}, {}, {});
  CHECK(t.boxes().size() == 2);
  t.update(a, std::vector<MeshChange>{unitBox(4, false, 2.0f)}, {}, {});
  CHECK(t.boxes().empty());
  // A mesh whose box is unknown gives no box when it moves: anti-lag alone follows it.
  std::vector<MeshChange> unknown = {MeshChange{}};
  t.update(a, unknown, {}, {});
  t.update(std::vector<rb::Instance>{at(5.0f)}, unknown, {}, {});
  CHECK(t.boxes().empty());
}

TEST_CASE("the change tracker reports changed local lights by their range, for local lights only", "[changes]") {
  rb::ChangeTracker t;
  std::vector<rb::LightSource> lights = {pointLight(0.0, 2.0f), pointLight(10.0, 0.0f)};
  t.update({}, {}, lights, {});
  t.update({}, {}, lights, {});
  CHECK(t.boxes().empty());
  lights[0].intensity = 3.0f;  // switched brighter: where it reaches
  t.update({}, {}, lights, {});
  REQUIRE(t.boxes().size() == 2);
  CHECK(t.boxes()[0].lo[0] == -2.0);
  CHECK(t.boxes()[0].hi[0] == 2.0);
  CHECK(t.boxes()[0].effects == RB_CHANGE_LOCAL_LIGHTS);
  lights[1].light.position[0] = 11.0;  // a light of unlimited range: everywhere
  t.update({}, {}, lights, {});
  REQUIRE(t.boxes().size() == 2);
  CHECK(t.boxes()[0].lo[0] <= -rb::kUnboundedChange);
  lights.pop_back();  // switched off
  t.update({}, {}, lights, {});
  REQUIRE(t.boxes().size() == 1);
  CHECK(t.boxes()[0].hi[1] >= rb::kUnboundedChange);

  // The engine's boxes come every frame they are given, for every effect.
  const rb::ChangedBox engine{{1.0, 2.0, 3.0}, {4.0, 5.0, 6.0}};
  t.update({}, {}, lights, std::span<const rb::ChangedBox>(&engine, 1));
  REQUIRE(t.boxes().size() == 1);
  CHECK(t.boxes()[0].effects == (rb::kChangeAllEffects | RB_CHANGE_REVEALS));  // it may be where something was

  // More boxes than the GPU list holds merge into its last one, which then holds them all.
  std::vector<rb::ChangedBox> many(rb::kMaxChangeBoxes + 10);
  for (size_t i = 0; i < many.size(); ++i) many[i].min[0] = many[i].max[0] = double(i);
  t.update({}, {}, lights, many);
  std::vector<rb::GpuChangeBox> gpu;
  const double origin[3] = {100.0, 0.0, 0.0};
  t.toGpu(origin, {}, gpu);
  REQUIRE(gpu.size() == rb::kMaxChangeBoxes);
  CHECK(gpu.back().lo[0] <= float(rb::kMaxChangeBoxes - 1) - 100.0f);
  CHECK(gpu.back().hi[0] >= float(many.size() - 1) - 100.0f);  // in the TLAS's space
}

TEST_CASE("the change tracker sends the last frames' boxes again as follow-ups, after this frame's", "[changes]") {
  rb::ChangeTracker t;
  const double origin[3] = {0.0, 0.0, 0.0};
  const rb::ChangeFollowUp followUp{2, RB_CHANGE_SHADOWS | RB_CHANGE_AO};
  std::vector<rb::GpuChangeBox> gpu;
  const MeshChange box = unitBox();
  std::vector<rb::Instance> instances{at(0.0f)};
  t.update(instances, std::span<const MeshChange>(&box, 1), {}, {});  // primes: no change
  instances[0] = at(5.0f);                                            // moves: old and new box
  t.update(instances, std::span<const MeshChange>(&box, 1), {}, {});
  t.toGpu(origin, followUp, gpu);
  REQUIRE(gpu.size() == 2);  // nothing before it to follow up
  CHECK(gpu[0].effects == (rb::kChangeAllEffects | RB_CHANGE_REVEALS));
  CHECK(gpu[1].effects == rb::kChangeAllEffects);

  // The two frames after it: no change of their own, the move's boxes again, for the effects with reset rays only.
  for (int frame = 1; frame <= 2; ++frame) {
    t.update(instances, std::span<const MeshChange>(&box, 1), {}, {});
    t.toGpu(origin, followUp, gpu);
    INFO("frame " << frame << " after the move");
    REQUIRE(gpu.size() == 2);
    CHECK(gpu[0].effects == (RB_CHANGE_SHADOWS | RB_CHANGE_AO | RB_CHANGE_REVEALS | RB_CHANGE_FOLLOW_UP));
    CHECK(gpu[1].effects == (RB_CHANGE_SHADOWS | RB_CHANGE_AO | RB_CHANGE_FOLLOW_UP));
    CHECK(gpu[0].lo[0] == std::nextafter(-1.0f, -INFINITY));  // the old box
    CHECK(gpu[1].lo[0] == std::nextafter(4.0f, -INFINITY));   // the new box
  }
  t.update(instances, std::span<const MeshChange>(&box, 1), {}, {});
  t.toGpu(origin, followUp, gpu);
  CHECK(gpu.empty());  // the third frame after it: followUp.frames is 2

  // A change with a follow-up: this frame's boxes come first, unflagged.
  instances[0] = at(9.0f);
  t.update(instances, std::span<const MeshChange>(&box, 1), {}, {});
  instances[0] = at(12.0f);
  t.update(instances, std::span<const MeshChange>(&box, 1), {}, {});
  t.toGpu(origin, followUp, gpu);
  REQUIRE(gpu.size() == 4);
  CHECK(gpu[0].effects == (rb::kChangeAllEffects | RB_CHANGE_REVEALS));
  CHECK(gpu[1].effects == rb::kChangeAllEffects);
  CHECK(gpu[2].effects == (RB_CHANGE_SHADOWS | RB_CHANGE_AO | RB_CHANGE_REVEALS | RB_CHANGE_FOLLOW_UP));
  t.toGpu(origin, {}, gpu);  // no follow-up asked for: no revealed pixels either
  REQUIRE(gpu.size() == 2);
  CHECK(gpu[0].effects == rb::kChangeAllEffects);

  // A local light's box concerns local lights alone, which have no reset rays: no follow-up.
  std::vector<rb::LightSource> lights{pointLight(0.0, 2.0f)};
  t.update(instances, std::span<const MeshChange>(&box, 1), lights, {});
  lights[0].light.position[0] = 3.0;
  t.update(instances, std::span<const MeshChange>(&box, 1), lights, {});
  t.update(instances, std::span<const MeshChange>(&box, 1), lights, {});
  t.toGpu(origin, followUp, gpu);
  CHECK(gpu.empty());

  // Follow-ups take only the room this frame's boxes leave, and never merge into one of them.
  std::vector<rb::ChangedBox> many(rb::kMaxChangeBoxes - 1);
  for (size_t i = 0; i < many.size(); ++i) many[i].min[0] = many[i].max[0] = double(i);
  t.update(instances, std::span<const MeshChange>(&box, 1), lights, many);
  t.update(instances, std::span<const MeshChange>(&box, 1), lights, many);
  t.toGpu(origin, followUp, gpu);
  REQUIRE(gpu.size() == rb::kMaxChangeBoxes);
  CHECK(gpu[rb::kMaxChangeBoxes - 2].effects == (rb::kChangeAllEffects | RB_CHANGE_REVEALS));
  CHECK(gpu.back().effects == ((rb::kChangeAllEffects & followUp.effects) | RB_CHANGE_REVEALS | RB_CHANGE_FOLLOW_UP));
  CHECK(gpu.back().hi[0] >= float(many.size() - 1));  // the rest of the last frame's merged into that follow-up
  many.push_back(many.back());
  t.update(instances, std::span<const MeshChange>(&box, 1), lights, many);
  t.toGpu(origin, followUp, gpu);
  REQUIRE(gpu.size() == rb::kMaxChangeBoxes);
  for (const rb::GpuChangeBox& g : gpu) CHECK((g.effects & RB_CHANGE_FOLLOW_UP) == 0u);  // no room: dropped

  // forget() (a history reset) leaves nothing to follow up.
  t.forget();
  t.update(instances, std::span<const MeshChange>(&box, 1), lights, {});
  t.toGpu(origin, followUp, gpu);
  CHECK(gpu.empty());
}
