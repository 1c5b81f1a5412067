// Preloaded (LD_PRELOAD) into the sanitized test programs by scripts/sanitize.sh; never linked into Raybridge.
// dlclose() leaves every library mapped. The Vulkan loader unloads the driver (libvulkan_lvp.so) and the layers
// in vkDestroyInstance, long before LeakSanitizer looks for leaks at exit; a leak allocated inside an unloaded
// library then has only "<unknown module>" frames, which no suppression by library name can match (and which
// would hide whether the allocation came from Raybridge). Newer loaders do the same thing on request
// (VK_LOADER_DISABLE_DYNAMIC_LIBRARY_UNLOADING=1, loader 1.3.261); Debian 12's 1.3.239 predates it.
// The sanitizers' own dlclose interceptor calls this one (the next definition after the program's).
int dlclose(void* handle) {
  (void)handle;
  return 0;
}
