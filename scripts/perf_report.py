#!/usr/bin/env python3
"""Assembles docs/data/perf_<device>.json from one GPU run of `scripts/gpu/run_remote.sh perf`.

Inputs: the rt-probe logs (primary/stress/miss rates on ~100k and ~1M triangles) and the stats.json of every
raybridge-render run (one folder per row, named SCENE__MODE__PRESET[__path]). Output: the shape of issue 11,
  {"device", "driver", "date", "command", "probe": {...}, "rows": [{"scene", "triangles", "instances", "width",
   "height", "preset", "mode", "hook_gpu_ms", "frame_gpu_ms", "passes": {name: {"gpu_ms", "rays", "grays",
   "fraction_of_probe_stress"}}, ["flythrough": {...}]}]}
Rays/s of each pass are given as a fraction of the probe's stress rate on the triangle count closest to the row's
scene (the probe's primary rate for primary rays). Usage:
  perf_report.py --probe-log LOG [--probe-log LOG] --renders DIR --command "..." --out FILE.json
"""
import argparse
import datetime
import json
import os
import re
import sys

TRACE = re.compile(r"^trace (\w+)\s+\d+x\d+ x \d+ rays/px: median ([\d.]+) ms .* = ([\d.]+) GigaRays/s")
SCENE = re.compile(r"^scene: .* = (\d+) triangles")
DEVICE = re.compile(r"^device: (.*?) \| driver (.*?) \(")


def parse_probe(path):
    """One probe run: {'triangles', 'primary_grays', 'stress_grays', 'miss_grays', 'device', 'driver'}."""
    out = {}
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            if m := SCENE.match(line):
                if out.get("triangles"):  # a second probe run in the same log starts a new record
                    yield out
                    out = {}
                out["triangles"] = int(m.group(1))
            elif m := DEVICE.match(line):
                out["device"], out["driver"] = m.group(1), m.group(2)
            elif m := TRACE.match(line):
                out[m.group(1) + "_grays"] = float(m.group(3))
                out[m.group(1) + "_ms"] = float(m.group(2))
    if out.get("triangles"):
        yield out


def closest_probe(probes, triangles):
    return min(probes, key=lambda p: abs(p["triangles"] - triangles)) if probes else None


def render_row(folder, name, probes):
    with open(os.path.join(folder, "stats.json"), encoding="utf-8") as f:
        st = json.load(f)
    parts = name.split("__")
    fs = st.get("frame_series", {})

    def p50(metric, fallback):
        """The median over the frames after the warm-up where the run has them, else the reported frame's value."""
        return fs[metric]["p50"] if metric in fs else fallback

    row = {
        "scene": parts[0],
        "triangles": st.get("triangles"),
        "instances": st.get("instances"),
        "width": st.get("width"),
        "height": st.get("height"),
        "mode": st.get("mode"),
        "preset": st.get("preset"),
        "frames": st.get("frames"),
        "hook_gpu_ms": p50("hook_gpu_ms", st["engine_gpu_ms"]["hook"]),
        "frame_gpu_ms": p50("frame_gpu_ms", st["engine_gpu_ms"]["frame_total"]),
        "timing": "median over frames after warm-up" if "hook_gpu_ms" in fs else "one frame",
        "engine_gpu_ms": st["engine_gpu_ms"],
    }
    probe = closest_probe(probes, st.get("triangles") or 0)
    passes = {}
    for pname, p in st.get("raybridge", {}).get("passes", {}).items():
        ms = p50(pname + "_gpu_ms", p["gpu_ms"])
        entry = {"gpu_ms": ms}
        if p.get("rays"):
            grays = p["rays"] / (ms * 1e-3) / 1e9 if ms > 0 else 0.0
            entry.update({"rays": p["rays"], "grays": round(grays, 4)})
            if probe and probe.get("stress_grays"):
                entry["fraction_of_probe_stress"] = round(grays / probe["stress_grays"], 4)
        passes[pname] = entry
    row["passes"] = passes
    if "raybridge" in st:
        row["memory_bytes"] = st["raybridge"].get("memory_bytes", {}).get("total")
        row["tlas_instances"] = st["raybridge"]["acceleration_structures"].get("tlas_instances")
    if len(parts) > 3:
        row["tag"] = parts[3]  # path: the fly-through; res, tri, inst: the cost curves
    if len(parts) > 3 and parts[3] == "path" and fs.get("frames"):
        row["flythrough"] = {"camera_path": st.get("camera_path", {}).get("file"), **fs}
    if probe:
        row["probe_triangles"] = probe["triangles"]
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--probe-log", action="append", default=[])
    ap.add_argument("--renders", required=True)
    ap.add_argument("--command", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    probes = [p for log in a.probe_log if os.path.exists(log) for p in parse_probe(log)]
    rows = []
    for name in sorted(os.listdir(a.renders)):
        folder = os.path.join(a.renders, name)
        if os.path.isfile(os.path.join(folder, "stats.json")):
            rows.append(render_row(folder, name, probes))
    if not rows:
        sys.exit(f"perf_report: no stats.json under {a.renders}")
    first = probes[0] if probes else {}
    million = closest_probe(probes, 1_000_000) or {}
    doc = {
        "device": first.get("device", "unknown"),
        "driver": first.get("driver", "unknown"),
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "command": a.command,
        "probe": {
            "stress_grays": million.get("stress_grays"),
            "primary_grays": million.get("primary_grays"),
            "miss_grays": million.get("miss_grays"),
            "triangles": million.get("triangles"),
            "runs": probes,
        },
        "rows": rows,
    }
    with open(a.out, "w", encoding="utf-8") as f:
        json.dump(doc, f, indent=1)
    for r in rows:
        passes = "  ".join(
            f"{n} {p['gpu_ms']:.2f} ms" + (f" {p['grays']:.2f} GR/s ({p.get('fraction_of_probe_stress', 0):.2f}x)" if 'grays' in p else "")
            for n, p in r["passes"].items())
        fly = r.get("flythrough")
        fly_s = f"  path p50/p99 hook {fly['hook_gpu_ms']['p50']:.2f}/{fly['hook_gpu_ms']['p99']:.2f} frame {fly['frame_gpu_ms']['p50']:.2f}/{fly['frame_gpu_ms']['p99']:.2f}" if fly and 'hook_gpu_ms' in fly else ""
        print(f"{r['scene']:6} {r['mode']:6} {r['preset']:12} {r['triangles']} tris: hook {r['hook_gpu_ms']:.2f} ms frame {r['frame_gpu_ms']:.2f} ms  {passes}{fly_s}")


if __name__ == "__main__":
    main()
