#include "gltf_document_check.h"

#include <algorithm>
#include <cstdio>
#include <set>
#include <string_view>
#include <utility>
#include <vector>

#include <tiny_gltf.h>

namespace sample_engine::detail {
namespace {

using nlohmann::json;

uint32_t le32(std::span<const uint8_t> bytes, size_t at) {
  return uint32_t(bytes[at]) | uint32_t(bytes[at + 1]) << 8 | uint32_t(bytes[at + 2]) << 16 |
         uint32_t(bytes[at + 3]) << 24;
}

std::string hex32(uint32_t v) {
  char s[16];
  std::snprintf(s, sizeof s, "0x%08X", v);
  return s;
}

// Where a failed parse stopped: the JSON path of the value being read.
class ErrorLocator : public nlohmann::json_sax<json> {
 public:
  size_t position = 0;
  std::string message;

  std::string path() const {
    std::string p;
    for (const Level& l : levels_) {
      if (l.array) p += "[" + std::to_string(l.index) + "]";
      else if (!l.key.empty())
        p += (p.empty() ? "" : ".") + l.key;
    }
    return p;
  }

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(size_t) override { return push(false); }
  bool key(string_t& k) override {
    levels_.back().key = k;
    return true;
  }
  bool end_object() override { return pop(); }
  bool start_array(size_t) override { return push(true); }
  bool end_array() override { return pop(); }
  bool parse_error(size_t at, const std::string&, const nlohmann::detail::exception& e) override {
    position = at;
    message = e.what();
    // "[json.exception.parse_error.101] parse error at line 1, column 9: syntax error ...": keep from "syntax".
    if (size_t s = message.find("] "); s != std::string::npos) message.erase(0, s + 2);
    if (size_t s = message.find(": syntax error"); s != std::string::npos) message.erase(0, s + 2);
    // The token read last can be a whole data: URI.
    if (size_t s = message.find("last read: '"); s != std::string::npos && message.size() > s + 12 + 40)
      message = message.substr(0, s + 12 + 40) + "...'";
    return false;
  }

 private:
  struct Level {
    bool array = false;
    size_t index = 0;
    std::string key;
  };
  std::vector<Level> levels_;

  bool value() {
    if (!levels_.empty() && levels_.back().array) ++levels_.back().index;
    return true;
  }
  bool push(bool array) {
    levels_.push_back({array, 0, {}});
    return true;
  }
  bool pop() {
    levels_.pop_back();
    return value();
  }
};

// A JSON value for a message: strings quoted (and shortened), containers by kind.
std::string describe(const json& v) {
  switch (v.type()) {
    case json::value_t::string: {
      const std::string& s = v.get_ref<const std::string&>();
      return "\"" + (s.size() > 40 ? s.substr(0, 40) + "..." : s) + "\"";
    }
    case json::value_t::array: return "an array";
    case json::value_t::object: return "an object";
    case json::value_t::number_float: {
      char s[32];
      std::snprintf(s, sizeof s, "%.17g", v.get<double>());
      return s;
    }
    default: return v.dump();
  }
}

bool isIndex(const json& v) { return v.is_number_unsigned() || (v.is_number_integer() && v.get<int64_t>() >= 0); }

// The base64 digits of a data: URI's payload: their decoded size, or an error naming the first bad character.
std::string base64Size(std::string_view text, size_t& bytes) {
  size_t digits = 0, padding = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    const bool digit = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '+' ||
                       c == '/';
    if (digit && padding == 0) ++digits;
    else if (c == '=' && padding < 2)
      ++padding;
    else
      return "its base64 data has '" + std::string(1, c) + "' at character " + std::to_string(i) +
             ", which is not a base64 digit";
  }
  bytes = digits / 4 * 3 + (digits % 4 == 0 ? 0 : digits % 4 - 1);
  return {};
}

class DocumentCheck {
 public:
  DocumentCheck(const json& doc, bool binary, std::optional<size_t> bin) : doc_(doc), binary_(binary), bin_(bin) {}

  std::string run() {
    if (!doc_.is_object()) return "the document is " + describe(doc_) + ", not a JSON object";
    depth();
    if (!ok()) return error_;
    const json* asset = member(doc_, "asset");
    if (!asset || !asset->is_object() || !member(*asset, "version") || !(*asset)["version"].is_string())
      fail("asset.version is missing (every glTF has an asset object with a version string)");
    for (const char* a : {"accessors", "animations", "buffers", "bufferViews", "cameras", "images", "materials",
                          "meshes", "nodes", "samplers", "scenes", "skins", "textures"})
      topArray(a);
    for (const char* a : {"extensionsUsed", "extensionsRequired"})
      if (const json* list = member(doc_, a)) {
        if (!list->is_array()) fail(std::string(a) + " is " + describe(*list) + ", not an array of names");
        else
          for (size_t i = 0; i < list->size() && ok(); ++i)
            if (!(*list)[i].is_string())
              fail(std::string(a) + "[" + std::to_string(i) + "] is " + describe((*list)[i]) + ", not a name");
      }
    if (!ok()) return error_;
    index(doc_, "", "scene", "scenes");
    each("buffers", [&](const json& o, const std::string& at, size_t i) { buffer(o, at, i); });
    each("bufferViews", [&](const json& o, const std::string& at, size_t) { bufferView(o, at); });
    each("accessors", [&](const json& o, const std::string& at, size_t) { accessor(o, at); });
    each("meshes", [&](const json& o, const std::string& at, size_t) { mesh(o, at); });
    each("nodes", [&](const json& o, const std::string& at, size_t) { node(o, at); });
    each("scenes", [&](const json& o, const std::string& at, size_t) { indices(o, at, "nodes", "nodes", false); });
    each("skins", [&](const json& o, const std::string& at, size_t) {
      indices(o, at, "joints", "nodes", true);
      index(o, at, "inverseBindMatrices", "accessors");
      index(o, at, "skeleton", "nodes");
    });
    each("animations", [&](const json& o, const std::string& at, size_t) { animation(o, at); });
    each("images", [&](const json& o, const std::string& at, size_t) { image(o, at); });
    each("textures", [&](const json& o, const std::string& at, size_t) {
      index(o, at, "sampler", "samplers");
      index(o, at, "source", "images");
    });
    each("materials", [&](const json& o, const std::string& at, size_t) { material(o, at); });
    return error_;
  }

 private:
  const json& doc_;
  const bool binary_;
  const std::optional<size_t> bin_;
  std::string error_;

  bool ok() const { return error_.empty(); }
  void fail(std::string message) {
    if (ok()) error_ = std::move(message);
  }
  static const json* member(const json& o, const char* key) {
    auto it = o.find(key);
    return it == o.end() ? nullptr : &*it;
  }
  static std::string path(const std::string& at, const char* key) { return at.empty() ? key : at + "." + key; }
  size_t count(const char* array) const {
    const json* a = member(doc_, array);
    return a && a->is_array() ? a->size() : 0;
  }

  // Nesting depth, iteratively (the check must not recurse either), naming the top-level member.
  void depth() {
    for (auto it = doc_.begin(); it != doc_.end() && ok(); ++it) {
      std::vector<std::pair<const json*, size_t>> stack{{&it.value(), 2}};
      while (!stack.empty()) {
        auto [v, d] = stack.back();
        stack.pop_back();
        if (!v->is_structured()) continue;
        if (d > kMaxGltfJsonDepth)
          return fail(it.key() + ": JSON nested deeper than " + std::to_string(kMaxGltfJsonDepth) + " levels");
        for (const json& child : *v) stack.push_back({&child, d + 1});
      }
    }
  }

  void topArray(const char* name) {
    const json* a = member(doc_, name);
    if (!a) return;
    if (!a->is_array()) return fail(std::string(name) + " is " + describe(*a) + ", not an array");
    for (size_t i = 0; i < a->size(); ++i)
      if (!(*a)[i].is_object())
        return fail(std::string(name) + "[" + std::to_string(i) + "] is " + describe((*a)[i]) + ", not an object");
  }

  template <typename Check>
  void each(const char* array, Check check) {
    const json* a = member(doc_, array);
    for (size_t i = 0; a && i < a->size() && ok(); ++i)
      check((*a)[i], std::string(array) + "[" + std::to_string(i) + "]", i);
  }

  // An optional (or required) object member; nullptr when absent or on failure.
  const json* object(const json& o, const std::string& at, const char* key, bool required = false) {
    const json* v = member(o, key);
    if (!v) {
      if (required) fail(path(at, key) + " is missing");
      return nullptr;
    }
    if (!v->is_object()) {
      fail(path(at, key) + " is " + describe(*v) + ", not an object");
      return nullptr;
    }
    return v;
  }

  // An index into the top-level array `target` (or, with targetCount, into another array).
  void indexValue(const json& v, const std::string& where, const char* target,
                  std::optional<size_t> targetCount = std::nullopt) {
    if (!isIndex(v)) return fail(where + " = " + describe(v) + " is not an index (an integer >= 0)");
    const size_t n = targetCount ? *targetCount : count(target);
    if (v.get<uint64_t>() >= n)
      fail(where + " = " + describe(v) + " is out of range (the " + (targetCount ? "animation" : "file") + " has " +
           std::to_string(n) + " " + target + ")");
  }
  void index(const json& o, const std::string& at, const char* key, const char* target, bool required = false,
             std::optional<size_t> targetCount = std::nullopt) {
    const json* v = member(o, key);
    if (!v) {
      if (required) fail(path(at, key) + " is missing");
      return;
    }
    indexValue(*v, path(at, key), target, targetCount);
  }
  // An array of distinct indices into `target`.
  void indices(const json& o, const std::string& at, const char* key, const char* target, bool required) {
    const json* v = member(o, key);
    if (!v) {
      if (required) fail(path(at, key) + " is missing");
      return;
    }
    if (!v->is_array()) return fail(path(at, key) + " is " + describe(*v) + ", not an array of indices");
    std::set<uint64_t> seen;
    for (size_t i = 0; i < v->size() && ok(); ++i) {
      const std::string where = path(at, key) + "[" + std::to_string(i) + "]";
      indexValue((*v)[i], where, target);
      if (ok() && !seen.insert((*v)[i].get<uint64_t>()).second)
        fail(where + " = " + describe((*v)[i]) + " is listed twice");
    }
  }
  // An integer in [min, max]; returns it (or nullopt when absent or on failure).
  std::optional<uint64_t> integer(const json& o, const std::string& at, const char* key, uint64_t min, uint64_t max,
                                  bool required = false) {
    const json* v = member(o, key);
    if (!v) {
      if (required) fail(path(at, key) + " is missing");
      return std::nullopt;
    }
    if (!isIndex(*v) || v->get<uint64_t>() < min || v->get<uint64_t>() > max) {
      fail(path(at, key) + " = " + describe(*v) + " is not an integer from " + std::to_string(min) + " to " +
           std::to_string(max));
      return std::nullopt;
    }
    return v->get<uint64_t>();
  }
  void number(const json& o, const std::string& at, const char* key) {
    if (const json* v = member(o, key); v && !v->is_number())
      fail(path(at, key) + " is " + describe(*v) + ", not a number");
  }
  // An array of `n` numbers (any count when n == 0).
  void numbers(const json& o, const std::string& at, const char* key, size_t n) {
    const json* v = member(o, key);
    if (!v) return;
    if (!v->is_array()) return fail(path(at, key) + " is " + describe(*v) + ", not an array of numbers");
    if (n && v->size() != n)
      return fail(path(at, key) + " has " + std::to_string(v->size()) + " elements; it needs " + std::to_string(n));
    for (size_t i = 0; i < v->size(); ++i)
      if (!(*v)[i].is_number())
        return fail(path(at, key) + "[" + std::to_string(i) + "] is " + describe((*v)[i]) + ", not a number");
  }
  void string(const json& o, const std::string& at, const char* key, bool required = false) {
    const json* v = member(o, key);
    if (!v && required) fail(path(at, key) + " is missing");
    else if (v && !v->is_string())
      fail(path(at, key) + " is " + describe(*v) + ", not a string");
  }

  void buffer(const json& o, const std::string& at, size_t i) {
    const std::optional<uint64_t> length = integer(o, at, "byteLength", 1, UINT64_MAX, true);
    string(o, at, "uri");
    if (!ok()) return;
    const json* uri = member(o, "uri");
    if (!uri) {
      if (!binary_) return fail(at + " has no uri (the buffers of a .gltf need one)");
      if (i != 0) return fail(at + " has no uri; in a .glb only buffers[0] may use the BIN chunk");
      if (!bin_) return fail(at + " has no uri and the .glb has no BIN chunk");
      if (*length > *bin_)
        fail(at + ".byteLength = " + std::to_string(*length) + " but the BIN chunk has " + std::to_string(*bin_) +
             " bytes");
      return;
    }
    const std::string& text = uri->get_ref<const std::string&>();
    if (text.rfind("data:", 0) != 0) return;  // a file: tinygltf reads it and compares its size to byteLength
    if (!tinygltf::IsDataURI(text))
      return fail(at + ".uri is a data: URI of type '" + text.substr(5, std::min<size_t>(text.find(','), 45) - 5) +
                  "', which the loader cannot read (buffers need base64, e.g. data:application/octet-stream;base64,)");
    size_t bytes = 0;
    if (std::string e = base64Size(std::string_view(text).substr(text.find(',') + 1), bytes); !e.empty())
      return fail(at + ".uri: " + e);
    if (bytes != *length)
      fail(at + ".byteLength = " + std::to_string(*length) + " but its data: URI holds " + std::to_string(bytes) +
           " bytes");
  }

  void bufferView(const json& o, const std::string& at) {
    index(o, at, "buffer", "buffers", true);
    const uint64_t offset = integer(o, at, "byteOffset", 0, UINT64_MAX).value_or(0);
    const std::optional<uint64_t> length = integer(o, at, "byteLength", 1, UINT64_MAX, true);
    if (const std::optional<uint64_t> stride = integer(o, at, "byteStride", 4, 252); stride && *stride % 4)
      fail(path(at, "byteStride") + " = " + std::to_string(*stride) + " is not a multiple of 4");
    if (!ok()) return;
    const json& buffer = doc_["buffers"][o["buffer"].get<size_t>()];
    const uint64_t bufferLength = buffer["byteLength"].get<uint64_t>();  // checked by buffer()
    // tinygltf decodes images from a buffer view without checking that it lies inside its buffer.
    if (*length > bufferLength || offset > bufferLength - *length)
      fail(at + " (byteOffset " + std::to_string(offset) + ", byteLength " + std::to_string(*length) +
           ") ends past the end of buffers[" + std::to_string(o["buffer"].get<size_t>()) + "] (byteLength " +
           std::to_string(bufferLength) + ")");
  }

  void accessor(const json& o, const std::string& at) {
    index(o, at, "bufferView", "bufferViews");
    integer(o, at, "byteOffset", 0, UINT64_MAX);
    if (const json* c = member(o, "componentType"); !c) fail(path(at, "componentType") + " is missing");
    else if (!c->is_number_integer() ||
             (c->get<int64_t>() < 5120 || c->get<int64_t>() > 5126 || c->get<int64_t>() == 5124))
      fail(path(at, "componentType") + " = " + describe(*c) +
           " is not a glTF component type (5120 BYTE, 5121 UNSIGNED_BYTE, 5122 SHORT, 5123 UNSIGNED_SHORT, 5125 "
           "UNSIGNED_INT or 5126 FLOAT)");
    const std::optional<uint64_t> count = integer(o, at, "count", 0, UINT64_MAX, true);
    string(o, at, "type", true);
    if (const json* type = member(o, "type"); ok() && type) {
      const std::string& t = type->get_ref<const std::string&>();
      if (t != "SCALAR" && t != "VEC2" && t != "VEC3" && t != "VEC4" && t != "MAT2" && t != "MAT3" && t != "MAT4")
        fail(path(at, "type") + " = " + describe(*type) + " is not SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3 or MAT4");
    }
    numbers(o, at, "min", 0);
    numbers(o, at, "max", 0);
    const json* sparse = ok() ? object(o, at, "sparse") : nullptr;
    if (!sparse) return;
    const std::string s = at + ".sparse";
    // tinygltf keeps sparse counts and offsets in an int: a larger value would wrap.
    const std::optional<uint64_t> sparseCount = integer(*sparse, s, "count", 1, INT32_MAX, true);
    if (sparseCount && count && *sparseCount > *count)
      fail(s + ".count = " + std::to_string(*sparseCount) + " is more than the accessor's count " +
           std::to_string(*count));
    if (const json* i = object(*sparse, s, "indices", true)) {
      index(*i, s + ".indices", "bufferView", "bufferViews", true);
      integer(*i, s + ".indices", "byteOffset", 0, INT32_MAX);
      if (const std::optional<uint64_t> c = integer(*i, s + ".indices", "componentType", 0, UINT32_MAX, true);
          c && *c != 5121 && *c != 5123 && *c != 5125)
        fail(s + ".indices.componentType = " + std::to_string(*c) +
             " is not UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT");
    }
    if (const json* v = ok() ? object(*sparse, s, "values", true) : nullptr) {
      index(*v, s + ".values", "bufferView", "bufferViews", true);
      integer(*v, s + ".values", "byteOffset", 0, INT32_MAX);
    }
  }

  void mesh(const json& o, const std::string& at) {
    const json* prims = member(o, "primitives");
    if (!prims || !prims->is_array() || prims->empty())
      return fail(path(at, "primitives") + (prims ? " is " + describe(*prims) + ", not" : " is missing; it needs") +
                  " an array of primitives");
    for (size_t p = 0; p < prims->size() && ok(); ++p) {
      const json& prim = (*prims)[p];
      const std::string pat = at + ".primitives[" + std::to_string(p) + "]";
      if (!prim.is_object()) return fail(pat + " is " + describe(prim) + ", not an object");
      if (const json* attributes = object(prim, pat, "attributes", true))
        for (auto it = attributes->begin(); it != attributes->end() && ok(); ++it)
          indexValue(it.value(), pat + ".attributes." + it.key(), "accessors");
      index(prim, pat, "indices", "accessors");
      index(prim, pat, "material", "materials");
      draco(o, prim, pat);
      integer(prim, pat, "mode", 0, 6);
      const json* targets = member(prim, "targets");
      if (targets && !targets->is_array()) fail(pat + ".targets is " + describe(*targets) + ", not an array");
      for (size_t t = 0; targets && targets->is_array() && t < targets->size() && ok(); ++t) {
        const std::string tat = pat + ".targets[" + std::to_string(t) + "]";
        if (!(*targets)[t].is_object()) return fail(tat + " is " + describe((*targets)[t]) + ", not an object");
        for (auto it = (*targets)[t].begin(); it != (*targets)[t].end() && ok(); ++it)
          indexValue(it.value(), tat + "." + it.key(), "accessors");
      }
    }
    numbers(o, at, "weights", 0);
  }

  // KHR_draco_mesh_compression in extensionsUsed only: the loader ignores it and reads the primitive's accessors,
  // the file's uncompressed fallback. An accessor of such a primitive without a buffer view (nor sparse values)
  // has no data; tinygltf would fail on its indices accessor with "invalid bufferView", naming no Draco.
  void draco(const json& mesh, const json& prim, const std::string& at) {
    const json* ext = member(prim, "extensions");
    if (!ok() || !ext || !ext->is_object() || !member(*ext, "KHR_draco_mesh_compression")) return;
    std::vector<uint64_t> used;
    for (const auto& [name, accessor] : prim["attributes"].items()) used.push_back(accessor.get<uint64_t>());
    if (const json* i = member(prim, "indices")) used.push_back(i->get<uint64_t>());
    for (uint64_t a : used) {
      const json& acc = doc_["accessors"][size_t(a)];
      if (!member(acc, "bufferView") && !member(acc, "sparse"))
        return fail(at + (mesh.contains("name") ? " (mesh " + describe(mesh["name"]) + ")" : std::string()) +
                    " is compressed with KHR_draco_mesh_compression and has no uncompressed data (accessors[" +
                    std::to_string(a) + "] has no bufferView): Draco-compressed meshes are unsupported");
    }
  }

  void node(const json& o, const std::string& at) {
    index(o, at, "camera", "cameras");
    index(o, at, "mesh", "meshes");
    index(o, at, "skin", "skins");
    indices(o, at, "children", "nodes", false);
    numbers(o, at, "matrix", 16);
    numbers(o, at, "translation", 3);
    numbers(o, at, "rotation", 4);
    numbers(o, at, "scale", 3);
    numbers(o, at, "weights", 0);
  }

  void animation(const json& o, const std::string& at) {
    const json* samplers = member(o, "samplers");
    const json* channels = member(o, "channels");
    for (auto [list, name] : {std::pair{samplers, "samplers"}, std::pair{channels, "channels"}}) {
      if (!list || !list->is_array())
        return fail(path(at, name) + (list ? " is " + describe(*list) + ", not an array" : " is missing"));
      for (size_t i = 0; i < list->size(); ++i)
        if (!(*list)[i].is_object())
          return fail(path(at, name) + "[" + std::to_string(i) + "] is " + describe((*list)[i]) + ", not an object");
    }
    for (size_t s = 0; s < samplers->size() && ok(); ++s) {
      const std::string sat = at + ".samplers[" + std::to_string(s) + "]";
      index((*samplers)[s], sat, "input", "accessors", true);
      index((*samplers)[s], sat, "output", "accessors", true);
      string((*samplers)[s], sat, "interpolation");
    }
    for (size_t c = 0; c < channels->size() && ok(); ++c) {
      const std::string cat = at + ".channels[" + std::to_string(c) + "]";
      index((*channels)[c], cat, "sampler", "samplers", true, samplers->size());
      if (const json* target = object((*channels)[c], cat, "target", true)) {
        index(*target, cat + ".target", "node", "nodes");
        string(*target, cat + ".target", "path", true);
      }
    }
  }

  void image(const json& o, const std::string& at) {
    const json* uri = member(o, "uri");
    if (!uri == !member(o, "bufferView")) return fail(at + " needs exactly one of uri and bufferView");
    index(o, at, "bufferView", "bufferViews");
    string(o, at, "uri");
    string(o, at, "mimeType");
    if (!ok() || !uri) return;
    const std::string& text = uri->get_ref<const std::string&>();
    // tinygltf fails the whole file on an empty one; other undecodable images only lose their texture.
    if (tinygltf::IsDataURI(text) && text.find(',') + 1 == text.size())
      fail(at + ".uri is a data: URI without data (a zero-byte image)");
  }

  void material(const json& o, const std::string& at) {
    auto textureInfo = [&](const json& parent, const std::string& pat, const char* key) {
      if (const json* t = object(parent, pat, key)) {
        index(*t, path(pat, key), "index", "textures", true);
        integer(*t, path(pat, key), "texCoord", 0, INT32_MAX);
        number(*t, path(pat, key), "scale");
        number(*t, path(pat, key), "strength");
      }
    };
    if (const json* pbr = object(o, at, "pbrMetallicRoughness")) {
      const std::string pat = path(at, "pbrMetallicRoughness");
      numbers(*pbr, pat, "baseColorFactor", 4);
      number(*pbr, pat, "metallicFactor");
      number(*pbr, pat, "roughnessFactor");
      textureInfo(*pbr, pat, "baseColorTexture");
      textureInfo(*pbr, pat, "metallicRoughnessTexture");
    }
    for (const char* t : {"normalTexture", "occlusionTexture", "emissiveTexture"}) textureInfo(o, at, t);
    numbers(o, at, "emissiveFactor", 3);
    number(o, at, "alphaCutoff");
    string(o, at, "alphaMode");
  }
};

}  // namespace

std::string splitGlb(std::span<const uint8_t> bytes, GlbChunks& out) {
  const size_t size = bytes.size();
  if (size < 12) return "the file has " + std::to_string(size) + " bytes, fewer than a .glb header's 12";
  if (le32(bytes, 0) != 0x46546C67)  // "glTF"
    return "the .glb magic is " + hex32(le32(bytes, 0)) + ", not \"glTF\" (0x46546C67)";
  if (const uint32_t version = le32(bytes, 4); version != 2)
    return ".glb version " + std::to_string(version) + "; the loader reads version 2";
  if (const uint32_t length = le32(bytes, 8); length != size)
    return "the .glb header's length is " + std::to_string(length) + " bytes but the file has " + std::to_string(size);
  if (size < 20) return "the .glb has no JSON chunk";
  const uint32_t jsonLength = le32(bytes, 12), jsonType = le32(bytes, 16);
  if (jsonType != 0x4E4F534A) return "the first .glb chunk has type " + hex32(jsonType) + ", not JSON (0x4E4F534A)";
  if (jsonLength == 0 || jsonLength > size - 20)
    return "the JSON chunk's length " + std::to_string(jsonLength) + " does not fit the " + std::to_string(size - 20) +
           " bytes after its header";
  out.json = bytes.subspan(20, jsonLength);
  out.bin.reset();
  const size_t at = 20 + size_t(jsonLength);
  if (at == size) return {};
  if (size - at < 8)
    return "the " + std::to_string(size - at) + " bytes after the JSON chunk are too few for a chunk header (8)";
  const uint32_t binLength = le32(bytes, at), binType = le32(bytes, at + 4);
  if (binType != 0x004E4942) return "the second .glb chunk has type " + hex32(binType) + ", not BIN (0x004E4942)";
  // tinygltf compares the BIN length with the bytes after the JSON chunk, its 8-byte header included, so it would
  // read up to 8 bytes past the file.
  if (binLength > size - at - 8)
    return "the BIN chunk's length " + std::to_string(binLength) + " does not fit the " +
           std::to_string(size - at - 8) + " bytes after its header";
  out.bin = bytes.subspan(at + 8, binLength);
  return {};
}

std::string parseJson(std::span<const uint8_t> text, json& out) {
  try {
    out = json::parse(text.begin(), text.end());
    return {};
  } catch (const json::exception&) {
  }
  // Parse again, without building anything, to say where it failed.
  ErrorLocator locator;
  json::sax_parse(text.begin(), text.end(), &locator);
  // The position counts the characters read, the end of the input included.
  const size_t position = std::min(locator.position, text.size());
  size_t line = 1, lineStart = 0;
  for (size_t i = 0; i + 1 < position; ++i)
    if (text[i] == '\n') ++line, lineStart = i + 1;
  const std::string where = "line " + std::to_string(line) + ", column " + std::to_string(position - lineStart);
  const std::string at = locator.path();
  return "invalid JSON" + (at.empty() ? std::string() : " at " + at) + " (" + where + "): " + locator.message;
}

std::string checkDocument(const json& doc, bool binary, std::optional<size_t> bin) {
  return DocumentCheck(doc, binary, bin).run();
}

}  // namespace sample_engine::detail
