#!/usr/bin/env python3
"""Plots raybridge-effects-bench --scenario motion results: how the temporal denoisers cope with motion and events.

    /usr/bin/python3 scripts/plot_motion.py RESULTS.json [--images DIR] [--out-dir docs/images/motion] [--tag lavapipe]

Writes, per run (one subplot per effect: shadows, ao, reflections, local_lights):
  <out-dir>/<tag>_lag.png      RMSE over the pixels an event changed (teleport, lamp_jump) against frames after the
                               event (0 = the event frame), denoised (solid) and the still control on the same
                               pixels (dashed), one line per event case and ray count; the legend gives the lag;
  <out-dir>/<tag>_summary.png  mean RMSE of every case, denoised (solid bars) against raw (hatched), per ray count;
  <out-dir>/<tag>_strip.png    only with --images (the folder given to the bench's --images): the teleport strip,
                               rows raw / denoised / reference of shadows, ao and reflections, columns frames -1, 0,
                               +1, +2 relative to the teleport;
and prints a markdown table: one row per case, effect and ray count (RMSE denoised and raw, flicker ratio, RMSE of
disoccluded pixels, lag frames of event cases, moving/at-rest ratio of steady and camera cases, denoise GPU ms).

Needs matplotlib and numpy: run it with a Python that has them (Debian: python3-matplotlib, /usr/bin/python3).
"""
import argparse
import json
import math
import os
import sys

EFFECTS = ["shadows", "ao", "reflections", "local_lights"]
STRIP_EFFECTS = ["shadows", "ao", "reflections"]
STRIP_ROWS = ["raw", "denoised", "reference"]
STRIP_FRAMES = [-1, 0, 1, 2]
MARKERS = ["o", "s", "^", "D", "v", "P"]


def fmt(x):
    """4 significant digits (trailing zeros kept); n/a for missing values."""
    return "n/a" if x is None else "0" if x == 0 else f"{x:#.4g}".rstrip(".")


def nrays(r):
    return f"{r} ray" + ("" if str(r) == "1" else "s")


def ray_counts(cases):
    return sorted({int(r) for c in cases for r in c["rays"]})


def effects_of(cases):
    present = {e for c in cases for per in c["rays"].values() for e in per}
    return [e for e in EFFECTS if e in present] + sorted(present - set(EFFECTS))


def grid(plt, n, cell=(5.6, 3.6)):
    cols = 2 if n > 1 else 1
    rows = max(1, math.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(cell[0] * cols, cell[1] * rows), squeeze=False)
    axes = [a for row in axes for a in row]
    for ax in axes[n:]:
        ax.set_visible(False)
    return fig, axes


def log_y(ax, ticker):
    """Log y axis with plain numbers (0.03, not 3x10^-2); labels 2, 3 and 5 in between when under 1.5 decades."""
    ax.set_yscale("log")
    lo, hi = ax.get_ylim()
    plain = ticker.FuncFormatter(lambda y, _: f"{y:g}")
    few = ticker.FuncFormatter(lambda y, _: f"{y:g}" if f"{y:.0e}"[0] in "235" else "")
    ax.yaxis.set_major_formatter(plain)
    ax.yaxis.set_minor_formatter(few if hi > 0 and lo > 0 and hi / lo < 10 ** 1.5 else ticker.NullFormatter())
    ax.tick_params(axis="y", which="both", labelsize=7)


def plot_lag(plt, ticker, doc, effects, title, path):
    cases = [c for c in doc["motion"]["cases"] if any("event" in E for per in c["rays"].values() for E in per.values())]
    if not cases:
        return False
    rays = ray_counts(cases)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    fig, axes = grid(plt, len(effects), cell=(5.6, 4.4))
    for ax, effect in zip(axes, effects):
        notes = {}
        for ci, case in enumerate(cases):
            for ri, r in enumerate(rays):
                ev = case["rays"].get(str(r), {}).get(effect, {}).get("event")
                if not ev:
                    continue
                if not ev.get("changed_pixels"):
                    notes.setdefault(case["name"], []).append(str(r))
                    continue
                pos = lambda v: [y if y and y > 0 else float("nan") for y in v]  # noqa: E731 (log scale)
                after, still = pos(ev["rmse_changed_after_event"]), pos(ev["rmse_changed_still"])
                lag = ev.get("lag_frames")
                lag = str(lag) if lag is not None else f"> {len(after) - 1}"
                style = dict(color=colours[ci % len(colours)], marker=MARKERS[ri % len(MARKERS)], markersize=4)
                ax.plot(range(len(after)), after, "-", **style,
                        label=f"{case['name']}, {nrays(r)} ({ev['changed_pixels']} px, lag {lag})")
                ax.plot(range(len(still)), still, "--", alpha=0.6, **style)
        log_y(ax, ticker)
        none = "; ".join(f"{name} at {', '.join(rs)} rays" for name, rs in notes.items())
        ax.set_title(effect + (f" (no pixel changed: {none})" if none else ""), fontsize=9)
        ax.set_xlabel("frames after the event (0 = event frame)", fontsize=8)
        ax.xaxis.get_major_locator().set_params(integer=True)
        ax.set_ylabel("RMSE over the changed pixels", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(True, which="both", alpha=0.3)
        if ax.lines:
            ax.legend(fontsize=7, title="solid: denoised; dashed: still control, same pixels", title_fontsize=7,
                      loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False)
        else:
            ax.text(0.5, 0.5, "no event changed a pixel", ha="center", transform=ax.transAxes, fontsize=8)
            ax.set_yticks([], minor=True)
            ax.set_yticks([])
    fig.suptitle(f"Denoised error after an event\n{title}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def plot_summary(plt, ticker, doc, effects, title, path):
    cases = doc["motion"]["cases"]
    rays = ray_counts(cases)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    fig, axes = grid(plt, len(effects), cell=(max(5.6, 0.8 * len(cases)), 3.6))
    width = 0.8 / max(1, 2 * len(rays))
    for ax, effect in zip(axes, effects):
        for ri, r in enumerate(rays):
            for k, (key, hatch, alpha) in enumerate([("rmse_mean", None, 0.9), ("rmse_raw_mean", "///", 0.4)]):
                xs, ys = [], []
                for i, case in enumerate(cases):
                    E = case["rays"].get(str(r), {}).get(effect)
                    if E and E.get(key) is not None:
                        xs.append(i - 0.4 + (2 * ri + k + 0.5) * width)
                        ys.append(max(E[key], 1e-6))
                label = f"{nrays(r)}, {'denoised' if k == 0 else 'raw'}"
                ax.bar(xs, ys, width, color=colours[ri % len(colours)], alpha=alpha, hatch=hatch,
                       edgecolor=colours[ri % len(colours)], label=label)
        log_y(ax, ticker)
        ax.set_xticks(range(len(cases)))
        ax.set_xticklabels([c["name"] for c in cases], fontsize=8, rotation=20)
        ax.set_title(effect, fontsize=10)
        ax.set_ylabel("mean RMSE vs reference", fontsize=8)
        ax.grid(True, axis="y", which="both", alpha=0.3)
    fig.legend(*axes[0].get_legend_handles_labels(), loc="lower center", ncol=2 * len(rays), fontsize=8, frameon=False)
    fig.suptitle(f"Mean RMSE per case, denoised against raw\n{title}", fontsize=10)
    fig.tight_layout(rect=(0, 0.35 / fig.get_figheight(), 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_strip(plt, images, rays, title, path):
    """Grid of the teleport PNGs at exact pixel positions; returns False when no image was found."""
    import matplotlib.image as mpimg
    folder = os.path.join(images, "motion")
    effects = [e for e in STRIP_EFFECTS if os.path.exists(os.path.join(folder, e, "teleport_raw_f0.png"))]
    if not effects:
        return False
    first = mpimg.imread(os.path.join(folder, effects[0], "teleport_raw_f0.png"))
    cell_w = first.shape[1] if 160 <= first.shape[1] <= 320 else 240  # native size, else scaled to 240 px
    cell_h = round(cell_w * first.shape[0] / first.shape[1])
    left, top, gap, group_gap = 78, 42, 3, 10
    rows = len(effects) * len(STRIP_ROWS)
    width = left + len(STRIP_FRAMES) * (cell_w + gap)
    height = top + rows * (cell_h + gap) + (len(effects) - 1) * group_gap + 4
    dpi = 100
    fig = plt.figure(figsize=(width / dpi, height / dpi), dpi=dpi, facecolor="white")
    fig.text(0.5, 1 - 6 / height, f"Teleport strip, {nrays(rays)} per pixel, {title}", ha="center", va="top", fontsize=8)
    for gi, effect in enumerate(effects):
        for ri, kind in enumerate(STRIP_ROWS):
            y = top + (gi * len(STRIP_ROWS) + ri) * (cell_h + gap) + gi * group_gap
            for fi, f in enumerate(STRIP_FRAMES):
                x = left + fi * (cell_w + gap)
                ax = fig.add_axes([x / width, 1 - (y + cell_h) / height, cell_w / width, cell_h / height])
                ax.set_xticks([])
                ax.set_yticks([])
                p = os.path.join(folder, effect, f"teleport_{kind}_f{f}.png")
                if os.path.exists(p):
                    img = mpimg.imread(p)
                    ax.imshow(img, cmap="gray" if img.ndim == 2 else None, vmin=0, vmax=1, interpolation="nearest")
                else:
                    ax.text(0.5, 0.5, "missing", ha="center", va="center", fontsize=7, transform=ax.transAxes)
                if gi == 0 and ri == 0:
                    ax.set_title(f"frame {f:+d}" + (" (teleport)" if f == 0 else ""), fontsize=7, pad=2)
                if fi == 0:
                    ax.set_ylabel(f"{effect}\n{kind}", fontsize=7, rotation=0, ha="right", va="center")
    fig.savefig(path, dpi=dpi, facecolor="white")
    plt.close(fig)
    return True


def markdown(doc):
    lines = ["| case | effect | rays | RMSE denoised | RMSE raw | flicker ratio | disocclusion RMSE | lag frames |"
             " steady ratio | pixels | denoise GPU ms |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    cases = doc["motion"]["cases"]
    for case in cases:
        for r in ray_counts([case]):
            per = case["rays"][str(r)]
            for effect in effects_of([case]):
                E = per.get(effect)
                if E is None:
                    continue
                lag, steady, pixels = "", "", ""
                if "event" in E:
                    ev = E["event"]
                    pixels = str(ev.get("changed_pixels", ""))
                    if not ev.get("changed_pixels"):
                        lag = "n/a"
                    elif ev.get("lag_frames") is None:
                        lag = f"> {len(ev.get('rmse_changed_after_event', [])) - 1}"
                    else:
                        lag = str(ev["lag_frames"])
                if "steady" in E:
                    steady, pixels = fmt(E["steady"].get("ratio")), str(E["steady"].get("pixels", ""))
                cells = [case["name"], effect, str(r), fmt(E.get("rmse_mean")), fmt(E.get("rmse_raw_mean")),
                         fmt(E.get("flicker_ratio")), fmt(E.get("disocclusion_rmse_mean")), lag, steady, pixels,
                         fmt(E.get("denoise_gpu_ms_median"))]
                lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("results", help="JSON written by raybridge-effects-bench --scenario motion --out")
    ap.add_argument("--images", help="folder given to raybridge-effects-bench --images (for the teleport strip)")
    ap.add_argument("--out-dir", default=os.path.join(os.path.dirname(__file__), "..", "docs", "images", "motion"))
    ap.add_argument("--tag", help="file-name prefix, e.g. lavapipe or h100 (default: from the device)")
    args = ap.parse_args()

    with open(args.results) as f:
        doc = json.load(f)
    if not doc.get("motion", {}).get("cases"):
        sys.exit(f"plot_motion.py: {args.results} has no motion cases (run the bench with --scenario motion)")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import matplotlib.ticker as ticker
    except ImportError:
        sys.exit("plot_motion.py: matplotlib is not installed (Debian: apt-get install python3-matplotlib, "
                 "then run it with /usr/bin/python3)")

    device = doc.get("device", {}).get("name", "unknown device")
    tag = args.tag or ("lavapipe" if doc.get("device", {}).get("is_cpu") else device.split()[1].lower()
                       if len(device.split()) > 1 else "gpu")
    title = f"{device}, {doc.get('width')}x{doc.get('height')}, {doc.get('date', '')[:10]}"
    effects = effects_of(doc["motion"]["cases"])
    os.makedirs(args.out_dir, exist_ok=True)
    out = lambda name: os.path.join(args.out_dir, f"{tag}_{name}.png")  # noqa: E731
    written = []
    if plot_lag(plt, ticker, doc, effects, title, out("lag")):
        written.append(out("lag"))
    else:
        print("lag plot skipped: no event case (teleport, lamp_jump) in the results", file=sys.stderr)
    plot_summary(plt, ticker, doc, effects, title, out("summary"))
    written.append(out("summary"))
    if args.images:
        plan = doc["motion"].get("plan", {})
        rays = plan.get("strip_rays") or (plan.get("rays") or ["?"])[1 if len(plan.get("rays", [])) > 1 else 0]
        if plot_strip(plt, args.images, rays, title, out("strip")):  # the bench's strip uses its 2nd ray count
            written.append(out("strip"))
        else:
            print(f"strip skipped: no {args.images}/motion/<effect>/teleport_*.png", file=sys.stderr)
    for p in written:
        print(f"wrote {p}", file=sys.stderr)
    print(markdown(doc))


if __name__ == "__main__":
    main()
