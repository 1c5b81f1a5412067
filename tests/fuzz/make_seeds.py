#!/usr/bin/env python3
"""Writes the committed seed corpora of the fuzz targets into tests/fuzz/corpus/<target>/ (a few KiB in all).

Run it again after changing it; the files are committed, so the fuzzers need no Python. The shared scenes are
added at run time by scripts/fuzz.sh, never copied here. Inputs that once crashed a target are committed next to
these (crash-*) and are not written by this script.
"""
import base64
import json
import os
import random
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
CORPUS = os.path.join(HERE, "corpus")

FLOAT, UBYTE, USHORT, UINT = 5126, 5121, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963


class Doc:
    """A glTF document with one buffer that the accessors' data is appended to (4-byte aligned)."""

    def __init__(self):
        self.bin = bytearray()
        self.doc = {"asset": {"version": "2.0"}, "bufferViews": [], "accessors": []}

    def view(self, data, target=None):
        while len(self.bin) % 4:
            self.bin.append(0)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target:
            view["target"] = target
        self.bin += data
        self.doc["bufferViews"].append(view)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, values, kind, component=FLOAT, target=None, bounds=False):
        fmt = {FLOAT: "f", UBYTE: "B", USHORT: "H", UINT: "I"}[component]
        width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}[kind]
        acc = {"bufferView": self.view(struct.pack("<%d%s" % (len(values), fmt), *values), target),
               "componentType": component, "count": len(values) // width, "type": kind}
        if bounds:
            acc["min"] = [min(values[i::width]) for i in range(width)]
            acc["max"] = [max(values[i::width]) for i in range(width)]
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def gltf(self):
        doc = dict(self.doc)
        uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(self.bin)).decode()
        doc["buffers"] = [{"byteLength": len(self.bin), "uri": uri}]
        return json.dumps(doc, separators=(",", ":")).encode()

    def glb(self):
        doc = dict(self.doc)
        doc["buffers"] = [{"byteLength": len(self.bin)}]
        text = json.dumps(doc, separators=(",", ":")).encode()
        text += b" " * (-len(text) % 4)
        binary = bytes(self.bin) + b"\0" * (-len(self.bin) % 4)
        chunks = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(binary), 0x004E4942) + binary
        return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


def triangle():
    d = Doc()
    pos = d.accessor([0, 0, 0, 1, 0, 0, 0, 1, 0], "VEC3", target=ARRAY_BUFFER, bounds=True)
    idx = d.accessor([0, 1, 2], "SCALAR", USHORT, target=ELEMENT_ARRAY_BUFFER)
    d.doc.update({"scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
                  "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}]})
    return d


def skinned_animated():
    """Two joints, JOINTS_0/WEIGHTS_0, inverse bind matrices, a morph target with a sparse accessor, and
    LINEAR rotation, STEP translation, CUBICSPLINE scale and weights channels."""
    d = Doc()
    positions = [0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0]
    pos = d.accessor(positions, "VEC3", bounds=True)
    nrm = d.accessor([0, 0, 1] * 4, "VEC3")
    uv = d.accessor([0, 0, 1, 0, 0, 1, 1, 1], "VEC2")
    joints = d.accessor([0, 1, 0, 0] * 4, "VEC4", UBYTE)
    weights = d.accessor([0.75, 0.25, 0, 0] * 4, "VEC4")
    idx = d.accessor([0, 1, 2, 2, 1, 3], "SCALAR", USHORT)
    identity = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]
    ibm = d.accessor(identity + identity[:12] + [0, -1, 0, 1], "MAT4")
    # Morph target: POSITION deltas as a sparse accessor (no base view: zeros) moving vertex 3.
    sparse_indices = d.view(struct.pack("<H", 3) + b"\0\0")
    sparse_values = d.view(struct.pack("<3f", 0, 0, 0.5))
    d.doc["accessors"].append({"componentType": FLOAT, "count": 4, "type": "VEC3",
                               "sparse": {"count": 1, "indices": {"bufferView": sparse_indices, "componentType": USHORT},
                                          "values": {"bufferView": sparse_values}}})
    morph = len(d.doc["accessors"]) - 1
    times = d.accessor([0, 1], "SCALAR", bounds=True)
    rotations = d.accessor([0, 0, 0, 1, 0, 0, 0.7071068, 0.7071068], "VEC4")
    translations = d.accessor([0, 1, 0, 0, 1.5, 0], "VEC3")
    scales = d.accessor([0, 0, 0, 1, 1, 1, 0, 0, 0] + [0, 0, 0, 2, 2, 2, 0, 0, 0], "VEC3")  # in, value, out
    morph_weights = d.accessor([0, 0, 0, 0, 1, 0], "SCALAR")  # CUBICSPLINE: in, value, out per key
    d.doc.update({
        "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0, "skin": 0}, {"name": "root", "children": [2]},
                  {"name": "tip", "translation": [0, 1, 0]}],
        "skins": [{"joints": [1, 2], "inverseBindMatrices": ibm}],
        "meshes": [{"weights": [0.5], "primitives": [{
            "attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv, "JOINTS_0": joints, "WEIGHTS_0": weights},
            "indices": idx, "targets": [{"POSITION": morph}]}]}],
        "animations": [{"name": "wave", "samplers": [
            {"input": times, "output": rotations, "interpolation": "LINEAR"},
            {"input": times, "output": translations, "interpolation": "STEP"},
            {"input": times, "output": scales, "interpolation": "CUBICSPLINE"},
            {"input": times, "output": morph_weights, "interpolation": "CUBICSPLINE"}],
            "channels": [{"sampler": 0, "target": {"node": 2, "path": "rotation"}},
                         {"sampler": 1, "target": {"node": 1, "path": "translation"}},
                         {"sampler": 2, "target": {"node": 2, "path": "scale"}},
                         {"sampler": 3, "target": {"node": 0, "path": "weights"}}]}],
    })
    return d


def png_1x1():
    raw = b"\0\xc0\x80\x40\xff"  # filter byte, one RGBA texel
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 1, 1, 8, 6, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def textured_lit():
    """A strip and a fan with a textured material (KHR_texture_transform, emissive strength), a camera, and
    KHR_lights_punctual lights on nodes."""
    d = Doc()
    pos = d.accessor([0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0], "VEC3", bounds=True)
    uv = d.accessor([0, 0, 1, 0, 0, 1, 1, 1], "VEC2")
    image = "data:image/png;base64," + base64.b64encode(png_1x1()).decode()
    transform = {"KHR_texture_transform": {"offset": [0.5, 0], "scale": [2, 2], "rotation": 0.3}}
    d.doc.update({
        "extensionsUsed": ["KHR_lights_punctual", "KHR_texture_transform", "KHR_materials_emissive_strength"],
        "extensionsRequired": ["KHR_texture_transform"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "color": [1, 0.5, 0.25], "intensity": 20, "range": 5},
            {"type": "spot", "intensity": 10, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}},
            {"type": "directional"}]}},
        "images": [{"uri": image}], "samplers": [{}], "textures": [{"source": 0, "sampler": 0}],
        "materials": [{"name": "lit", "alphaMode": "MASK", "alphaCutoff": 0.3, "doubleSided": True,
                       "emissiveFactor": [1, 1, 1],
                       "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2}},
                       "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "extensions": transform},
                                                "metallicFactor": 0.2, "roughnessFactor": 0.7}}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 100}}],
        "scene": 0, "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": [{"mesh": 0, "rotation": [0, 0.3826834, 0, 0.9238795]},
                  {"camera": 0, "translation": [0, 0, 5]},
                  {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 2, 0]},
                  {"extensions": {"KHR_lights_punctual": {"light": 1}}, "children": [4]},
                  {"extensions": {"KHR_lights_punctual": {"light": 2}},
                   "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 3, 0, 1]}],
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": pos, "TEXCOORD_0": uv}, "mode": 5, "material": 0},
            {"attributes": {"POSITION": pos}, "mode": 6},
            {"attributes": {"POSITION": pos}, "mode": 1}]}],
    })
    return d


def write(target, name, data):
    folder = os.path.join(CORPUS, target)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def main():
    write("gltf_loader", "triangle.gltf", triangle().gltf())
    write("gltf_loader", "triangle.glb", triangle().glb())
    write("gltf_loader", "skinned_animated.gltf", skinned_animated().gltf())
    write("gltf_loader", "skinned_animated.glb", skinned_animated().glb())
    write("gltf_loader", "textured_lit.gltf", textured_lit().gltf())

    # Arguments separated by newlines (render_options_fuzz also splits on NUL).
    options = {
        "defaults": "",
        "scene_size": "--scene\nscene.gltf\n--width\n640\n--height\n360\n--frames\n2",
        "camera": "--camera\n0,1,5,0,0,0,45\n--sun\n0.3,1,0.2\n--sun-radius\n0.5",
        "effects": "--preset\nultra\n--effects\nshadows,ao,reflections\n--shadow-rays\n8\n--ao-rays\n4\n--ao-range\n2"
                   "\n--ao-estimator\ndistance\n--reflection-roughness\n0.4\n--reflection-rays\n2\n--light-rays\n0"
                   "\n--no-denoise\n--tile-classifier",
        "raster": "--mode\nraster\n--shadow-map-size\n2048\n--pcf\n3\n--gbuffer-normals\ngeometric",
        "animation": "--scene\nfox.glb\n--time\n1.5\n--fps\n30\n--animation\nRun\n--dump\n--out\nframes",
        "characters": "--characters\n3\n--models-from\nmodels\n--dynamic-builds\nasync-late",
        "perf": "--perf-scene\n--perf-ground\n64\n--perf-copies\n2\n--device\nllvmpipe\n--validation",
        "camera_path": "--camera-path\npath.json\n--mode\nraytraced\n--frames\n5\n--fps\n24",
        "help": "--help",
        # Valid values at the edges of what the parser accepts (a sun whose squared length overflows a float, the
        # narrowest fov, a hex float, the largest AO range), and the repeated option that keeps the last value.
        "edges": "--sun\n1e30,1e30,1e30\n--camera\n0,6,0,0,0,0,0.01\n--sun-radius\n0x1p-2\n--ao-range\n3e38"
                 "\n--width\n64\n--width\n16",
    }
    for name, text in options.items():
        write("render_options", name + ".txt", text)

    write("camera_path", "two_keys.json", json.dumps(
        {"version": 1, "fovy_degrees": 50, "keyframes": [
            {"position": [0, 1, 5], "orientation": [0, 0, 0, 1], "duration": 1.5},
            {"position": [2, 1, 3], "orientation": [0, 0.3826834, 0, 0.9238795], "fovy_degrees": 40}]}))
    write("camera_path", "three_keys.json", json.dumps(
        {"version": 1, "keyframes": [
            {"position": [0, 0, 0], "orientation": [0, 0, 0, 2], "duration": 0.5, "fovy_degrees": 70},
            {"position": [1e3, -2, 0.5], "orientation": [0, 0, 0, -1], "duration": 2},
            {"position": [0, 0, 0], "orientation": [1, 0, 0, 0], "duration": 0}]}))
    write("camera_path", "one_key.json", '{"version":1,"keyframes":[{"position":[1,2,3],"orientation":[0,1,0,0]}]}')

    # Mesh registration: FuzzedDataProvider bytes, so any bytes are valid input; a few fixed random ones.
    rng = random.Random(12)
    for i in range(4):
        write("mesh_registration", "random_%d.bin" % i, bytes(rng.randrange(256) for _ in range(64 + 96 * i)))


if __name__ == "__main__":
    main()
