#!/usr/bin/env python3
"""Draws docs/validation.md's figures from the runs docs/validation/run.sh wrote.

Usage: python3 docs/validation/figures.py OUT_DIR PILE FIGURE_DIR  (standard library and gnuplot)

Writes FIGURE_DIR/PILE-forces.svg: P(f/<f>) of the grain-grain contacts, pooled over the seeds
whose two runs both reached equilibrium, one curve per protocol; and FIGURE_DIR/PILE-phi.svg:
the solid fraction of each such seed under both protocols.
"""
import json
import pathlib
import subprocess
import sys
import tempfile

BINS = [0.125 * k for k in range(41)]  # f/<f> from 0 to 5
TERMINAL = "svg size 640,420 font 'sans,12'"


def normalised_forces(run_dir):
    contacts = json.loads((run_dir / "packing.json").read_text()).get("contacts") or []
    forces = [c["normal_force"] for c in contacts if c["b"] >= 0 and c["normal_force"] > 0.0]
    mean = sum(forces) / len(forces)
    return [f / mean for f in forces]


def density(values):
    """Histogram of values on BINS as a probability density (values beyond the last bin are
    counted in the normalisation, not drawn)."""
    counts = [0] * (len(BINS) - 1)
    for v in values:
        k = int(v / (BINS[1] - BINS[0]))
        if k < len(counts):
            counts[k] += 1
    width = BINS[1] - BINS[0]
    return [(BINS[k] + width / 2, counts[k] / (len(values) * width)) for k in range(len(counts))]


def main():
    if len(sys.argv) != 4:
        sys.exit("usage: figures.py OUT_DIR PILE FIGURE_DIR")
    root, pile, figures = pathlib.Path(sys.argv[1]), sys.argv[2], pathlib.Path(sys.argv[3])
    protocols = ("dynamic", "quasi-static")
    seeds = []
    for run in sorted((root / pile / "dynamic").glob("s*"), key=lambda p: int(p.name[1:])):
        dirs = [root / pile / p / run.name for p in protocols]
        results = [d / "result.json" for d in dirs]
        if all(r.exists() and json.loads(r.read_text())["equilibrium"]["reached"] for r in results):
            seeds.append(run.name)
    if not seeds:
        sys.exit(f"figures.py: no seed of {pile} reached equilibrium with both protocols in {root}")
    figures.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        for p in protocols:
            pooled = [x for s in seeds for x in normalised_forces(root / pile / p / s)]
            (tmp / f"{p}.dat").write_text("".join(f"{x:.4f} {y:.6f}\n" for x, y in density(pooled)))
        phi = [[json.loads((root / pile / p / s / "result.json").read_text())["solid_fraction"] for p in protocols]
               for s in seeds]
        (tmp / "phi.dat").write_text("".join(f"{s[1:]} {a:.5f} {b:.5f}\n" for s, (a, b) in zip(seeds, phi)))
        script = f"""
set terminal {TERMINAL}
set output '{figures / (pile + "-forces.svg")}'
set title '{pile}: normal forces of the grain-grain contacts, {len(seeds)} seeds pooled'
set xlabel 'f / <f>'; set ylabel 'P(f / <f>)'; set logscale y; set key top right
plot '{tmp / "dynamic.dat"}' using 1:2 with linespoints title 'dynamic', \\
     '{tmp / "quasi-static.dat"}' using 1:2 with linespoints title 'quasi-static'
unset logscale y
set output '{figures / (pile + "-phi.svg")}'
set title '{pile}: solid fraction by seed'
set xlabel 'seed'; set ylabel 'phi'; set key outside right top
plot '{tmp / "phi.dat"}' using 1:2 with points pt 7 title 'dynamic', '' using 1:3 with points pt 5 title 'quasi-static'
"""
        subprocess.run(["gnuplot"], input=script, text=True, check=True)
    print(f"{figures / (pile + '-forces.svg')}, {figures / (pile + '-phi.svg')} ({len(seeds)} seeds)")


if __name__ == "__main__":
    main()
