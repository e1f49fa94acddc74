#!/usr/bin/env python3
"""Where the falls of a sweep's nscd runs spend their solver iterations (docs/performance.md,
"What sets a medium run's cost").

Usage, after a sweep (or `confpack reproduce`) into SWEEP_DIR:
    python3 docs/validation/fall_cost.py SWEEP_DIR [--after T]

For every finished nscd run on the quasi-static protocol it reads result.json's timing history (one
entry per equilibrium check) and splits the fall at simulated time T (default 20 t0, by when a
medium pile has landed): after T the fall is the creep that ends it. Prints one Markdown row per
configuration (family and width; the median over its seeds): grains, the fall's end, its steps and
iterations, and for the creep the steps per t0, the iterations per step and per t0.
"""
import argparse
import json
import statistics
import sys
from pathlib import Path


def creep_of(result, after):
    """(fall end t, fall steps, fall iterations, creep steps/t0, creep it/step, creep it/t0) or None."""
    timing = result.get("timing", {})
    fall = timing.get("stages", {}).get("dynamic")
    history = timing.get("history") or []
    if not fall or not history:
        return None
    inside = [e for e in history if e["steps"] <= fall["steps"]]
    creep = [e for e in inside if e["time"] >= after]
    if len(creep) < 2:
        return None
    first, last = creep[0], creep[-1]
    steps = last["steps"] - first["steps"]
    iterations = last["iterations"] - first["iterations"]
    span = last["time"] - first["time"]
    if steps <= 0 or span <= 0:
        return None
    return (fall["simulated_time"], fall["steps"], fall["iterations"], steps / span, iterations / steps,
            iterations / span)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sweep_dir", type=Path)
    parser.add_argument("--after", type=float, default=20.0, help="start of the creep [t0] (default 20)")
    args = parser.parse_args()
    runs = args.sweep_dir / "runs"
    if not runs.is_dir():
        sys.exit(f"fall_cost.py: {runs} is not a folder: give a sweep folder (made by confpack sweep)")
    groups = {}
    for done in sorted(runs.glob("*/done.json")):
        label = json.loads(done.read_text()).get("label", "")
        result_file = done.parent / "result.json"
        if not label.endswith(" nscd") or not result_file.exists():
            continue
        result = json.loads(result_file.read_text())
        row = creep_of(result, args.after)
        if row is None:
            continue
        # "MSP xS=0 W=10 mu=0 s2 nscd" -> configuration "MSP xS=0 W=10 mu=0"
        configuration = " ".join(label.split()[:-2])
        groups.setdefault(configuration, []).append((result["n_grains"],) + row)
    if not groups:
        sys.exit(f"fall_cost.py: no finished nscd run with a fall in {runs}")
    print(f"| configuration | runs | grains | fall ends at t | fall steps | fall iterations "
          f"| after t = {args.after:g}: steps per t0 | iterations per step | iterations per t0 |")
    print("|---|---|---|---|---|---|---|---|---|")
    for configuration, rows in groups.items():
        med = [statistics.median(column) for column in zip(*rows)]
        print(f"| {configuration} | {len(rows)} | {med[0]:,.0f} | {med[1]:.0f} | {med[2]:,.0f} | {med[3]:,.0f} "
              f"| {med[4]:.0f} | {med[5]:,.0f} | {med[6]:,.0f} |")


if __name__ == "__main__":
    main()
