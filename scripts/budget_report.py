#!/usr/bin/env python3
"""The frame budget's sweep (scripts/gpu/budget_sweep.sh) as one JSON and a markdown table.

Reads the folder of the sweep's stats.json files (NAME.json, as budget_sweep.sh's archive holds them) and its
render_gpu.log (the probe's stress and primary rates), writes --out JSON and prints the rows of docs/performance.md's
"Frame budget" table: per scene and budget, HybridEffects::record()'s GPU time p50/p99 (frames after the warm-up),
the plan's fixed cost, floor and levels, and each effect's error (RMSE over the reference's RMS) against the
unbudgeted `ultra` of the same path (raybridge-render --compare-with).

    python3 scripts/budget_report.py DIR --out docs/data/budget_h100.json
"""
import argparse
import glob
import json
import os
import re


def probe_rates(log_path):
    rates = {}
    if not os.path.exists(log_path):
        return rates
    for line in open(log_path, encoding="utf-8", errors="replace"):
        m = re.match(r"trace (stress|primary)\s.*= ([0-9.]+) GigaRays/s", line)
        if m:
            rates[m.group(1) + "_grays_per_s"] = float(m.group(2))
    return rates


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dir")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    rates = probe_rates(os.path.join(a.dir, "render_gpu.log"))
    rows = {}
    for path in sorted(glob.glob(os.path.join(a.dir, "*.json"))):
        name = os.path.splitext(os.path.basename(path))[0]
        s = json.load(open(path))
        fs = s["frame_series"]
        rb = s["raybridge"]
        refl = rb["passes"].get("reflection", {})
        row = {
            "record_gpu_ms": fs.get("record_gpu_ms", {}),
            "frames": fs.get("frames"),
            "warmup_frames_left_out": fs.get("warmup_frames_left_out"),
            "budget": rb.get("budget", {}),
            "passes": rb["passes"],
            "error_vs_unbudgeted": {k: v["relative_rmse"] for k, v in s.get("compare_with", {}).get("images", {}).items()},
            "device": s.get("device", {}),
        }
        if refl.get("rays_per_second") and rates.get("stress_grays_per_s"):
            row["reflection_fraction_of_stress"] = refl["rays_per_second"] / (rates["stress_grays_per_s"] * 1e9)
        rows[name] = row
    json.dump({"probe": rates, "runs": rows}, open(a.out, "w"), indent=1)
    print("| run | record() p50 | p99 | fixed | floor | reflection level | shadows / AO given | error: shadow, AO, reflection |")
    print("|---|---:|---:|---:|---:|---:|---:|---|")
    for name, r in rows.items():
        b, t = r["budget"], r["record_gpu_ms"]
        e = r["error_vs_unbudgeted"]
        err = ", ".join(f"{100 * e[k]:.1f}%" for k in ("shadow", "ao", "reflection") if k in e) or "(reference)"
        given = b.get("given_ms", {})
        floor = f"{b.get('floor_ms', 0):.2f}{' (over the budget)' if b.get('below_floor') else ''}" if b.get("budget_ms") else ""
        print(f"| {name} | {t.get('p50', 0):.2f} | {t.get('p99', 0):.2f} | {b.get('fixed_ms', 0):.2f} | {floor} | "
              f"{b.get('reflection_level', '')} | {given.get('shadows', 0):.2f} / {given.get('ao', 0):.2f} | {err} |")
    for name, r in rows.items():
        if "reflection_fraction_of_stress" in r:
            p = r["passes"]["reflection"]
            print(f"{name}: reflection {p['gpu_ms']:.2f} ms, {p['rays'] / 1e6:.2f} Mrays, "
                  f"{p['rays_per_second'] / 1e9:.2f} GR/s = {r['reflection_fraction_of_stress']:.2f}x stress")


if __name__ == "__main__":
    main()
