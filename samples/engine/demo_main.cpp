// raybridge-engine-demo: renders the default demo scene (or a glTF file) headless to a PNG, or opens an
// interactive viewer with --window.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>

#include "cli_support.h"
#include "sample_engine/engine.h"
#include "sample_engine/gltf_loader.h"
#include "sample_engine/procedural.h"
#include "sample_engine/window.h"

using namespace sample_engine;

namespace {

struct Options {
  std::string out = "engine_demo.png";
  std::string exr;
  std::string scene;
  uint32_t width = 1280, height = 720;
  uint32_t shadowMapSize = 2048;
  uint32_t pcf = 3;
  uint32_t ssaoKernel = 0;       // 0 = SSAO off
  uint32_t probeResolution = 0;  // 0 = constant-sky reflections
  std::string effectsPrefix;     // writes PREFIX_ssao.png / PREFIX_shadow.png
  bool window = false;
  bool validation = false;
  int frames = 0;         // --window: close after this many frames (0 = run until closed); headless: frames to render
  double time = 0.0;      // animation time of the (last) headless frame; the viewer starts there
  std::string animation;  // index or name; empty = the scene's first
  bool restPose = false;
};

void addOptions(CLI::App& app, Options& o) {
  rbCli::prepare(app);
  app.description(
      "Renders the default demo scene (or a glTF file) headless: one frame, written as a PNG (and an EXR of the\n"
      "HDR image); --window opens an interactive viewer instead.");
  app.footer("Viewer (--window): drag = orbit, scroll = zoom, WASD/QE = move, Shift = faster, Esc = quit.");
  app.add_option("--out", o.out, "PNG to write (default engine_demo.png)")->type_name("FILE.png");
  app.add_option("--exr", o.exr, "also the HDR image as an EXR")->type_name("FILE.exr");
  app.add_option("--width", o.width, "image width (default 1280)")->type_name("W")->check(rbCli::wholeNumber(1, 16384));
  app.add_option("--height", o.height, "image height (default 720)")
      ->type_name("H")
      ->check(rbCli::wholeNumber(1, 16384));
  app.add_option("--scene", o.scene, "scene to render (default: the procedural demo scene)")
      ->type_name("FILE.gltf|.glb")
      ->check(rbCli::nonEmpty("file name"));
  app.add_option("--shadow-map-size", o.shadowMapSize, "shadow map texels per side (default 2048)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(kMinShadowMapSize, kMaxShadowMapSize));
  app.add_option("--pcf", o.pcf, "PCF taps per axis (default 3)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(1, kMaxShadowPcfKernel));
  app.add_option("--ssao", o.ssaoKernel, "enables the engine's SSAO with KERNEL samples (default 0 = off)")
      ->type_name("KERNEL")
      ->check(rbCli::zeroOrWholeNumber(1, 64, "off"));
  app.add_option("--probe", o.probeResolution, "a RES^2-per-face reflection probe (default 0 = constant sky)")
      ->type_name("RES")
      ->check(rbCli::zeroOrWholeNumber(8, 512, "constant sky"));
  app.add_option("--effects", o.effectsPrefix,
                 "writes the shadow-map visibility (and SSAO) images as PREFIX_shadow.png /\nPREFIX_ssao.png")
      ->type_name("PREFIX")
      ->check(rbCli::nonEmpty("prefix"));
  app.add_option("--time", o.time,
                 "poses the scene's animation at T seconds (headless frames end there, 1/30 s\n"
                 "apart; the viewer plays from T) (default 0)")
      ->type_name("T")
      ->check(rbCli::realNumber(rbCli::atLeast(0.0)));
  app.add_option("--animation", o.animation, "the animation that plays, by index or name (default: the first)")
      ->type_name("N|NAME")
      ->check(rbCli::nonEmpty("index or name"));
  app.add_flag("--rest-pose", o.restPose, "play no animation");
  app.add_flag("--validation", o.validation, "enable VK_LAYER_KHRONOS_validation");
  app.add_option("--frames", o.frames,
                 "headless: frames to render (the last is written); --window: close after N\n"
                 "frames (default 0 = one frame / run until closed)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(0, 1000000));
  app.add_flag("--window", o.window, "open the interactive viewer");
}

// Parses argv; false after printing an error that names the option and the value. --help prints the help and
// exits 0.
bool parse(int argc, char** argv, Options& o) {
  CLI::App app{"", "raybridge-engine-demo"};
  addOptions(app, o);
  bool help = false;
  if (std::string e = rbCli::parse(app, argc, argv, help); !e.empty()) {
    std::fprintf(stderr, "raybridge-engine-demo: error: %s\nsee raybridge-engine-demo --help\n", e.c_str());
    return false;
  }
  if (help) {
    std::printf("%s", app.help().c_str());
    std::exit(0);
  }
  return true;
}

bool loadScene(const Options& o, Scene& scene) {
  if (o.scene.empty()) {
    scene = makeDefaultDemoScene();
    return true;
  }
  SceneLoadResult r = loadGltf(o.scene);
  for (const auto& w : r.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (!r.ok()) {
    std::fprintf(stderr, "error: %s\n", r.error.c_str());
    return false;
  }
  scene = std::move(r.scene);
  return true;
}

// The animation to play (FrameParams::animations), or an error naming the scene's animations.
bool pickAnimation(const Options& o, const Scene& scene, FrameParams& p) {
  p.restPose = o.restPose;
  p.time = o.time;
  if (o.animation.empty()) return true;
  std::optional<uint32_t> index = scene.animationIndex(o.animation);
  if (!index) {
    std::fprintf(stderr, "error: --animation %s: no such animation; the scene's animations are %s\n",
                 o.animation.c_str(), scene.describeAnimations().c_str());
    return false;
  }
  p.animations = {{*index, 0.0}};
  return true;
}

FrameParams initialParams(const Options& o, const Engine& engine) {
  FrameParams p;
  const Scene& s = engine.scene();
  p.camera = s.camera ? *s.camera : defaultCameraFor(engine.sceneBounds());
  if (s.sun) p.sun = *s.sun;
  p.shadow.mapSize = o.shadowMapSize;
  p.shadow.pcfKernelSize = o.pcf;
  p.ssao.enabled = o.ssaoKernel > 0;
  p.ssao.kernelSize = o.ssaoKernel;
  p.reflectionProbe.enabled = o.probeResolution > 0;
  p.reflectionProbe.resolution = o.probeResolution;
  p.outputShadowVisibility = !o.effectsPrefix.empty();
  return p;
}

// A [0,1] float image as a gray PNG.
Status writeGray(const std::string& path, const std::vector<float>& values, uint32_t width, uint32_t height) {
  ImageRGBA8 img;
  img.width = width;
  img.height = height;
  img.pixels.resize(size_t(width) * height * 4);
  for (size_t i = 0; i < values.size(); ++i) {
    const uint8_t v = uint8_t(std::clamp(values[i], 0.0f, 1.0f) * 255.0f + 0.5f);
    img.pixels[i * 4 + 0] = img.pixels[i * 4 + 1] = img.pixels[i * 4 + 2] = v;
    img.pixels[i * 4 + 3] = 255;
  }
  return writePng(path, img);
}

int writeEffects(const Options& o, Engine& engine) {
  const VkExtent2D size = engine.renderSize();
  auto shadow = engine.readbackShadowVisibility();
  if (!shadow) return std::fprintf(stderr, "error: %s\n", shadow.error.c_str()), 1;
  if (Status s = writeGray(o.effectsPrefix + "_shadow.png", shadow.value, size.width, size.height); !s)
    return std::fprintf(stderr, "error: %s\n", s.error.c_str()), 1;
  if (o.ssaoKernel > 0) {
    auto ssao = engine.readbackSsao();
    if (!ssao) return std::fprintf(stderr, "error: %s\n", ssao.error.c_str()), 1;
    if (Status s = writeGray(o.effectsPrefix + "_ssao.png", ssao.value, size.width, size.height); !s)
      return std::fprintf(stderr, "error: %s\n", s.error.c_str()), 1;
  }
  std::printf("wrote %s_*.png\n", o.effectsPrefix.c_str());
  return 0;
}

void printTimings(const PassTimings& t) {
  if (!t.valid) return;
  std::printf("GPU ms: deform %.2f  shadow %.2f  probe %.2f%s  prepass %.2f  ssao %.2f  shadow-vis %.2f  hook %.2f"
              "  local-shadow %.2f  local-irradiance %.2f  lighting %.2f  tonemap %.2f\n",
              t.deformMs, t.shadowMs, t.probeMs, t.probeCaptured ? " (captured)" : "", t.prepassMs, t.ssaoMs,
              t.shadowVisibilityMs, t.hookMs, t.localShadowMs, t.localIrradianceMs, t.lightingMs, t.tonemapMs);
}

int runHeadless(const Options& o) {
  EngineConfig cfg;
  cfg.enableValidation = o.validation;
  auto created = Engine::create(cfg);
  if (!created) {
    std::fprintf(stderr, "error: %s\n", created.error.c_str());
    return 1;
  }
  Engine& engine = *created.value;
  std::printf("device: %s\n", engine.deviceInfo().name.c_str());
  Scene scene;
  if (!loadScene(o, scene)) return 1;
  if (Status s = engine.loadScene(scene); !s) return std::fprintf(stderr, "error: %s\n", s.error.c_str()), 1;
  if (Status s = engine.setRenderSize(o.width, o.height); !s)
    return std::fprintf(stderr, "error: %s\n", s.error.c_str()), 1;
  FrameParams params = initialParams(o, engine);
  if (!pickAnimation(o, engine.scene(), params)) return 1;
  if (!engine.deformedInstances().empty())
    std::printf("animated: %zu deforming instances, %zu animations (%s)\n", engine.deformedInstances().size(),
                engine.scene().animations.size(), engine.scene().describeAnimations().c_str());
  // Extra frames (--frames N) give steady-state timings; the first one's are printed too (probe capture).
  // They lead up to --time at 30 frames per second, so the written frame shows --time.
  const double lastTime = o.time;
  for (int i = 1; i < o.frames; ++i) {
    params.time = std::max(0.0, lastTime - double(o.frames - i) / 30.0);
    if (Status s = engine.renderFrame(params); !s) return std::fprintf(stderr, "error: %s\n", s.error.c_str()), 1;
    if (i == 1) {
      if (Status s = engine.waitIdle(); !s) return std::fprintf(stderr, "error: %s\n", s.error.c_str()), 1;
      std::printf("first frame ");
      printTimings(engine.lastTimings());
    }
  }
  auto t0 = std::chrono::steady_clock::now();
  params.time = lastTime;
  if (Status s = engine.renderFrame(params); !s) return std::fprintf(stderr, "error: %s\n", s.error.c_str()), 1;
  auto ldr = engine.readbackLdr();
  auto t1 = std::chrono::steady_clock::now();
  if (!ldr) return std::fprintf(stderr, "error: %s\n", ldr.error.c_str()), 1;
  if (Status s = writePng(o.out, ldr.value); !s) return std::fprintf(stderr, "error: %s\n", s.error.c_str()), 1;
  std::printf("wrote %s (%ux%u), frame + readback %.1f ms\n", o.out.c_str(), o.width, o.height,
              std::chrono::duration<double, std::milli>(t1 - t0).count());
  if (!o.exr.empty()) {
    auto hdr = engine.readbackHdr();
    if (!hdr) return std::fprintf(stderr, "error: %s\n", hdr.error.c_str()), 1;
    if (Status s = writeExr(o.exr, hdr.value); !s) return std::fprintf(stderr, "error: %s\n", s.error.c_str()), 1;
    std::printf("wrote %s\n", o.exr.c_str());
  }
  if (!o.effectsPrefix.empty())
    if (int rc = writeEffects(o, engine); rc != 0) return rc;
  printTimings(engine.lastTimings());
  const LocalShadowStats local = engine.lastLocalShadowStats();
  std::printf("KHR lights: %u, shadow-mapped %u (%u views)\n", local.lights, local.shadowedLights, local.shadowViews);
  if (o.validation) std::printf("validation errors: %u\n", engine.validationErrorCount());
  return o.validation && engine.validationErrorCount() > 0 ? 2 : 0;
}

// Orbit camera: yaw/pitch/distance around a target point.
struct Orbit {
  glm::vec3 target;
  float yaw, pitch, distance;

  static Orbit from(const Camera& c) {
    glm::vec3 d = c.eye - c.target;
    float dist = std::max(glm::length(d), 1e-3f);
    return {c.target, std::atan2(d.x, d.z), std::asin(std::clamp(d.y / dist, -1.0f, 1.0f)), dist};
  }
  void apply(Camera& c) const {
    glm::vec3 dir(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw));
    c.target = target;
    c.eye = target + dir * distance;
  }
};

int runWindow(const Options& o) {
  auto win = Window::create("Raybridge sample engine", int(o.width), int(o.height));
  if (!win) return std::fprintf(stderr, "error: %s\n", win.error.c_str()), 1;
  Window& window = *win.value;
  EngineConfig cfg;
  cfg.enableValidation = o.validation;
  cfg.enableSwapchain = true;
  cfg.instanceExtensions = window.requiredInstanceExtensions();
  auto created = Engine::create(cfg);
  if (!created) return std::fprintf(stderr, "error: %s\n", created.error.c_str()), 1;
  Engine& engine = *created.value;
  Scene scene;
  if (!loadScene(o, scene)) return 1;
  if (Status s = engine.loadScene(scene); !s) return std::fprintf(stderr, "error: %s\n", s.error.c_str()), 1;
  auto surface = window.createSurface(engine.instance());
  if (!surface) return std::fprintf(stderr, "error: %s\n", surface.error.c_str()), 1;
  int fbw = 0, fbh = 0;
  window.framebufferSize(fbw, fbh);
  if (Status s = engine.attachSurface(surface.value, uint32_t(fbw), uint32_t(fbh)); !s)
    return std::fprintf(stderr, "error: %s\n", s.error.c_str()), 1;

  FrameParams params = initialParams(o, engine);
  if (!pickAnimation(o, engine.scene(), params)) return 1;
  const auto start = std::chrono::steady_clock::now();
  Orbit orbit = Orbit::from(params.camera);
  const float sceneSize = std::max(engine.sceneBounds().radius(), 1.0f);
  double lastX = 0, lastY = 0;
  window.cursorPosition(lastX, lastY);
  auto last = std::chrono::steady_clock::now();
  int frames = 0;
  while (!window.shouldClose()) {
    window.pollEvents();
    if (window.keyDown(Window::Key::Escape)) window.requestClose();
    auto now = std::chrono::steady_clock::now();
    float dt = std::chrono::duration<float>(now - last).count();
    last = now;
    double x, y;
    window.cursorPosition(x, y);
    if (window.mouseButtonDown(0)) {
      orbit.yaw -= float(x - lastX) * 0.005f;
      orbit.pitch = std::clamp(orbit.pitch + float(y - lastY) * 0.005f, -1.5f, 1.5f);
    }
    lastX = x;
    lastY = y;
    orbit.distance = std::max(orbit.distance * std::pow(0.9f, float(window.takeScrollDelta())), 0.05f);
    float speed = sceneSize * 0.5f * dt * (window.keyDown(Window::Key::LeftShift) ? 4.0f : 1.0f);
    glm::vec3 forward(-std::sin(orbit.yaw), 0.0f, -std::cos(orbit.yaw)), right(-forward.z, 0.0f, forward.x);
    if (window.keyDown(Window::Key::W)) orbit.target += forward * speed;
    if (window.keyDown(Window::Key::S)) orbit.target -= forward * speed;
    if (window.keyDown(Window::Key::D)) orbit.target += right * speed;
    if (window.keyDown(Window::Key::A)) orbit.target -= right * speed;
    if (window.keyDown(Window::Key::E)) orbit.target.y += speed;
    if (window.keyDown(Window::Key::Q)) orbit.target.y -= speed;
    orbit.apply(params.camera);

    int w = 0, h = 0;
    window.framebufferSize(w, h);
    if (w == 0 || h == 0) continue;  // minimized
    VkExtent2D size = engine.renderSize();
    if (uint32_t(w) != size.width || uint32_t(h) != size.height) engine.resizeSwapchain(uint32_t(w), uint32_t(h));
    params.time = o.time + std::chrono::duration<double>(now - start).count();
    if (Status s = engine.renderFrame(params); !s) {
      std::fprintf(stderr, "error: %s\n", s.error.c_str());
      break;
    }
    if (++frames % 120 == 0) printTimings(engine.lastTimings());
    if (o.frames > 0 && frames >= o.frames) window.requestClose();
  }
  engine.waitIdle();
  printTimings(engine.lastTimings());
  const LocalShadowStats local = engine.lastLocalShadowStats();
  std::printf("KHR lights: %u, shadow-mapped %u (%u views)\n", local.lights, local.shadowedLights, local.shadowViews);
  if (o.validation) std::printf("validation errors: %u\n", engine.validationErrorCount());
  return o.validation && engine.validationErrorCount() > 0 ? 2 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, o)) return 1;
  return o.window ? runWindow(o) : runHeadless(o);
}
