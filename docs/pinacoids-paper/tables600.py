#!/usr/bin/env python3
"""The tables of docs/pinacoids-and-the-paper.md, "A larger pile, and the walls" and "The
paper-like model on the larger piles", from the sweep folder of
docs/examples/pinacoids-paper-600.json and the inflated readings of its exact piles.

    python3 docs/pinacoids-paper/tables600.py SWEEPDIR [INFLATEDIR] [--csv DIR] > tables.md

Every value is the mean over the seeds +- its standard error (sample standard deviation / sqrt(n)).
C is the weighted least-squares fit phi(W) = phi_bulk - C/W through W = 5, 10 and the biperiodic
box at 1/W = 0, each point weighted by its standard error (numpy.polyfit with w = 1/sigma and the
covariance unscaled). INFLATEDIR holds `confpack analyze --inflate S --type-band 0.035` folders
named rNNNN-S (S = 1.00 to 1.07) for the exact model's runs. With --csv DIR it also writes the
figure's data, the biperiodic means: DIR/variants600.csv (a model's phi and its largest exact
interpenetration) and DIR/inflation600.csv (S, phi, its error and the exact interpenetration).
"""
import argparse
import csv
import json
import math
from collections import defaultdict
from pathlib import Path

import numpy as np


def load(path):
    with open(path) as f:
        return json.load(f)


def variant(config):
    """The model of a run, as the tables name it."""
    c = config["compaction"]
    o = config.get("backend_options", {})
    if c.get("protocol") == "quasi-static":
        return "exact model, quasi-static (today)"
    law = o.get("contact_law", "gap")
    detection = o.get("contact_detection", "exact")
    dt = c.get("dt")
    name = {("gap", "exact"): "exact model", ("velocity", "exact"): "velocity law",
            ("gap", "common_plane"): "common-plane detection",
            ("velocity", "common_plane"): "both (paper-like)"}[(law, detection)]
    return f"{name}, dt {dt:g}"


def width(config):
    box = config["box"]
    return "biperiodic" if box.get("periodic_y") else int(round(box["width"]))


def stat(values):
    v = np.asarray([x for x in values if x is not None and math.isfinite(x)], dtype=float)
    if v.size == 0:
        return (math.nan, math.nan, 0)
    se = v.std(ddof=1) / math.sqrt(v.size) if v.size > 1 else math.nan
    return (v.mean(), se, v.size)


def text(s, digits=4):
    mean, se, n = s
    if n == 0:
        return "-"
    return f"{mean:.{digits}f} ± {se:.{digits}f}" if math.isfinite(se) else f"{mean:.{digits}f}"


def quantities(result):
    z = result["coordination"]
    band = result.get("coordination_band") or {}
    return {
        "phi": result["solid_fraction"],
        "interp": result["interpenetration_percent"]["exact"],
        "Z": z["Z"], "Zs": z["simple"], "Zd": z["double"], "Zt": z["triple"],
        "constraints": z["simple"] + 2 * z["double"] + 3 * z["triple"],
        "nematic": result["nematic"]["bulk"],
        "rest": result["equilibrium"]["reached"],
        "Zt_band": band.get("triple"), "constraints_band": band.get("constraints"),
        "lattice_min": result["interpenetration_percent"].get("lattice_min"),
        "lattice_max": result["interpenetration_percent"].get("lattice_max"),
        "t": result["equilibrium"].get("simulated_time"),
        "wall_s": result.get("timing", {}).get("wall_s"),
    }


def fit_c(points):
    """phi(W) = phi_bulk - C/W, weighted; points: (1/W, mean, se). Returns phi_bulk, C and their errors."""
    x = np.array([p[0] for p in points])
    y = np.array([p[1] for p in points])
    s = np.array([p[2] for p in points])
    coef, cov = np.polyfit(x, y, 1, w=1.0 / s, cov="unscaled")
    chi2 = float(np.sum(((y - np.polyval(coef, x)) / s) ** 2))
    return coef[1], math.sqrt(cov[1, 1]), -coef[0], math.sqrt(cov[0, 0]), chi2


def c_row(label, groups):
    """A row of a C table: phi at W = 5, 10 and biperiodic (groups: width -> [quantities]) and the fit."""
    points, cells = [], []
    for w in (5, 10, "biperiodic"):
        q = groups.get(w)
        s = stat(r["phi"] for r in q) if q else (math.nan, math.nan, 0)
        cells.append(text(s))
        if s[2] >= 2:
            points.append((0.0 if w == "biperiodic" else 1.0 / w, s[0], s[1]))
    if len(points) < 3:
        return None
    bulk, bulk_se, c, c_se, chi2 = fit_c(points)
    return f"| {label} | {' | '.join(cells)} | {bulk:.4f} ± {bulk_se:.4f} | {c:.3f} ± {c_se:.3f} | {chi2:.2f} |"


def write_csv(path, header, rows):
    with open(path, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(header)
        out.writerows(rows)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sweep", type=Path)
    parser.add_argument("inflated", type=Path, nargs="?")
    parser.add_argument("--csv", type=Path, help="write the figure's data here")
    args = parser.parse_args()
    sweep = args.sweep
    runs = defaultdict(list)  # (variant, width) -> [quantities]
    for done in sorted(sweep.glob("runs/r*/done.json")):
        run = done.parent
        config = load(run / "config.json")
        runs[(variant(config), width(config))].append(quantities(load(run / "result.json")))

    variants = list(dict.fromkeys(v for v, _ in runs))
    print("## Biperiodic piles\n")
    print("| model | runs | at rest | phi | interpenetration, exact, largest [%] | Z | Z_s | Z_d | Z_t "
          "| Z_s + 2 Z_d + 3 Z_t | nematic, bulk | t [t0] | wall time [s] |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    variant_rows = []
    for v in variants:
        q = runs.get((v, "biperiodic"))
        if not q:
            continue
        phi, interp_max = stat(r["phi"] for r in q), max(r["interp"] for r in q)
        variant_rows.append([v, f"{phi[0]:.5f}", f"{interp_max:.3e}"])
        col = lambda k, d=2: text(stat(r[k] for r in q), d)
        print(f"| {v} | {len(q)} | {sum(r['rest'] for r in q)} | {text(phi, 4)} | "
              f"{interp_max:.1e} | {col('Z')} | {col('Zs')} | {col('Zd')} | {col('Zt')} | "
              f"{col('constraints')} | {col('nematic', 3)} | {col('t', 0)} | {col('wall_s', 0)} |")

    print("\n## The walls: C\n")
    print("| model | phi, W = 5 | phi, W = 10 | phi, biperiodic | phi_bulk (fit) | C [d_L] | chi² (1 dof) |")
    print("|---|---|---|---|---|---|---|")
    for v in variants:
        row = c_row(v, {w: runs.get((v, w)) for w in (5, 10, "biperiodic")})
        if row:
            print(row)

    if args.csv:
        write_csv(args.csv / "variants600.csv", ["model", "phi", "interp_exact_max"], variant_rows)

    if args.inflated:
        inflated = defaultdict(list)  # (width, S) -> [quantities]
        for result in sorted(args.inflated.glob("r*-*/result.json")):
            run, scale = result.parent.name.split("-")
            w = width(load(sweep / "runs" / run / "config.json"))
            inflated[(w, scale)].append(quantities(load(result)))
        scales = sorted({s for _, s in inflated})
        print("\n## The exact biperiodic piles inflated (band 0.035 d)\n")
        print("| S | phi | interpenetration, exact [%] | lattice bounds [%] | Z | Z_t exact | Z_t band "
              "| Z_s + 2 Z_d + 3 Z_t band |")
        print("|---|---|---|---|---|---|---|---|")
        inflation_rows = []
        for s in scales:
            q = inflated.get(("biperiodic", s))
            if not q:
                continue
            phi, interp = stat(r["phi"] for r in q), stat(r["interp"] for r in q)
            inflation_rows.append([s, f"{phi[0]:.5f}", f"{phi[1]:.5f}", f"{interp[0]:.4f}"])
            col = lambda k, d=2: text(stat(r[k] for r in q), d)
            print(f"| {s} | {text(phi, 4)} | {text(interp, 2)} | {np.mean([r['lattice_min'] for r in q]):.2f}, "
                  f"{np.mean([r['lattice_max'] for r in q]):.2f} | {col('Z')} | {col('Zt')} | {col('Zt_band')} | "
                  f"{col('constraints_band')} |")
        print("\n## The exact piles inflated: C\n")
        print("| S | phi, W = 5 | phi, W = 10 | phi, biperiodic | phi_bulk (fit) | C [d_L] | chi² (1 dof) |")
        print("|---|---|---|---|---|---|---|")
        for s in scales:
            row = c_row(s, {w: inflated.get((w, s)) for w in (5, 10, "biperiodic")})
            if row:
                print(row)
        if args.csv:
            write_csv(args.csv / "inflation600.csv", ["S", "phi", "phi_se", "interp_exact"], inflation_rows)


if __name__ == "__main__":
    main()
