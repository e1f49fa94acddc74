#!/usr/bin/env python3
"""Compares the dynamic and quasi-static protocols on the runs docs/validation/run.sh wrote, or
two of nscd's preconditioners on those of COMPARE=preconditioners docs/validation/run.sh.

Usage: python3 docs/validation/compare.py OUT_DIR  (standard library only)

For each pile and each quantity: mean +- standard error over the seeds of each variant (protocol
or preconditioner), their difference +- its standard error, and whether the difference is within
two standard errors. Only seeds whose two runs both reached equilibrium are compared (the others
are counted).
"""
import csv
import json
import math
import pathlib
import sys

# The two variants a pile's runs compare, by the names of their folders (run.sh).
VARIANT_PAIRS = (("dynamic", "quasi-static"), ("sgs", "cholesky"), ("sgs", "switching"))


def force_stats(packing_path):
    """P(f/<f>) of the grain-grain contacts, summarised: fraction below 0.5, above 2, <(f/<f>)^2>."""
    contacts = json.loads(packing_path.read_text()).get("contacts") or []
    forces = [c["normal_force"] for c in contacts if c["b"] >= 0 and c["normal_force"] > 0.0]
    if not forces:
        return None
    mean = sum(forces) / len(forces)
    x = [f / mean for f in forces]
    return {
        "P(f/<f> < 0.5)": sum(v < 0.5 for v in x) / len(x),
        "P(f/<f> > 2)": sum(v > 2.0 for v in x) / len(x),
        "<(f/<f>)^2>": sum(v * v for v in x) / len(x),
    }


def wall_layer_phi(run_dir):
    """Mean phi(y) over the first d_L from the walls (walled boxes only)."""
    path = run_dir / "phi_y.csv"
    if not path.exists():
        return None
    rows = [r for r in csv.reader(line for line in path.read_text().splitlines() if not line.startswith("#"))]
    if len(rows) < 2:
        return None
    header, data = rows[0], rows[1:]
    y, phi = header.index("y"), header.index("phi")
    near = [float(r[phi]) for r in data if float(r[y]) <= 1.0]
    return sum(near) / len(near) if near else None


def quantities(run_dir):
    r = json.loads((run_dir / "result.json").read_text())
    q = {
        "phi": r["solid_fraction"],
        "Z": r["coordination"]["Z"],
        "rattler fraction": r["coordination"]["rattler_fraction"],
        "fabric anisotropy a": r["anisotropy"],
    }
    if r["coordination"].get("double") is not None and r["coordination"].get("triple"):
        for k in ("simple", "double", "triple"):
            q["Z_" + k[0]] = r["coordination"][k]
    fs = force_stats(run_dir / "packing.json")
    if fs:
        q.update(fs)
    wl = None if r["config"]["box"]["periodic_y"] else wall_layer_phi(run_dir)
    if wl is not None:
        q["phi(y < 1) near walls"] = wl
    return r, q


def mean_se(values):
    n = len(values)
    m = sum(values) / n
    if n < 2:
        return m, float("nan")
    var = sum((v - m) ** 2 for v in values) / (n - 1)
    return m, math.sqrt(var / n)


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: compare.py OUT_DIR")
    root = pathlib.Path(sys.argv[1])
    for pile_dir in sorted(p for p in root.iterdir() if p.is_dir()):
        # The pair whose two folders are there, else one with either (its runs are then counted missing).
        pair = next((p for p in VARIANT_PAIRS if all((pile_dir / v).is_dir() for v in p)), None) or next(
            (p for p in VARIANT_PAIRS if any((pile_dir / v).is_dir() for v in p)), None)
        if pair is None:
            continue
        first, second = pair
        runs = {}
        for variant in pair:
            for run in sorted((pile_dir / variant).glob("s*")):
                if (run / "result.json").exists():
                    runs.setdefault(run.name, {})[variant] = run
        both, values, cost, missed = [], {}, {first: [], second: []}, []
        for seed, pr in sorted(runs.items(), key=lambda kv: int(kv[0][1:])):
            if len(pr) < 2:
                continue
            res = {variant: quantities(d) for variant, d in pr.items()}
            for variant, (r, _) in res.items():
                cost[variant].append(r["timing"]["wall_s"])
            if not all(r["equilibrium"]["reached"] for r, _ in res.values()):
                missed.append(seed + "".join(f" {p}:{'yes' if r['equilibrium']['reached'] else 'no'}"
                                             for p, (r, _) in res.items()))
                continue
            both.append(seed)
            for variant, (_, q) in res.items():
                for k, v in q.items():
                    values.setdefault(k, {}).setdefault(variant, []).append(v)
        print(f"## {pile_dir.name}\n")
        print(f"Seeds compared (both at equilibrium): {len(both)} ({', '.join(both)}).")
        if missed:
            print(f"Left out (a run not at equilibrium): {'; '.join(missed)}.")
        for variant, c in cost.items():
            if c:
                c = sorted(c)
                print(f"Median wall time, {variant}: {c[len(c) // 2]:.1f} s over {len(c)} runs.")
        print()
        print(f"| quantity | {first} | {second} | difference | within 2 SE |")
        print("|---|---|---|---|---|")
        for k, per in values.items():
            if len(per.get(first, [])) < 2 or len(per.get(second, [])) < 2:
                continue
            md, sd = mean_se(per[first])
            mq, sq = mean_se(per[second])
            diff, se = mq - md, math.hypot(sd, sq)
            ok = "yes" if abs(diff) <= 2 * se else "no"
            print(f"| {k} | {md:.4g} ± {sd:.2g} | {mq:.4g} ± {sq:.2g} | {diff:+.3g} ± {se:.2g} | {ok} |")
        print()


if __name__ == "__main__":
    main()
