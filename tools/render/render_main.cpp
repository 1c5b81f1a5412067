// raybridge-render: one headless image of a scene with the sample engine, in raster mode (the engine's shadow
// maps, SSAO and reflection probe), hybrid mode (Raybridge's ray-traced shadows, AO, reflections and shadowed
// local lights through the adapter) or ray-traced mode (no raster shading: Raybridge shades primary rays into the
// engine's HDR target), plus optional dumps and stats.
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "animated_scene.h"
#include "camera_path.h"
#include "dump_compare.h"
#include "frame_capture.h"
#include "frame_series.h"
#include "glossy_scene.h"
#include "perf_scene.h"
#include "raybridge_sample_engine_adapter.h"
#include "render_options.h"
#include "sample_engine/gltf_loader.h"
#include "sample_engine/procedural.h"

namespace se = sample_engine;
using namespace rbRender;

namespace {

int fail(const std::string& message, int code = 1) {
  std::fprintf(stderr, "raybridge-render: error: %s\n", message.c_str());
  return code;
}

// The first of `path` and its parents that exists and is not a folder, or "" (what makes a folder uncreatable).
std::string fileInTheWay(const std::filesystem::path& path) {
  std::error_code ec;
  for (std::filesystem::path p = path; !p.empty(); p = p.parent_path()) {
    const std::filesystem::file_status s = std::filesystem::status(p, ec);
    if (std::filesystem::exists(s) && !std::filesystem::is_directory(s)) return p.string();
    if (p == p.parent_path()) break;
  }
  return {};
}

// --out, checked before the scene loads and before any Vulkan work: the folder is created and a probe file written
// into it and removed, so that a folder that cannot take the images fails at once rather than after the render.
// The probe's name is longer than any file the command writes, so a folder at the path-length limit fails here too.
std::string prepareOutputFolder(const std::string& folder) {
  namespace fs = std::filesystem;
  const std::string what = "--out: the folder '" + folder + "'";
  const std::string advice = "; give a folder that can be created and written to";
  if (const std::string file = fileInTheWay(folder); !file.empty())
    return what + " cannot be created: '" + file + "' is a file, not a folder" + advice;
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) return what + " cannot be created: " + ec.message() + advice;
  const fs::path probe = fs::path(folder) / (".raybridge-render-write-test-" + std::to_string(getpid()));
  errno = 0;
  std::FILE* f = std::fopen(probe.c_str(), "wbx");  // x: never replaces a file of the same name
  if (!f) return what + " cannot be written to: " + std::strerror(errno) + advice;
  int error = std::fputs("probe\n", f) < 0 || std::fflush(f) != 0 ? (errno ? errno : EIO) : 0;
  if (std::fclose(f) != 0 && !error) error = errno ? errno : EIO;
  fs::remove(probe, ec);
  if (error) return what + " cannot be written to: " + std::strerror(error) + advice;
  return {};
}

// "" if `path` is an existing regular file, else what it is instead, for "--scene: 'x' ...".
std::string notARegularFile(const std::string& path, const std::string& kind) {
  std::error_code ec;
  const std::filesystem::file_status s = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(s))
    return "file '" + path + "' does not exist (" + (ec ? ec.message() : std::string("No such file or directory")) +
           ")";
  if (std::filesystem::is_directory(s)) return "'" + path + "' is a folder, not " + kind;
  if (!std::filesystem::is_regular_file(s)) return "'" + path + "' is not a regular file; give " + kind;
  return {};
}

se::Result<se::Scene> loadScene(const RenderOptions& o, std::vector<se::AnimationPlayback>& playbacks) {
  using R = se::Result<se::Scene>;
  const std::string modelsDir = o.modelsFrom.empty() ? std::string(RAYBRIDGE_SOURCE_DIR) + "/../shared/scenes"
                                                     : o.modelsFrom;
  if (!o.modelsFrom.empty()) {
    std::error_code ec;
    if (!std::filesystem::is_directory(o.modelsFrom, ec))
      return R::failure("--models-from: '" + o.modelsFrom + "' " +
                        (std::filesystem::exists(o.modelsFrom, ec) ? "is not a folder" : "does not exist") +
                        "; give the folder of the shared glTF models");
  }
  if (o.perfScene) {
    PerfSceneInfo info;
    auto perf = makePerfScene(
        modelsDir, info,
        {.groundSegments = o.perfGroundSegments, .copiesScale = o.perfCopies, .groundOnly = o.perfGroundOnly});
    if (!perf) return R::failure("--perf-scene: " + perf.error);
    if (!info.missing.empty() && !o.perfGroundOnly)
      std::fprintf(stderr, "warning: --perf-scene: not found in %s, left out: %s\n", modelsDir.c_str(),
                   info.missing.c_str());
    return perf;
  }
  if (o.glossyScene) return R::success(makeGlossyScene());
  if (o.characters) {
    const std::string& dir = modelsDir;
    // In front of the demo's objects, facing its camera's view (the benchmark centres them on the scene).
    auto animated = rbAnimated::makeAnimatedScene(dir, o.characters, glm::vec2(0.0f, 5.5f));
    if (!animated)
      return R::failure("--characters: " + animated.error +
                        "; --models-from gives the folder of the shared glTF models");
    playbacks = animated.value.playbacks;
    return R::success(std::move(animated.value.scene));
  }
  if (o.scene.empty()) return R::success(se::makeDefaultDemoScene());
  if (std::string e = notARegularFile(o.scene, "a glTF file (.gltf or .glb)"); !e.empty())
    return R::failure("--scene: " + e);
  se::SceneLoadResult r = se::loadGltf(o.scene);
  for (const std::string& w : r.warnings) std::fprintf(stderr, "warning: %s: %s\n", o.scene.c_str(), w.c_str());
  if (!r.ok()) return R::failure("--scene: cannot load glTF '" + o.scene + "': " + r.error);
  if (r.scene.instances.empty()) return R::failure("--scene: '" + o.scene + "' has no triangle meshes to render");
  return R::success(std::move(r.scene));
}

// Near/far of a camera the options place: fitted to the scene bounds seen from its eye.
void fitDepthRange(se::Camera& c, const se::Bounds& bounds) {
  const float radius = bounds.valid() ? std::max(bounds.radius(), 1e-3f) : 1.0f;
  const float distance = bounds.valid() ? glm::length(c.eye - bounds.center()) : 0.0f;
  c.zFar = distance + radius * 2.0f;
  c.zNear = std::clamp(distance - radius * 1.5f, c.zFar * 1e-4f, c.zFar * 0.1f);
}

// The camera of the options, else the scene's, else one framed on the bounds; near/far fitted to the bounds.
se::Camera chooseCamera(const RenderOptions& o, const se::Scene& scene, const se::Bounds& bounds, std::string& source) {
  if (!o.eye) {
    source = scene.camera ? "scene" : "bounds";
    return scene.camera ? *scene.camera : se::defaultCameraFor(bounds);
  }
  source = "option";
  se::Camera c;
  c.eye = *o.eye;
  c.target = *o.target;
  c.fovYDegrees = o.fovYDegrees;
  fitDepthRange(c, bounds);
  return c;
}

// Frame k's time on the camera path: k/(N-1) of the path (the last frame at its end), or k/fps clamped to the end.
double pathTime(const RenderOptions& o, const rbCameraPath::CameraPath& path, uint32_t k) {
  const double duration = path.totalDuration();
  return o.fps ? std::min(double(k) / *o.fps, duration) : double(k) * duration / double(std::max(o.frames - 1, 1u));
}

// A view straight up or down has no defined up for the engine's camera: an error naming the time, else "".
std::string checkPathPose(const rbCameraPath::CameraPose& pose, double t) {
  if (std::abs(pose.forward()[1]) <= 0.9999) return {};
  return "--camera-path: at t = " + std::to_string(t) +
         " s the camera looks straight up or down; the engine's camera keeps +Y up, so tilt the orientation a little";
}

// The path's cameras against the command's camera limits (render_options.h), before any Vulkan work: every
// keyframe's position and fov (the poses between are interpolated from them), and the pose of every frame rendered.
std::string checkPathCameras(const RenderOptions& o, const rbCameraPath::CameraPath& path) {
  static const char* const axes[3] = {"x", "y", "z"};
  for (size_t i = 0; i < path.keys.size(); ++i) {
    const std::string where = "--camera-path: '" + o.cameraPath + "': keyframe " + std::to_string(i) + ": ";
    for (size_t c = 0; c < 3; ++c) {
      const double v = path.keys[i].position[c];
      if (std::string e = checkCameraCoordinate(v, std::string("position ") + axes[c] + " " + formatNumber(v));
          !e.empty())
        return where + e;
    }
    if (std::string e = checkFovY(path.keys[i].fovYDegrees, "fovy_degrees " + formatNumber(path.keys[i].fovYDegrees));
        !e.empty())
      return where + e;
  }
  for (uint32_t k = 0; k < o.frames; ++k) {
    const double t = pathTime(o, path, k);
    if (std::string e = checkPathPose(path.at(t), t); !e.empty()) return e;
  }
  return {};
}

// The camera on the path at time t. se::Camera is eye, target and fov with up = +Y, so the orientation's roll
// about the view direction cannot be represented and is ignored; a view straight up or down has no defined
// up and is an error naming the time.
se::Result<se::Camera> pathCamera(const rbCameraPath::CameraPath& path, double t, const se::Bounds& bounds) {
  const rbCameraPath::CameraPose pose = path.at(t);
  const std::array<double, 3> f = pose.forward();
  if (std::string e = checkPathPose(pose, t); !e.empty()) return se::Result<se::Camera>::failure(e);
  const glm::dvec3 eye(pose.position[0], pose.position[1], pose.position[2]);
  // The target is as far as the eye is from the origin (at least 1): far from the origin a unit step would lose
  // the direction's precision in float.
  const double reach = std::max(1.0, glm::length(eye));
  se::Camera c;
  c.eye = glm::vec3(eye);
  c.target = glm::vec3(eye + glm::dvec3(f[0], f[1], f[2]) * reach);
  c.fovYDegrees = float(pose.fovYDegrees);
  fitDepthRange(c, bounds);
  return se::Result<se::Camera>::success(c);
}

nlohmann::json vec(const glm::vec3& v) { return {v.x, v.y, v.z}; }

// The engine's whole frame on the GPU: every pass it timed.
double frameTotalMs(const se::PassTimings& t) {
  return t.shadowMs + t.probeMs + t.prepassMs + t.ssaoMs + t.shadowVisibilityMs + t.hookMs + t.lightingMs +
         t.tonemapMs + t.localShadowMs + t.localIrradianceMs;
}

// The SDK's passes by their stats.json names; with `effects`, only those the front end runs.
std::vector<std::pair<const char*, const rb::PassStats*>> namedPassStats(const rb::HybridStats& es,
                                                                         const rb::HybridEffects* effects = nullptr) {
  const std::pair<const char*, const rb::PassStats*> all[] = {
      {"shadow", !effects || effects->shadowPass() ? &es.shadow : nullptr},
      {"shadow_denoise", !effects || effects->shadowDenoiser() ? &es.shadowDenoise : nullptr},
      {"ao", !effects || effects->aoPass() ? &es.ao : nullptr},
      {"ao_denoise", !effects || effects->aoDenoiser() ? &es.aoDenoise : nullptr},
      {"reflection", !effects || effects->reflectionPass() ? &es.reflection : nullptr},
      {"reflection_denoise", !effects || effects->reflectionDenoiser() ? &es.reflectionDenoise : nullptr},
      {"local_lights", !effects || effects->localLightPass() ? &es.localLights : nullptr},
      {"local_lights_denoise", !effects || effects->localLightDenoiser() ? &es.localLightsDenoise : nullptr}};
  std::vector<std::pair<const char*, const rb::PassStats*>> out;
  for (const auto& e : all)
    if (e.second) out.push_back(e);
  return out;
}

// `keepAlpha`: A is the image's fourth channel (4 channels only), else 1.
se::ImageRGBA32F toExr(const CapturedFrame& f, const std::vector<float>& values, int channels, bool keepAlpha = false) {
  se::ImageRGBA32F img;
  img.width = f.width;
  img.height = f.height;
  img.pixels.resize(size_t(f.width) * f.height * 4);
  for (size_t i = 0; i < size_t(f.width) * f.height; ++i) {
    for (int c = 0; c < 3; ++c) img.pixels[i * 4 + c] = values[i * channels + (channels == 1 ? 0 : c)];
    img.pixels[i * 4 + 3] = keepAlpha && channels == 4 ? values[i * 4 + 3] : 1.0f;
  }
  return img;
}

// lights.png: irradiance E (lux) shown as E / (1 + E) per channel, sRGB-encoded. The mapping is fixed, so pictures
// of different renders compare (no per-image exposure).
se::ImageRGBA8 irradiancePicture(const se::ImageRGBA32F& e) {
  se::ImageRGBA8 img;
  img.width = e.width, img.height = e.height;
  img.pixels.resize(size_t(e.width) * e.height * 4);
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    if (i % 4 == 3) {
      img.pixels[i] = 255;
      continue;
    }
    const float v = std::max(e.pixels[i], 0.0f), c = v / (1.0f + v);
    const float srgb = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
    img.pixels[i] = uint8_t(std::clamp(srgb, 0.0f, 1.0f) * 255.0f + 0.5f);
  }
  return img;
}

// Distance along each pixel-centre primary ray from the eye to the surface, from the depth buffer and the
// hook's camera-relative viewProj (the eye is at the origin of its space).
std::vector<float> distances(const CapturedFrame& f, const glm::mat4& viewProj) {
  const glm::dmat4 inv = glm::inverse(glm::dmat4(viewProj));
  std::vector<float> out(size_t(f.width) * f.height, 0.0f);
  for (uint32_t y = 0; y < f.height; ++y) {
    for (uint32_t x = 0; x < f.width; ++x) {
      const size_t i = size_t(y) * f.width + x;
      const double d = f.depth[i];
      if (d >= 1.0) continue;  // sky: cleared to the far plane
      glm::dvec4 p = inv * glm::dvec4((x + 0.5) / f.width * 2.0 - 1.0, (y + 0.5) / f.height * 2.0 - 1.0, d, 1.0);
      out[i] = float(glm::length(glm::dvec3(p) / p.w));
    }
  }
  return out;
}

// What one run of the command carries from step to step. The members are declared in the order the steps create
// them, so they are destroyed in reverse: the capture and the adapter before the engine whose device they use.
struct RenderRun {
  explicit RenderRun(const RenderOptions& options)
      : o(options),
        hybrid(o.mode == Mode::Hybrid),
        rayTraced(o.mode == Mode::RayTraced),
        modeName(hybrid      ? "hybrid"
                 : rayTraced ? "raytraced"
                             : "raster") {}

  const RenderOptions& o;
  const bool hybrid, rayTraced;
  const char* const modeName;

  se::Scene scene;
  rbCameraPath::CameraPath cameraPath;
  int animation = -1;  // the animation that plays (index into Scene::animations), -1 = the scene has none
  se::FrameParams params;

  std::unique_ptr<se::Engine> engine;
  std::string cameraSource;

  ResolvedEffects fx;
  size_t lightCount = 0;
  rb::EffectSet effects = 0;
  bool wantShadows = false, wantAo = false, wantReflections = false, wantLights = false;
  std::unique_ptr<rbAdapter::Adapter> adapter;
  std::unique_ptr<FrameCapture> capture;

  // Set for the last frame with --dump; the hook records the copies and keeps that frame's camera-relative viewProj.
  bool captureNext = false;
  std::string captureError;
  glm::mat4 capturedViewProj{1.0f};

  FrameSeries series;
  double capturedPathTime = 0.0;
  se::PassTimings timings;  // of the last frame without capture copies
  se::ImageRGBA8 ldr;
  se::ImageRGBA32F hdr;
};

// Everything the options name is checked before any Vulkan work, so bad input fails fast: the output folder,
// the scene, the camera path and the animation. Returns "" or the error.
std::string loadInputs(RenderRun& run) {
  const RenderOptions& o = run.o;
  if (std::string e = prepareOutputFolder(o.out); !e.empty()) return e;
  std::vector<se::AnimationPlayback> characterPlaybacks;  // --characters: one animation per character
  auto scene = loadScene(o, characterPlaybacks);
  if (!scene) return scene.error;
  run.scene = std::move(scene.value);
  if (!o.cameraPath.empty()) {
    if (std::string e = rbCameraPath::loadCameraPath(o.cameraPath, run.cameraPath); !e.empty())
      return "--camera-path: " + e;
    if (std::string e = checkPathCameras(o, run.cameraPath); !e.empty()) return e;
  }
  if (!characterPlaybacks.empty()) {
    run.params.animations = characterPlaybacks;
    run.animation = int(characterPlaybacks[0].animation);
  } else if (!run.scene.animations.empty()) {
    std::optional<uint32_t> index = o.animation.empty() ? std::optional<uint32_t>(0)
                                                        : run.scene.animationIndex(o.animation);
    if (!index) {
      std::string names;
      for (size_t i = 0; i < run.scene.animations.size(); ++i)
        names += (i ? ", " : "") + std::to_string(i) + " '" + run.scene.animations[i].name + "'";
      return "--animation: the scene has no animation " + o.animation + "; its animations are " + names;
    }
    run.animation = int(*index);
    run.params.animations = {{*index, 0.0}};
  } else if (!o.animation.empty()) {
    return "--animation " + o.animation + ": the scene has no animations";
  }
  return {};
}

// The same device in every mode (Raybridge's extensions enabled, the optional ones where the device has them), so
// the modes, and --reorder, compare like for like. Loads the scene and places the camera and the sun.
std::string createEngine(RenderRun& run) {
  const RenderOptions& o = run.o;
  rb::RequiredFeatures features;
  rb::OptionalFeatures optionalFeatures;
  se::EngineConfig config;
  config.enableValidation = o.validation;
  config.deviceNameFilter = o.device;
  rbAdapter::configureEngine(config, features, &optionalFeatures);
  auto created = se::Engine::create(config);
  if (!created) return "engine: " + created.error;
  run.engine = std::move(created.value);
  se::Engine& engine = *run.engine;
  if (se::Status s = engine.loadScene(run.scene); !s) return s.error;
  if (se::Status s = engine.setRenderSize(o.width, o.height); !s) return s.error;

  se::FrameParams& params = run.params;
  params.camera = chooseCamera(o, engine.scene(), engine.sceneBounds(), run.cameraSource);
  if (!o.cameraPath.empty()) run.cameraSource = "path";
  if (o.sun) params.sun.direction = glm::normalize(*o.sun);
  else if (engine.scene().sun)
    params.sun = *engine.scene().sun;
  params.sun.direction = glm::normalize(params.sun.direction);
  return {};
}

// The effects of the mode: Raybridge's through the adapter (hybrid, ray-traced), or the engine's own
// counterparts (raster); plus the frame capture of --dump.
std::string setUpEffects(RenderRun& run) {
  const RenderOptions& o = run.o;
  se::Engine& engine = *run.engine;
  se::FrameParams& params = run.params;
  run.fx = resolve(o);
  ResolvedEffects& fx = run.fx;
  // The scene's punctual lights are shadowed by Raybridge with any preset but none, unless --effects leaves them out
  // (no light, no pass).
  run.lightCount = engine.scene().lights.size();
  if (!o.effects && run.lightCount && o.preset != rb::Preset::None) fx.hybrid.effects |= rb::kEffectLocalLights;
  if (run.rayTraced)
    fx.hybrid.effects = 0;  // no G-buffer effect: the primary rays' hits are lit by sun, sky and lights
  run.effects = fx.hybrid.effects;
  run.wantShadows = run.effects & rb::kEffectShadows, run.wantAo = run.effects & rb::kEffectAo;
  run.wantReflections = run.effects & rb::kEffectReflections, run.wantLights = run.effects & rb::kEffectLocalLights;
  if (run.hybrid || run.rayTraced) {
    rbAdapter::AdapterConfig ac;
    ac.effects = fx.hybrid;
    ac.rayTraced = run.rayTraced;
    params.externalColor = run.rayTraced;  // the hook shades the frame; the engine draws no G-buffer or lighting
    ac.geometricNormals = o.geometricNormals;
    ac.accelerationStructures.dynamicMode = o.dynamicMode;
    auto a = rbAdapter::Adapter::create(engine, ac);
    if (!a) return "adapter: " + a.error;
    run.adapter = std::move(a.value);
    // Traced shadows replace the shadow map, and a preset without shadows has none in either mode: nothing
    // samples the map, so the engine draws none.
    params.shadow.enabled = false;
  } else {
    // The engine's own counterparts of the effects: the preset's shadow map and PCF, SSAO, the probe.
    params.shadow.enabled = fx.raster.mapSize > 0;
    if (fx.raster.mapSize) params.shadow.mapSize = fx.raster.mapSize;
    params.shadow.pcfKernelSize = fx.raster.pcfKernel ? fx.raster.pcfKernel : 1u;  // 0 = one hardware 2x2 tap
    params.ssao.enabled = run.wantAo;
    params.ssao.radius = fx.hybrid.ao.range ? fx.hybrid.ao.range : rb::kDefaultAoRange;
    params.reflectionProbe.enabled = run.wantReflections;
    params.outputShadowVisibility = o.dump;
  }
  // The engine's own shadowed irradiance of the punctual lights (shadow maps for the strongest few), for lights.exr
  // wherever Raybridge does not compute it.
  params.outputLocalLightIrradiance = o.dump && run.lightCount && !(run.hybrid && run.wantLights) && !run.rayTraced;
  if (o.dump) {
    auto c = FrameCapture::create(engine);
    if (!c) return c.error;
    run.capture = std::move(c.value);
  }
  return {};
}

// The images --dump copies in the hook: the primary rays' distances (ray-traced mode; the pre-pass images are only
// cleared), or Raybridge's effect images (hybrid; an effect that is off names a 1x1 neutral image: nothing to dump).
std::vector<CaptureImage> imagesToCapture(const rbAdapter::Adapter* adapter) {
  if (!adapter) return {};
  if (const rb::PrimaryShadingPass* shading = adapter->primaryShading())
    return {{"distance", shading->outputs().distance, 1, true}};
  const rb::HybridOutputs& fo = adapter->effects().outputs();
  const rb::EffectSet on = adapter->effects().desc().effects;
  auto of = [&](rb::EffectSet effect, const rb::EffectImage& e) { return (on & effect) ? e.image : VK_NULL_HANDLE; };
  std::vector<CaptureImage> images = {{"shadow", of(rb::kEffectShadows, fo.shadow), 1},
                                      {"ao", of(rb::kEffectAo, fo.ao), 1},
                                      {"ao_raw", of(rb::kEffectAo, fo.aoRaw), 1},
                                      {"reflection", of(rb::kEffectReflections, fo.reflection), 4},
                                      {"lights", of(rb::kEffectLocalLights, fo.localLights), 4}};
  if (fo.shadowRaw.image != fo.shadow.image) images.push_back({"shadow_raw", fo.shadowRaw.image, 1});  // denoised
  if (fo.localLightsRaw.image != fo.localLights.image) images.push_back({"lights_raw", fo.localLightsRaw.image, 4});
  return images;
}

// The adapter records its frame in the engine's pre-pass hook; the frame --dump captures also copies its images
// there, while they are in the state the passes left them.
void installPrepassHook(RenderRun& run) {
  run.engine->setPrepassHook([&run](const se::PrepassHookInfo& info, se::LightingInputs& inputs) {
    if (run.adapter) run.adapter->recordFrame(info, inputs);
    if (!run.captureNext) return;
    run.captureNext = false;
    run.capturedViewProj = info.viewProj;
    const std::vector<CaptureImage> images = imagesToCapture(run.adapter.get());
    const se::PassImage& normal = run.o.geometricNormals ? info.geometricNormal : info.normalRoughness;
    if (se::Status s = run.capture->record(info, normal, images); !s) run.captureError = s.error;
  });
}

// Every frame's GPU times as they resolve (the engine's after its fence, the SDK's kFramesInFlight later), for
// the percentiles of stats.json's frame_series.
void collectTimings(RenderRun& run) {
  const se::PassTimings t = run.engine->lastTimings();
  if (t.valid) {
    run.series.add("frame_gpu_ms", t.frameNumber, frameTotalMs(t));
    run.series.add("hook_gpu_ms", t.frameNumber, t.hookMs);
  }
  if (!run.adapter) return;
  if (const rb::PrimaryShadingPass* shading = run.adapter->primaryShading(); shading && shading->stats().frame)
    run.series.add("primary_shading_gpu_ms", shading->stats().frame, shading->stats().gpuMs);
  const rb::HybridStats es = run.adapter->effects().stats();
  for (const auto& [name, p] : namedPassStats(es))
    if (p->frame) run.series.add(std::string(name) + "_gpu_ms", p->frame, p->gpuMs);
  if (es.hook.frame) run.series.add("record_gpu_ms", es.hook.frame, es.hook.gpuMs);  // what --budget holds
}

// Frame k of N: its animation time and, with --camera-path, its camera. Frame k shows time - (N-1-k)/fps (every
// frame at `time` without --fps), so the last, captured frame is always at `time`; a time before 0 is clamped to 0.
// On the path, frame k is at k/(N-1) of the path (the last frame at its end), or k/fps clamped to the end.
se::Status renderFrame(RenderRun& run, uint32_t k) {
  const RenderOptions& o = run.o;
  run.params.time = o.fps ? std::max(0.0, o.time - double(o.frames - 1 - k) / *o.fps) : o.time;
  if (!o.cameraPath.empty()) {
    run.capturedPathTime = pathTime(o, run.cameraPath, k);
    auto camera = pathCamera(run.cameraPath, run.capturedPathTime, run.engine->sceneBounds());
    if (!camera) return se::Status::failure(camera.error);
    run.params.camera = camera.value;
  }
  return run.engine->renderFrame(run.params);
}

// Renders the frames and reads the final images back. With --dump the last frame also copies its pre-pass and
// effect images; the timings reported are those of the frame before it, which has no capture copies.
std::string renderFrames(RenderRun& run) {
  const RenderOptions& o = run.o;
  se::Engine& engine = *run.engine;
  const uint32_t plain = run.capture && o.frames > 1 ? o.frames - 1 : o.frames;
  for (uint32_t f = 0; f < plain; ++f) {
    if (se::Status s = renderFrame(run, f); !s) return s.error;
    collectTimings(run);
  }
  if (se::Status s = engine.waitIdle(); !s) return s.error;
  collectTimings(run);
  run.timings = engine.lastTimings();
  if (run.capture) {
    run.captureNext = true;
    if (se::Status s = renderFrame(run, o.frames - 1); !s) return s.error;
  }
  auto ldr = engine.readbackLdr();  // waits for the GPU
  if (!ldr) return ldr.error;
  auto hdr = engine.readbackHdr();
  if (!hdr) return hdr.error;
  if (run.adapter && !run.adapter->lastError().empty()) return "Raybridge: " + run.adapter->lastError();
  if (!run.captureError.empty()) return run.captureError;
  run.ldr = std::move(ldr.value);
  run.hdr = std::move(hdr.value);
  return {};
}

// final.png and final.exr, and the summary lines of the run.
std::string writeFinalImages(const RenderRun& run) {
  const RenderOptions& o = run.o;
  // The folder was checked at the start; it is created again in case it went away during the render.
  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  if (ec) return "--out: the folder '" + o.out + "' cannot be created: " + ec.message();
  const std::filesystem::path out(o.out);
  if (se::Status s = se::writePng((out / "final.png").string(), run.ldr); !s) return s.error;
  if (se::Status s = se::writeExr((out / "final.exr").string(), run.hdr); !s) return s.error;
  std::printf("wrote %s and %s (%ux%u, %s)\n", (out / "final.png").c_str(), (out / "final.exr").c_str(), o.width,
              o.height, run.modeName);
  if (const nlohmann::json fs = run.series.summary(); fs.contains("frame_gpu_ms"))
    std::printf("over %d frames after %u warm-up frames: frame GPU ms p50 %.2f p99 %.2f; hook p50 %.2f p99 %.2f\n",
                fs["frames"].get<int>(), kFrameSeriesWarmupFrames, fs["frame_gpu_ms"]["p50"].get<double>(),
                fs["frame_gpu_ms"]["p99"].get<double>(), fs["hook_gpu_ms"]["p50"].get<double>(),
                fs["hook_gpu_ms"]["p99"].get<double>());
  if (!o.cameraPath.empty())
    std::printf("camera path %s: %zu keyframes, %.3f s; the captured frame is at %.3f s\n", o.cameraPath.c_str(),
                run.cameraPath.keys.size(), run.cameraPath.totalDuration(), run.capturedPathTime);
  return {};
}

// stats.json: what was rendered (size, frames, animation, scene, camera, camera path).
void addSceneStats(const RenderRun& run, nlohmann::json& stats) {
  const RenderOptions& o = run.o;
  se::Engine& engine = *run.engine;
  const se::FrameParams& params = run.params;
  stats["mode"] = run.modeName;
  stats["width"] = o.width;
  stats["height"] = o.height;
  stats["frames"] = o.frames;
  stats["frame_series"] = run.series.summary();
  stats["animation"] = {{"time", o.time},
                        {"fps", o.fps ? nlohmann::json(*o.fps) : nlohmann::json(nullptr)},
                        {"index", run.animation},
                        {"name", run.animation >= 0 ? engine.scene().animations[size_t(run.animation)].name : ""},
                        {"deformed_instances", engine.deformedInstances().size()}};
  stats["gbuffer_normals"] = o.geometricNormals ? "geometric" : "shading";
  stats["scene"] = o.characters      ? "procedural demo scene with " + std::to_string(o.characters) + " characters"
                   : o.perfScene     ? "performance scene"
                   : o.glossyScene   ? "glossy scene"
                   : o.scene.empty() ? "procedural demo scene"
                                     : o.scene;
  stats["device"] = {{"name", engine.deviceInfo().name}};
  stats["camera"] = {{"eye", vec(params.camera.eye)},
                     {"target", vec(params.camera.target)},
                     {"fovy_degrees", params.camera.fovYDegrees},
                     {"z_near", params.camera.zNear},
                     {"z_far", params.camera.zFar},
                     {"source", run.cameraSource}};
  if (!o.cameraPath.empty())
    stats["camera_path"] = {{"file", o.cameraPath},
                            {"keyframes", run.cameraPath.keys.size()},
                            {"duration_s", run.cameraPath.totalDuration()},
                            {"time_s", run.capturedPathTime}};
}

// stats.json: the sun, the preset and each effect's settings as the passes ran them (defaults filled in).
void addEffectStats(const RenderRun& run, nlohmann::json& stats) {
  const rb::HybridEffectsDesc& hd = run.fx.hybrid;
  const bool hybrid = run.hybrid, wantAo = run.wantAo, wantReflections = run.wantReflections;
  const uint32_t shadowRays = hd.shadows.raysPerPixel ? hd.shadows.raysPerPixel : 1u;  // the engine's sun has no size
  stats["sun"] = {{"direction", vec(run.params.sun.direction)},
                  {"angular_radius_degrees", hybrid && run.wantShadows ? run.fx.sunRadiusDegrees : 0.0f},
                  {"rays_per_pixel", run.rayTraced               ? 1u
                                     : hybrid && run.wantShadows ? shadowRays
                                                                 : 0u}};  // raytraced: hard
  stats["preset"] = rb::toString(run.o.preset);
  stats["effects"] = {
      {"enabled", effectSetToString(run.effects)},
      {"denoise", run.o.denoise},
      {"ao_rays_per_pixel", wantAo ? (hd.ao.raysPerPixel ? hd.ao.raysPerPixel : rb::kDefaultAoRays) : 0u},
      {"ao_range", hd.ao.range ? hd.ao.range : rb::kDefaultAoRange},
      {"ao_estimator", hd.ao.estimator == rb::AoEstimator::Binary ? "binary" : "distance"},
      {"reflection_roughness_threshold", hd.reflections.roughnessThreshold ? hd.reflections.roughnessThreshold
                                                                           : rb::kDefaultReflectionRoughnessThreshold},
      {"reflection_rays_per_pixel",
       wantReflections ? (hd.reflections.raysPerPixel ? hd.reflections.raysPerPixel : rb::kDefaultReflectionRays) : 0u},
      {"ao_half_resolution", hybrid && wantAo && hd.ao.schedule.halfResolution},
      {"reflection_half_resolution", hybrid && wantReflections && hd.reflections.schedule.halfResolution}};
  // Adaptive rays (--adaptive): per effect, the time target (0 = the uniform rays, redistributed) and the
  // granularity ("pixel", or the tile in launch cells, "8x8").
  for (auto [name, a] :
       {std::pair{"shadows", &hd.shadows.schedule.adaptive}, std::pair{"ao", &hd.ao.schedule.adaptive}}) {
    std::string granularity = "pixel";
    if (a->granularity == rb::AdaptiveRayGranularity::Tile) {
      const uint32_t tw = a->tileWidth ? a->tileWidth : rb::kDefaultAdaptiveTileWidth;
      const uint32_t th = a->tileHeight ? a->tileHeight : rb::kDefaultAdaptiveTileHeight;
      granularity = std::to_string(tw) + "x" + std::to_string(th);
    }
    if (a->enabled) {
      stats["effects"]["adaptive"][name] = {{"time_budget_ms", a->timeBudgetMs}, {"granularity", granularity}};
    }
  }
}

// stats.json: the scene's punctual lights and who shadows them; in raster mode, the engine's counterparts drawn.
void addLightAndRasterStats(const RenderRun& run, nlohmann::json& stats) {
  se::Engine& engine = *run.engine;
  const se::LocalShadowStats ls = engine.lastLocalShadowStats();
  uint32_t byType[3] = {0, 0, 0};
  for (const se::PunctualLight& l : engine.scene().lights) ++byType[uint32_t(l.type)];
  const bool traced = (run.hybrid && run.wantLights) || run.rayTraced;
  const rb::LocalLightEffectSettings& ll = run.fx.hybrid.localLights;
  stats["lights"] = {{"count", run.lightCount},
                     {"directional", byType[0]},
                     {"point", byType[1]},
                     {"spot", byType[2]},
                     {"shadowed_by", !run.lightCount ? "none"
                                     : traced        ? "raybridge"
                                                     : "engine shadow maps for the strongest lights"},
                     {"mode", run.rayTraced                         ? "one resampled light per hit"
                              : !traced                             ? "raster"
                              : ll.mode == rb::ManyLightMode::Exact ? "exact"
                                                                    : "stochastic"},
                     {"rays_per_pixel",
                      run.hybrid && traced && ll.mode == rb::ManyLightMode::Stochastic ? ll.raysPerPixel : 0u},
                     {"denoised", traced && run.adapter && run.adapter->effects().localLightDenoiser() != nullptr},
                     {"shadow_mapped_lights", traced ? 0u : ls.shadowedLights},
                     {"shadow_map_views", traced ? 0u : ls.shadowViews}};
  if (run.o.mode == Mode::Raster) {
    const se::ShadowMapStats sm = engine.lastShadowMapStats();
    stats["effects"]["raster_counterparts"] = {{"shadows", sm.enabled ? "shadow map" : "none (unshadowed sun)"},
                                               {"shadow_map_size", sm.enabled ? sm.mapSize : 0u},
                                               {"pcf_kernel", sm.enabled ? sm.pcfKernel : 0u},
                                               {"ao", run.wantAo ? "SSAO" : "off"},
                                               {"reflections",
                                                run.wantReflections ? "reflection probe" : "constant sky"}};
  }
}

// stats.json: the engine's GPU times of the reported frame and the scene's size.
void addEngineStats(const RenderRun& run, nlohmann::json& stats) {
  const se::PassTimings& timings = run.timings;
  stats["engine_gpu_ms"] = {{"valid", timings.valid},
                            {"shadow_map", timings.shadowMs},
                            {"probe", timings.probeMs},
                            {"ssao", timings.ssaoMs},
                            {"shadow_visibility_output", timings.shadowVisibilityMs},
                            {"prepass", timings.prepassMs},
                            {"hook", timings.hookMs},
                            {"lighting", timings.lightingMs},
                            {"tonemap", timings.tonemapMs},
                            {"local_shadow_maps", timings.localShadowMs},
                            {"local_irradiance_output", timings.localIrradianceMs},
                            {"frame_total", frameTotalMs(timings)}};
  const se::Scene& scene = run.engine->scene();
  uint64_t sceneTriangles = 0;
  for (const se::Instance& inst : scene.instances) sceneTriangles += scene.meshes[inst.mesh].triangleCount();
  stats["triangles"] = sceneTriangles;
  stats["instances"] = scene.instances.size();
  stats["rays_traced"] = 0;
}

// Each pass's GPU time and rays for stats.json, printed on one "Raybridge (...):" line; returns the rays traced.
uint64_t addPassStats(const RenderRun& run, nlohmann::json& passes) {
  const rb::HybridEffects& fxo = run.adapter->effects();
  const rb::HybridStats es = fxo.stats();
  uint64_t rays = 0;
  std::printf("Raybridge (%s):", run.rayTraced ? "raytraced" : effectSetToString(run.effects).c_str());
  std::vector<std::pair<const char*, const rb::PassStats*>> named = namedPassStats(es, &fxo);
  const rb::PassStats shadingStats = run.adapter->primaryShading() ? run.adapter->primaryShading()->stats()
                                                                   : rb::PassStats{};
  if (run.rayTraced) named.push_back({"primary_shading", &shadingStats});
  for (const auto& [name, p] : named) {
    passes[name] = {
        {"gpu_ms", p->gpuMs}, {"rays", p->rays}, {"rays_per_second", p->raysPerSecond()}, {"frame", p->frame}};
    if (p->tilesTotal()) {
      passes[name]["tiles"] = {{"traced", p->tilesTraced},
                               {"skipped", p->tilesSkipped},
                               {"converged", p->tilesConverged},
                               {"rays_saved", p->raysSaved}};
    }
    rays += p->rays;
    std::printf(" %s %.1f ms", name, p->gpuMs);
    if (p->rays) std::printf(" %.2f Mrays (%.1f Mrays/s)", p->rays * 1e-6, p->raysPerSecond() * 1e-6);
    std::printf(";");
  }
  return rays;
}

// stats.json's "raybridge": the passes, the acceleration structures and the SDK's memory by category; the device's
// driver and shader execution reordering. Only with the adapter (hybrid and ray-traced modes).
void addRaybridgeStats(const RenderRun& run, nlohmann::json& stats) {
  const RenderOptions& o = run.o;
  rbAdapter::Adapter& adapter = *run.adapter;
  const rb::DeviceInfo& di = adapter.context().deviceInfo();
  stats["device"]["driver"] = di.driverName;
  stats["device"]["driver_info"] = di.driverInfo;
  // Shader execution reordering: enabled on the device, whether the driver says it reorders, and whether the
  // reflections of the reported frame used it (only with --reorder).
  stats["device"]["invocation_reorder"] = di.invocationReorder;
  stats["device"]["invocation_reorder_reorders"] = di.invocationReorderReorders;
  const rb::ReflectionPass* reflectionPass = run.adapter->effects().reflectionPass();
  stats["effects"]["reflection_invocation_reorder"] = reflectionPass && reflectionPass->reordered();
  const rb::AsStats as = run.adapter->accelerationStructures().stats();
  double buildMs = 0.0;
  for (const rb::BuildBatchTiming& b : as.batches) buildMs += b.gpuMs;
  const rb::MemoryStats mem = adapter.context().memoryStats();
  nlohmann::json memory;
  for (size_t c = 0; c < size_t(rb::MemoryCategory::Count); ++c)
    memory[rb::toString(rb::MemoryCategory(c))] = mem.bytes[c];
  memory["total"] = mem.total();
  // HybridEffects' own, by effect and category (EffectMemoryStats), with bytes per pixel of the pass images.
  const rb::EffectMemoryStats byEffect = run.adapter->effects().memoryByEffect();
  const double pixels = double(o.width) * double(o.height);
  nlohmann::json effects = nlohmann::json::object();
  for (const auto& [name, m] :
       {std::pair{"shadows", &byEffect.shadows}, std::pair{"ao", &byEffect.ao},
        std::pair{"reflections", &byEffect.reflections}, std::pair{"local_lights", &byEffect.localLights},
        std::pair{"shared", &byEffect.shared}}) {
    nlohmann::json e;
    for (rb::MemoryCategory c :
         {rb::MemoryCategory::ShaderTables, rb::MemoryCategory::PassImages, rb::MemoryCategory::PassBuffers})
      e[rb::toString(c)] = m->of(c);
    e["total"] = m->total();
    e["pass_image_bytes_per_pixel"] = double(m->of(rb::MemoryCategory::PassImages)) / pixels;
    effects[name] = e;
  }
  memory["by_effect"] = effects;
  memory["pass_image_bytes_per_pixel"] = double(byEffect.total().of(rb::MemoryCategory::PassImages)) / pixels;
  nlohmann::json passes = nlohmann::json::object();
  const uint64_t rays = addPassStats(run, passes);
  std::printf(" BLAS build %.2f ms; memory %.1f MiB\n", buildMs, mem.total() / 1048576.0);
  stats["rays_traced"] = rays;
  // The frame budget (--budget; FrameBudgetStats) as the last frame planned it, and HybridEffects::record()'s own time.
  const rb::HybridStats es = run.adapter->effects().stats();
  const rb::FrameBudgetStats& b = es.budget;
  nlohmann::json budget = {
      {"budget_ms", b.budgetMs},
      {"fixed_ms", b.fixedMs},
      {"floor_ms", b.floorMs},
      {"below_floor", b.belowFloor},
      {"given_ms",
       {{"shadows", b.shadowsMs}, {"ao", b.aoMs}, {"reflections", b.reflectionsMs}, {"local_lights", b.localLightsMs}}},
      {"reflection_level", b.reflectionLevel},
      {"local_light_level", b.localLightLevel},
      {"measurements", b.measurements},
      {"level_steps", b.levelSteps}};
  stats["raybridge"] = {
      {"passes", passes},
      {"record_gpu_ms", es.hook.gpuMs},
      {"budget", budget},
      {"acceleration_structures",
       {{"blas_build_gpu_ms", buildMs},
        {"build_batches", as.batches.size()},
        {"blas_count", as.blasCount},
        {"blas_triangles", as.triangles},
        {"blas_bytes", as.blasBytes},
        {"tlas_bytes", as.tlasBytes},
        {"scratch_bytes", as.scratchBytes},
        {"storage_block_bytes", as.storageBlockBytes},
        {"dedup_hits", as.dedupHits},
        {"tlas_instances", adapter.lastTlas().instanceCount},
        {"tlas_skipped_instances", adapter.lastTlas().skippedInstances},
        {"tlas_mode", o.tlasMode == rb::TlasBuildMode::Rebuild            ? "rebuild"
                      : o.tlasMode == rb::TlasBuildMode::UpdateIfPossible ? "refit"
                                                                          : "adaptive"},
        {"tlas_builds", as.tlasBuilds},
        {"tlas_refits", as.tlasRefits},
        {"dynamic_builds", o.dynamicMode == rb::DynamicBuildMode::InFrame          ? "in-frame"
                           : o.dynamicMode == rb::DynamicBuildMode::AsyncSameFrame ? "async"
                                                                                   : "async-late"},
        {"refits", as.refits},
        {"rebuilds", as.rebuilds},
        {"async", as.async},
        {"async_queue_family", as.async ? nlohmann::json(as.asyncQueueFamily) : nlohmann::json(nullptr)},
        {"async_fallback_reason", as.asyncFallbackReason},
        {"stale_blas", as.staleBlas},
        {"async_gpu_ms", as.lastAsyncGpuMs},
        {"dynamic_blas_bytes", as.dynamicBlasBytes}}},
      {"memory_bytes", memory}};
}

// The statistics of the run (written as stats.json with --dump), printing the SDK's and the engine's GPU times.
// The SDK resolves a pass's GPU time kFramesInFlight frames after recording it.
nlohmann::json collectStats(const RenderRun& run) {
  nlohmann::json stats;
  addSceneStats(run, stats);
  addEffectStats(run, stats);
  addLightAndRasterStats(run, stats);
  addEngineStats(run, stats);
  if (run.adapter) addRaybridgeStats(run, stats);
  const se::PassTimings& timings = run.timings;
  std::printf("engine GPU ms: shadow map %.2f  probe %.2f  prepass %.2f  ssao %.2f  hook %.2f  lighting %.2f  tonemap "
              "%.2f  total %.2f\n",
              timings.shadowMs, timings.probeMs, timings.prepassMs, timings.ssaoMs, timings.hookMs, timings.lightingMs,
              timings.tonemapMs, frameTotalMs(timings));
  stats["validation"] = {{"enabled", run.o.validation}, {"errors", run.engine->validationErrorCount()}};
  return stats;
}

// --dump's images, each as an EXR in the output folder, in the order they are written; the first error stops it.
class DumpWriter {
 public:
  explicit DumpWriter(const std::filesystem::path& out) : out_(out) {}

  void exr(const std::string& name, const se::ImageRGBA32F& img) {
    if (!error_.empty()) return;
    se::Status s = se::writeExr((out_ / name).string(), img, /*halfFloat=*/false);
    error_ = s ? std::string() : s.error;
    written_.push_back(name);
  }
  // The shadowed irradiance of the punctual lights: the EXR and, beside it, its fixed-mapping picture.
  void lights(const std::string& name, const se::ImageRGBA32F& img) {
    if (!error_.empty()) return;
    se::Status s = se::writeExr((out_ / (name + ".exr")).string(), img, /*halfFloat=*/false);
    error_ = s ? std::string() : s.error;
    if (!error_.empty()) return;
    s = se::writePng((out_ / (name + ".png")).string(), irradiancePicture(img));
    error_ = s ? std::string() : s.error;
    written_.push_back(name + ".exr"), written_.push_back(name + ".png");
  }
  void fail(const std::string& error) { error_ = error; }

  const std::string& error() const { return error_; }
  std::vector<std::string>& written() { return written_; }

 private:
  std::filesystem::path out_;
  std::string error_;
  std::vector<std::string> written_;
};

// The engine's own images of the frame: the punctual lights' irradiance where Raybridge did not compute it, and in
// raster mode the shadow-map visibility and SSAO.
void dumpEngineImages(RenderRun& run, const CapturedFrame& f, DumpWriter& w) {
  se::Engine& engine = *run.engine;
  if (w.error().empty() && run.params.outputLocalLightIrradiance) {
    auto irradiance = engine.readbackLocalLightIrradiance();
    if (!irradiance) w.fail(irradiance.error);
    std::vector<float> values;
    for (const glm::vec4& v : irradiance.value) values.insert(values.end(), {v.r, v.g, v.b, v.a});
    if (w.error().empty()) w.lights("lights", toExr(f, values, 4));
  }
  if (w.error().empty() && run.o.mode == Mode::Raster) {
    auto visibility = engine.readbackShadowVisibility();
    if (!visibility) w.fail(visibility.error);
    else
      w.exr("shadow.exr", toExr(f, visibility.value, 1));
    if (w.error().empty() && run.wantAo) {
      auto ssao = engine.readbackSsao();
      if (!ssao) w.fail(ssao.error);
      else
        w.exr("ao.exr", toExr(f, ssao.value, 1));
    }
  }
}

// --dump: depth (distance from the eye), normals, the effect images and stats.json.
std::string writeDump(RenderRun& run, const nlohmann::json& stats) {
  const std::filesystem::path out(run.o.out);
  const CapturedFrame f = run.capture->read();
  DumpWriter w(out);
  // The hook's viewProj is camera-relative: the eye is at the origin of the positions it reconstructs.
  // Ray-traced: the primary rays' own distances (the same convention); the engine drew no G-buffer normals.
  w.exr("depth.exr", toExr(f, run.rayTraced ? f.images.at("distance") : distances(f, run.capturedViewProj), 1));
  // A: the G-buffer normal image's own (the roughness, with shading normals), which reflections read.
  if (!run.rayTraced) w.exr("normal.exr", toExr(f, f.normal, 4, true));
  // Hybrid: Raybridge's images as captured in the hook (raw only where a denoiser ran).
  for (const auto& [name, channels] : {std::pair{"shadow", 1}, std::pair{"shadow_raw", 1}, std::pair{"ao", 1},
                                       std::pair{"ao_raw", 1}, std::pair{"reflection", 4}})
    if (auto it = f.images.find(name); it != f.images.end())
      w.exr(std::string(name) + ".exr", toExr(f, it->second, channels));
  for (const char* name : {"lights", "lights_raw"})
    if (auto it = f.images.find(name); it != f.images.end()) w.lights(name, toExr(f, it->second, 4));
  dumpEngineImages(run, f, w);
  if (!w.error().empty()) return w.error();
  nlohmann::json written = stats;
  if (!run.o.compareWith.empty()) {
    std::string error;
    written["compare_with"] = compareDumps(run.o.compareWith, out, error);
    if (!error.empty()) return error;
    for (const auto& [name, e] : written["compare_with"]["images"].items())
      std::printf("%s against %s: RMSE %.5f (%.2f%% of its RMS)\n", name.c_str(), run.o.compareWith.c_str(),
                  e["rmse"].get<double>(), 100.0 * e["relative_rmse"].get<double>());
  }
  if (se::Status s = se::writeFile((out / "stats.json").string(), written.dump(2) + "\n"); !s) return s.error;
  w.written().push_back("stats.json");
  std::printf("wrote");
  for (size_t i = 0; i < w.written().size(); ++i) std::printf("%s %s", i ? "," : "", w.written()[i].c_str());
  std::printf("\n");
  return {};
}

}  // namespace

int main(int argc, char** argv) {
  RenderOptions o;
  if (std::string e = parseRenderOptions(argc, argv, o); !e.empty()) {
    std::fprintf(stderr, "%s", renderUsage());
    return fail(e, 2);
  }
  if (o.help) return std::printf("%s", renderUsage()), 0;
  if (const char* v = std::getenv("RAYBRIDGE_VALIDATION"); v && std::string(v) == "1") o.validation = true;

  RenderRun run(o);
  if (std::string e = loadInputs(run); !e.empty()) return fail(e);
  if (std::string e = createEngine(run); !e.empty()) return fail(e);
  if (std::string e = setUpEffects(run); !e.empty()) return fail(e);
  installPrepassHook(run);
  if (std::string e = renderFrames(run); !e.empty()) return fail(e);
  if (std::string e = writeFinalImages(run); !e.empty()) return fail(e);
  const nlohmann::json stats = collectStats(run);
  if (o.dump) {
    if (std::string e = writeDump(run, stats); !e.empty()) return fail(e);
  }
  if (o.validation) {
    std::printf("validation errors: %u\n", run.engine->validationErrorCount());
    if (run.engine->validationErrorCount() > 0) return fail("the validation layer reported errors", 3);
  }
  run.engine->setPrepassHook({});
  return 0;
}
