#!/usr/bin/env python3
"""What a run's last stretch to rest costs, after its solid fraction has stopped changing
(docs/performance.md, "The last contacts cost the most").

Usage, after `confpack run ... --out DIR` (any backend, any protocol):
    python3 docs/validation/settle_cost.py DIR/result.json [DIR2/result.json ...] [--within D]

It reads result.json's timing history (one entry per equilibrium check) and finds the first check
from which phi stays within D (default 1e-4) of its final value. Prints one Markdown row per run:
the time of that check and of the last (rest, if the run reached it), the steps and solver iterations after it (and their share of
the run's), the iterations a step before and after it, and Z at that check and at the end.
"""
import argparse
import json


def settle_of(history, within):
    """Index of the first check from which phi stays within `within` of the last check's."""
    final = history[-1]["solid_fraction"]
    k = len(history) - 1
    while k > 0 and abs(history[k - 1]["solid_fraction"] - final) <= within:
        k -= 1
    return k


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("results", nargs="+", help="result.json files")
    parser.add_argument("--within", type=float, default=1e-4, help="phi's band around its final value")
    args = parser.parse_args()
    print("| run | phi final from t | end at t | steps after | iterations after | "
          "iterations a step, before / after | Z then / at the end |")
    print("|---|---|---|---|---|---|---|")
    for path in args.results:
        with open(path) as f:
            history = json.load(f)["timing"]["history"]
        if len(history) < 2:
            print(f"| {path} | (fewer than two checks) | | | | | |")
            continue
        settled, last = history[settle_of(history, args.within)], history[-1]
        steps = last["steps"] - settled["steps"]
        iterations = last["iterations"] - settled["iterations"]
        before = settled["iterations"] / max(1, settled["steps"])
        after = iterations / max(1, steps)
        print(f"| {path} | {settled['time']:.1f} | {last['time']:.1f} | "
              f"{steps:,} ({steps / max(1, last['steps']):.0%}) | "
              f"{iterations:,} ({iterations / max(1, last['iterations']):.0%}) | "
              f"{before:,.0f} / {after:,.0f} | {settled['Z']:.3f} / {last['Z']:.3f} |")


if __name__ == "__main__":
    main()
