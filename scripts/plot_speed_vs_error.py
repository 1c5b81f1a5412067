#!/usr/bin/env python3
"""Plots raybridge-effects-bench results: speed against error, one figure per effect.

    scripts/plot_speed_vs_error.py RESULTS.json [--images DIR] [--out-dir docs/images/effects] [--tag lavapipe]

Each figure has two rows (x = GPU ms of the effect's own passes, then of the whole frame) and one or two
columns (y = RMSE against the converged reference; y = mean FLIP over the surface pixels when --images is given
and the flip-evaluator package is installed). One curve per method: traced raw, traced denoised (and both at half
resolution, AO and reflections), raster (raster points that no other raster setting beats in both time and error
are joined, the rest are plain markers).
Writes <out-dir>/<tag>_<effect>.png and prints a markdown table (with FLIP and the rays/s of traced passes).

Needs matplotlib and numpy; FLIP needs `pip install flip-evaluator` (skipped with a message otherwise).
Where the images cannot travel (the GPU machine), compute FLIP there and keep it in the JSON:
    scripts/plot_speed_vs_error.py R.json --images DIR --flip-into R.json --no-plots
and plot later from the JSON alone (stored flip_mean values are used when --images is not given).
"""
import argparse
import json
import os
import sys

METHODS = [  # key, legend, colour, marker
    ("traced_raw", "traced, raw", "tab:blue", "o"),
    ("traced_denoised", "traced, denoised (1 frame)", "tab:green", "s"),
    ("traced_half_raw", "traced half res, raw", "tab:cyan", "o"),
    ("traced_half_denoised", "traced half res, denoised (1 frame)", "tab:olive", "s"),
    ("raster", "raster", "tab:red", "^"),
]


def load_flip():
    try:
        import flip_evaluator  # noqa: F401
        return flip_evaluator
    except ImportError:
        return None


def flip_means(doc, images, flip):
    """Mean FLIP (LDR) of each row's PNG against its effect's reference PNG, over the mask's white pixels."""
    import numpy as np
    from PIL import Image  # pulled in by matplotlib's dependencies on most systems

    def load(path):
        return np.asarray(Image.open(path).convert("RGB"), dtype=np.float32) / 255.0

    out = {}
    for effect, e in doc["effects"].items():
        ref_rel = e["reference"].get("image")
        if not ref_rel:
            continue
        ref = load(os.path.join(images, ref_rel))
        mask_path = os.path.join(images, effect, "mask.png")
        mask = load(mask_path)[..., 0] > 0.5 if os.path.exists(mask_path) else np.ones(ref.shape[:2], bool)
        for row in e["rows"]:
            if not row.get("image"):
                continue
            test = load(os.path.join(images, row["image"]))
            error_map, _, _ = flip.evaluate(ref, test, "LDR", inputsRGB=True, applyMagma=False)
            error_map = np.asarray(error_map)
            if error_map.ndim == 3:
                error_map = error_map[..., 0]
            out[(effect, row["id"])] = float(error_map[mask].mean()) if mask.any() else float(error_map.mean())
    return out


def pareto(points):
    """Points (x, y, label) not beaten in both x and y by another, sorted by x."""
    pts = sorted(points, key=lambda p: (p[0], p[1]))
    front, best = [], float("inf")
    for p in pts:
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


def short_label(row):
    p = row.get("params", {})
    if row["method"] != "raster":
        return str(p.get("rays_per_pixel", ""))
    if "map_size" in p:
        return f"{p['map_size'] // 1024}k/{p['pcf_kernel']}"
    if "ssao_kernel" in p:
        return str(p["ssao_kernel"])
    if "probe_resolution" in p:
        return f"probe {p['probe_resolution']}" if p["probe_resolution"] else "sky"
    return row["setting"]


def plot_effect(plt, ticker, effect, e, flips, device, out_path, size):
    metrics = [("rmse", "RMSE vs reference")]
    if flips:
        metrics.append(("flip", "mean FLIP (LDR) vs reference"))
    xs = [("effect_ms", "GPU ms of the effect's passes"), ("frame_ms", "GPU ms of the whole frame")]
    fig, axes = plt.subplots(len(xs), len(metrics), figsize=(6.2 * len(metrics), 4.4 * len(xs)), squeeze=False)
    positive = [r[k] for r in e["rows"] for k, _ in xs if r[k] > 0]
    floor = min(positive) / 2 if positive else 1e-3
    for i, (xkey, xlabel) in enumerate(xs):
        for j, (ykey, ylabel) in enumerate(metrics):
            ax = axes[i][j]
            for key, legend, colour, marker in METHODS:
                pts = []
                for r in e["rows"]:
                    if r["method"] != key:
                        continue
                    y = r["rmse"] if ykey == "rmse" else flips.get((effect, r["id"]))
                    if y is None:
                        continue
                    pts.append((max(r[xkey], floor), max(y, 1e-6), short_label(r)))
                if not pts:
                    continue
                if key == "raster":
                    ax.scatter([p[0] for p in pts], [p[1] for p in pts], color=colour, marker=marker, alpha=0.45)
                    line = pareto(pts)
                else:
                    line = sorted(pts)
                ax.plot([p[0] for p in line], [p[1] for p in line], color=colour, marker=marker, label=legend)
                for x, y, label in pts:
                    ax.annotate(label, (x, y), textcoords="offset points", xytext=(4, 3), fontsize=7, color=colour)
            ax.set_xscale("log")
            ax.set_yscale("log")
            for axis in (ax.xaxis, ax.yaxis):  # plain numbers rather than 4x10^0
                axis.set_major_formatter(ticker.FormatStrFormatter("%g"))
                axis.set_minor_formatter(ticker.NullFormatter())
            ax.set_xlabel(xlabel + (" (0 ms plotted at %.3g)" % floor if any(r[xkey] <= 0 for r in e["rows"]) else ""))
            ax.set_ylabel(ylabel)
            ax.grid(True, which="both", alpha=0.3)
            if i == 0 and j == 0:
                ax.legend(fontsize=8)
    ref = e["reference"]
    fig.suptitle(f"{effect}: speed against error, {device}, {size}\n"
                 f"error on the {e['compared']}; reference {ref['rays_per_pixel']} rays/pixel", fontsize=10)
    fig.tight_layout()
    fig.savefig(out_path, dpi=110)
    plt.close(fig)


def markdown(doc, flips):
    raw = doc.get("raw_rate", {}).get("stress_grays_per_second")
    lines = ["| effect | method | setting | effect ms | frame ms | RMSE | bias | FLIP | Mrays/s (traced pass) |"
             + (" of raw rate |" if raw else ""),
             "|---|---|---|---:|---:|---:|---:|---:|---:|" + ("---:|" if raw else "")]
    for effect, e in doc["effects"].items():
        for r in e["rows"]:
            flip = flips.get((effect, r["id"]))
            trace = [p for name, p in r["passes"].items() if not name.endswith("_denoise")]
            rate = trace[0]["rays_per_second"] if trace else None
            cells = [effect, r["method"], r["setting"], f"{r['effect_ms']:.3f}", f"{r['frame_ms']:.3f}",
                     f"{r['rmse']:.5f}", f"{r['bias']:+.5f}", f"{flip:.4f}" if flip is not None else "",
                     f"{rate * 1e-6:.1f}" if rate else ""]
            if raw:
                cells.append(f"{rate / (raw * 1e9):.3f}" if rate else "")
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def import_matplotlib():
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import matplotlib.ticker as ticker
    except ImportError:
        sys.exit("plot_speed_vs_error.py: matplotlib is not installed (apt-get install python3-matplotlib)")
    return plt, ticker


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("results", help="JSON written by raybridge-effects-bench --out")
    ap.add_argument("--images", help="folder given to raybridge-effects-bench --images (for FLIP)")
    ap.add_argument("--out-dir", default=os.path.join(os.path.dirname(__file__), "..", "docs", "images", "effects"))
    ap.add_argument("--tag", help="file-name prefix, e.g. lavapipe or h100 (default: from the device)")
    ap.add_argument("--flip-into", metavar="JSON",
                    help="also write the results with each row's FLIP mean (flip_mean) to this file, so that "
                         "later plots need no images (may be RESULTS itself)")
    ap.add_argument("--no-plots", action="store_true",
                    help="with --flip-into: only compute FLIP (no matplotlib needed), e.g. on the GPU machine")
    args = ap.parse_args()

    with open(args.results) as f:
        doc = json.load(f)
    if args.no_plots and not (args.flip_into and args.images):
        sys.exit("plot_speed_vs_error.py: --no-plots needs --images and --flip-into")

    flips = {}
    if args.images:
        flip = load_flip()
        if flip is None:
            print("FLIP skipped: the flip-evaluator package is not installed (pip install flip-evaluator)",
                  file=sys.stderr)
        else:
            flips = flip_means(doc, args.images, flip)
    else:  # FLIP stored by an earlier --flip-into run (e.g. on the GPU machine, where the images stay)
        flips = {(effect, r["id"]): r["flip_mean"] for effect, e in doc["effects"].items() for r in e["rows"]
                 if r.get("flip_mean") is not None}
        if not flips:
            print("FLIP skipped: no --images folder given and no flip_mean in the JSON", file=sys.stderr)
    if args.flip_into:
        for effect, e in doc["effects"].items():
            for r in e["rows"]:
                if (effect, r["id"]) in flips:
                    r["flip_mean"] = flips[(effect, r["id"])]
        with open(args.flip_into, "w") as f:
            json.dump(doc, f, indent=2)
        print(f"wrote {args.flip_into} (FLIP means of {len(flips)} rows)", file=sys.stderr)
        if args.no_plots:
            return

    plt, ticker = import_matplotlib()
    device = doc["device"]["name"]
    tag = args.tag or ("lavapipe" if doc["device"].get("is_cpu") else device.split()[1].lower()
                       if len(device.split()) > 1 else "gpu")
    os.makedirs(args.out_dir, exist_ok=True)
    size = f"{doc['width']}x{doc['height']}"
    for effect, e in doc["effects"].items():
        path = os.path.join(args.out_dir, f"{tag}_{effect}.png")
        plot_effect(plt, ticker, effect, e, flips, device, path, size)
        print(f"wrote {path}", file=sys.stderr)
    print(markdown(doc, flips))


if __name__ == "__main__":
    main()
