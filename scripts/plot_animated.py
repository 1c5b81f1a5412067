#!/usr/bin/env python3
"""Plots raybridge-animated-bench results: graphics-queue GPU time per frame, sync against async, and prints the
markdown table for docs/benchmarks.md ("animated").

    /usr/bin/python3 scripts/plot_animated.py RESULTS.json [--characters 50] [--out docs/images/animated_h200.png]

Needs matplotlib (Debian: python3-matplotlib).
"""
import argparse
import json


def table(report):
    rows = ["| characters | mode | graphics p50 ms | p99 ms | p99/p50 | frame interval p50 ms | p99 ms | async-queue ms |"
            " BLAS GPU ms/frame | shadow trace ms | refit tris/frame | rebuild tris/frame | stale BLAS | memory MiB |",
            "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in report["runs"]:
        g, i = r["graphics_ms"], r["frame_interval_ms"]
        rows.append("| %d | %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.0f | %.0f | %.1f | %.1f |" % (
            r["characters"], r["mode"], g["p50"], g["p99"], g["p99"] / g["p50"] if g["p50"] else 0.0, i["p50"], i["p99"],
            r["async_ms_mean"], r.get("blas_gpu_ms_per_frame", 0.0), r["shadow_ms_mean"], r["refit_triangles_per_frame"], r["rebuild_triangles_per_frame"],
            r["stale_blas_mean"], r["memory_bytes"] / 1048576.0))
    return "\n".join(rows)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("results")
    ap.add_argument("--characters", type=int, default=50)
    ap.add_argument("--out", default="docs/images/animated_frame_times.png")
    ap.add_argument("--no-plot", action="store_true")
    a = ap.parse_args()
    with open(a.results) as f:
        report = json.load(f)
    print(table(report))
    if a.no_plot:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    runs = [r for r in report["runs"] if r["characters"] == a.characters]
    if not runs:
        raise SystemExit("no run with %d characters in %s" % (a.characters, a.results))
    fig, axes = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    for r in runs:
        axes[0].plot(r["frames"]["graphics_ms"], label=r["mode"], linewidth=0.9)
        axes[1].plot(r["frames"]["interval_ms"], label=r["mode"], linewidth=0.9)
    axes[0].set_ylabel("graphics-queue GPU ms")
    axes[1].set_ylabel("frame interval ms (CPU)")
    axes[1].set_xlabel("frame")
    axes[0].set_title("%s, %d characters, %dx%d, hard shadows + AO" % (report["device"], a.characters,
                                                                        report["width"], report["height"]))
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.set_ylim(bottom=0)
    axes[0].legend(fontsize=8, ncol=3)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
