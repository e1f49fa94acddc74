#!/usr/bin/env python3
"""Where the falls of a sweep's nscd runs spend their solver iterations (docs/performance.md,
"What sets a medium run's cost").

Usage, after a sweep (or `confpack reproduce`) into SWEEP_DIR and a build with the Python module
(README, "Build and test"):
    PYTHONPATH=build/python python3 docs/validation/fall_cost.py SWEEP_DIR [--after T]

For every finished nscd run on the quasi-static protocol it reads result.json's timing history (one
entry per equilibrium check) and splits the fall at simulated time T (default 20 t0, by when a
medium pile has landed): after T the fall is the creep that ends it. Prints one Markdown row per
configuration (family and width; the median over its seeds): grains, the fall's end, its steps and
iterations, and for the creep the steps per t0, the iterations per step and per t0.
"""
import argparse
import statistics

import confpack.study


def creep_of(result, after):
    """(fall end t, fall steps, fall iterations, creep steps/t0, creep it/step, creep it/t0) or None."""
    timing = result.get("timing", {})
    fall = timing.get("stages", {}).get("dynamic")
    history = timing.get("history") or []
    if not fall or not history:
        return None
    creep = [e for e in history if e["steps"] <= fall["steps"] and e["time"] >= after]
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
    parser.add_argument("sweep_dir")
    parser.add_argument("--after", type=float, default=20.0, help="start of the creep [t0] (default 20)")
    args = parser.parse_args()
    try:
        runs = confpack.study.load(args.sweep_dir, details=True)
    except ValueError as e:  # not a sweep folder, or a run table that no longer holds
        raise SystemExit(f"fall_cost.py: {e}")
    groups = {}
    for run in runs:
        if run["backend"] != "nscd" or run["status"] != "done":
            continue
        row = creep_of(run["result"], args.after)
        if row is None:
            continue
        width = f"bi{run['W']:g}" if run["biperiodic"] else f"{run['W']:g}"
        configuration = f"{run['family']} x_S={run['x_S']:g} W={width} mu_w={run['mu_w']:g}"
        groups.setdefault(configuration, []).append((run["result"]["n_grains"],) + row)
    if not groups:
        raise SystemExit(f"fall_cost.py: no finished nscd run with a fall in {args.sweep_dir}")
    print(f"| configuration | runs | grains | fall ends at t | fall steps | fall iterations "
          f"| after t = {args.after:g}: steps per t0 | iterations per step | iterations per t0 |")
    print("|---|---|---|---|---|---|---|---|---|")
    for configuration, rows in groups.items():
        med = [statistics.median(column) for column in zip(*rows)]
        print(f"| {configuration} | {len(rows)} | {med[0]:,.0f} | {med[1]:.0f} | {med[2]:,.0f} | {med[3]:,.0f} "
              f"| {med[4]:.0f} | {med[5]:,.0f} | {med[6]:,.0f} |")


if __name__ == "__main__":
    main()
