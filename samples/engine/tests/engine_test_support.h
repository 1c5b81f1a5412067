// Helpers shared by the engine's test files.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <memory>

#include <catch2/catch_test_macros.hpp>

#include "sample_engine/engine.h"

namespace test_support {

// An engine with validation on (tests assert validationErrorCount() == 0 at the end).
inline std::unique_ptr<sample_engine::Engine> makeEngine(sample_engine::EngineConfig config = {}) {
  config.enableValidation = true;
  auto r = sample_engine::Engine::create(config);
  INFO(r.error);
  REQUIRE(r.ok());
  return std::move(r.value);
}

// The shared glTF sample models: $RAYBRIDGE_SCENES, else ../shared/scenes beside the source tree.
inline std::filesystem::path sharedScenesDir() {
  if (const char* env = std::getenv("RAYBRIDGE_SCENES"); env && *env) return env;
  return std::filesystem::path(RAYBRIDGE_SOURCE_DIR) / ".." / "shared" / "scenes";
}

}  // namespace test_support
