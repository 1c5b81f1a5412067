// tinygltf's implementation for gltf_loader_fuzz, from the system's header: compiled here with the fuzzer's
// instrumentation in place of the system's libtinygltf.so (which the engine links), so that the fuzzer is guided
// through tinygltf's parsing too. stb_image is not compiled in: it comes from the system's libstb.
#define TINYGLTF_IMPLEMENTATION
#include <tiny_gltf.h>
