#!/usr/bin/env python3
"""The per-width tables of docs/medium.md, "Bullet's piles brought to rest".

    PYTHONPATH=build/python python3 docs/medium/settle_table.py SWEEP REPORT FAMILY [X_S]

SWEEP is a settle sweep's folder (`settle_with`), REPORT the folder `confpack report SWEEP` wrote;
FAMILY is MSP, BSP or MPP and X_S the percentage of small grains (default 0). Prints one Markdown
row a width (side walls without friction): phi and Z of the bulk region, nscd, Bullet as it stopped
and Bullet at rest, each the mean ± standard error (std / sqrt(n); a lone seed's value alone) of
REPORT's tables/solid_fraction.csv and coordination.csv, and the grains' moves to rest: the mean
over the settled seeds of each settle's mean displacement, and the largest displacement of any of
them (the sweep's `bullet_settled` runs as confpack.study.load reads them, docs/python.md) [d_L].
A width with fewer settled Bullet seeds than nscd's says how many.
"""
import csv
import math
import pathlib
import sys

import confpack.study

HEADER = ("| W | phi, nscd | phi, Bullet as it stopped | phi, Bullet at rest | Z, nscd "
          "| Z, Bullet as it stopped | Z, Bullet at rest "
          "| grains moved to rest, mean / largest (d_L) |")
SIDES = ("nscd", "bullet", "bullet_settled")


def same_percentage(a, b):
    """Whether two x_S percentages (of a report table's CSV, of confpack.study.load, of the command
    line) are the same one, whichever of them went through a decimal string."""
    return abs(float(a) - float(b)) < 1e-9


def table_rows(path, key, family, xs):
    """{(W, biperiodic): row} of one report table's rows for `key`, `family` and `xs`."""
    rows = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            if row["key"] == key and row["family"] == family and same_percentage(row["x_S"], xs) and \
                    float(row["mu_w"]) == 0.0:
                rows[(float(row["W"]), row["biperiodic"] == "1")] = row
    return rows


def seeds(row, side):
    """How many seeds a report table's row averages for `side` (0 when it has none, or when the
    table has no such series, as a study without `settle_with` has no bullet_settled)."""
    return int(row.get(side + "_n") or 0)


def stat(row, side, digits):
    n = seeds(row, side)
    if n == 0:
        return "-"
    mean = float(row[side + "_mean"])
    if n == 1:
        return f"{mean:.{digits}f} (1 seed)"
    return f"{mean:.{digits}f} ± {float(row[side + '_std']) / math.sqrt(n):.{digits}f}"


def report_tables(folder, family, xs):
    """(phi rows, Z rows) of the tables/ of a report folder, by table_rows."""
    return (table_rows(folder / "tables" / "solid_fraction.csv", "solid_fraction", family, xs),
            table_rows(folder / "tables" / "coordination.csv", "coordination/Z", family, xs))


def width_name(where):
    return "biperiodic" if where[1] else f"{where[0]:g}"


def width_label(where, row, side):
    """The W cell: the width, and how many seeds `side` has where it has fewer than nscd's."""
    given, ran = seeds(row, side), seeds(row, "nscd")
    plural = "s" if given > 1 else ""
    return width_name(where) + (f" (Bullet: {given} seed{plural})" if 0 < given < ran else "")


def table_order(rows):
    """The widths of `rows` in the tables' order: walled widths rising, then the biperiodic box."""
    return sorted(rows, key=lambda w: (w[1], w[0]))


def family_runs(sweep, backend, family, xs):
    """{(W, biperiodic): [run]}: the sweep's runs of `backend` that are done, of `family` and `xs`,
    side walls without friction (as confpack.study.load reads them)."""
    runs = {}
    for run in confpack.study.load(sweep):
        if run["backend"] == backend and run["status"] == "done" and run["family"] == family \
                and same_percentage(run["x_S"], xs) and run["mu_w"] == 0.0:
            runs.setdefault((run["W"], run["biperiodic"]), []).append(run)
    return runs


def settle_moves(sweep, family, xs):
    """{(W, biperiodic): (mean displacement, largest displacement)} over the settled Bullet runs."""
    return {w: (sum(r["settle/mean_displacement"] for r in v) / len(v), max(r["settle/max_displacement"] for r in v))
            for w, v in family_runs(sweep, "bullet_settled", family, xs).items()}


def main(argv):
    if len(argv) not in (4, 5):
        sys.exit("usage: " + __doc__.strip().splitlines()[2].strip())
    sweep, report, family = pathlib.Path(argv[1]), pathlib.Path(argv[2]), argv[3]
    xs = float(argv[4]) if len(argv) == 5 else 0.0
    phi, z = report_tables(report, family, xs)
    moves = settle_moves(sweep, family, xs)
    print(HEADER)
    print("|---" * 8 + "|")
    for where in table_order(phi):
        # A Bullet run and its settle finish as one sweep run, so both Bullet columns have `settled`.
        width = width_label(where, phi[where], "bullet_settled")
        moved = moves.get(where)
        cells = [width] + [stat(phi[where], s, 4) for s in SIDES] + [stat(z[where], s, 3) for s in SIDES]
        cells.append(f"{moved[0]:.3f} / {moved[1]:.2f}" if moved else "-")
        print("| " + " | ".join(cells) + " |")


if __name__ == "__main__":
    try:
        main(sys.argv)
    except (OSError, KeyError, ValueError, RuntimeError) as e:
        sys.exit(f"settle_table.py: {e} (SWEEP and REPORT: a settle sweep's folder and its report's)")
