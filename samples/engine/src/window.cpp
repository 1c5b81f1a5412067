// GLFW window: the only translation unit of the engine that calls GLFW.
#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

#include "sample_engine/window.h"

namespace sample_engine {

namespace {
GLFWwindow* handle(void* w) { return static_cast<GLFWwindow*>(w); }
}  // namespace

Result<std::unique_ptr<Window>> Window::create(const std::string& title, int width, int height) {
  using R = Result<std::unique_ptr<Window>>;
  if (!glfwInit()) {
    const char* msg = nullptr;
    glfwGetError(&msg);
    return R::failure(std::string("glfwInit failed: ") + (msg ? msg : "no display?"));
  }
  if (!glfwVulkanSupported()) {
    glfwTerminate();
    return R::failure("GLFW reports no Vulkan support");
  }
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  GLFWwindow* w = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!w) {
    const char* msg = nullptr;
    glfwGetError(&msg);
    glfwTerminate();
    return R::failure(std::string("glfwCreateWindow failed: ") + (msg ? msg : "unknown"));
  }
  std::unique_ptr<Window> window(new Window());
  window->window_ = w;
  glfwSetWindowUserPointer(w, window.get());
  glfwSetScrollCallback(w, [](GLFWwindow* gw, double, double dy) {
    static_cast<Window*>(glfwGetWindowUserPointer(gw))->scroll_ += dy;
  });
  return R::success(std::move(window));
}

Window::~Window() {
  if (window_) glfwDestroyWindow(handle(window_));
  glfwTerminate();
}

std::vector<std::string> Window::requiredInstanceExtensions() const {
  uint32_t n = 0;
  const char** names = glfwGetRequiredInstanceExtensions(&n);
  return std::vector<std::string>(names, names + n);
}

Result<VkSurfaceKHR> Window::createSurface(VkInstance instance) const {
  VkSurfaceKHR surface = VK_NULL_HANDLE;
  VkResult r = glfwCreateWindowSurface(instance, handle(window_), nullptr, &surface);
  if (r != VK_SUCCESS)
    return Result<VkSurfaceKHR>::failure("glfwCreateWindowSurface failed: " + std::to_string(int(r)));
  return Result<VkSurfaceKHR>::success(surface);
}

bool Window::shouldClose() const { return glfwWindowShouldClose(handle(window_)); }
void Window::requestClose() { glfwSetWindowShouldClose(handle(window_), GLFW_TRUE); }
void Window::pollEvents() { glfwPollEvents(); }
void Window::framebufferSize(int& width, int& height) const {
  glfwGetFramebufferSize(handle(window_), &width, &height);
}


bool Window::keyDown(Key key) const {
  int code = GLFW_KEY_UNKNOWN;
  switch (key) {
    case Key::W: code = GLFW_KEY_W; break;
    case Key::A: code = GLFW_KEY_A; break;
    case Key::S: code = GLFW_KEY_S; break;
    case Key::D: code = GLFW_KEY_D; break;
    case Key::Q: code = GLFW_KEY_Q; break;
    case Key::E: code = GLFW_KEY_E; break;
    case Key::LeftShift: code = GLFW_KEY_LEFT_SHIFT; break;
    case Key::Escape: code = GLFW_KEY_ESCAPE; break;
  }
  return glfwGetKey(handle(window_), code) == GLFW_PRESS;
}

bool Window::mouseButtonDown(int button) const {
  return glfwGetMouseButton(handle(window_), GLFW_MOUSE_BUTTON_1 + button) == GLFW_PRESS;
}

void Window::cursorPosition(double& x, double& y) const { glfwGetCursorPos(handle(window_), &x, &y); }

double Window::takeScrollDelta() {
  double d = scroll_;
  scroll_ = 0.0;
  return d;
}

}  // namespace sample_engine
