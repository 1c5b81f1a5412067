#!/usr/bin/env python3
"""Merges motion-benchmark JSONs of the same build and plan that ran different ray counts (raybridge-effects-bench
--scenario motion --motion-rays ...; scripts/gpu/run_remote.sh motion runs one set per call to stay inside the device
tool's 10-minute limit) into one document: the first file's, with every case's per-ray-count results and change-mask
timings from all of them, and "merged_from" naming each run.

    scripts/merge_motion.py OUT.json RUN1.json RUN2.json ...
"""
import json
import sys


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    out, runs = argv[0], [json.load(open(p)) for p in argv[1:]]
    doc = runs[0]
    by_name = {c["name"]: c for c in doc["motion"]["cases"]}
    for run in runs[1:]:
        if run["width"] != doc["width"] or run["height"] != doc["height"]:
            print(f"{out}: runs of different sizes cannot be merged", file=sys.stderr)
            return 1
        for case in run["motion"]["cases"]:
            into = by_name.get(case["name"])
            if into is None:
                print(f"{out}: case {case['name']} is not in the first run", file=sys.stderr)
                return 1
            into["rays"].update(case["rays"])
            for key in ("change_masks_gpu_ms_median", "change_masks_frames"):
                if key in case:
                    into.setdefault(key, {}).update(case[key])
        doc["checks_passed"] = doc["checks_passed"] and run["checks_passed"]
    rays = sorted({int(r) for c in doc["motion"]["cases"] for r in c["rays"]})
    doc["motion"]["plan"]["rays"] = rays
    doc["merged_from"] = [
        {"date": r["date"], "command_line": r["command_line"], "seconds": r["seconds"], "rays": r["motion"]["plan"]["rays"]}
        for r in runs
    ]
    with open(out, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")
    print(f"{out}: {len(runs)} runs, rays {rays}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
