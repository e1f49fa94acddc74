#!/usr/bin/env python3
"""The per-width tables of docs/medium.md, "Bullet given nscd's time".

    PYTHONPATH=build/python python3 docs/medium/equal_time_table.py EQUAL REPORT SETTLED FAMILY [X_S]

EQUAL is an equal-time sweep's folder (`equal_time`), REPORT the folder `confpack report EQUAL`
wrote, SETTLED the report folder of the settle sweep of the same family (`settle_with`), whose
Bullet runs stopped at their own time limit and were then brought to rest (or any folder whose
tables/ hold the same family's Bullet runs at their own limit, e.g. docs/medium for the study's own:
the at-rest column is then '-'); FAMILY is MSP, BSP or MPP and X_S the percentage of small grains
(default 0). Prints one Markdown row a width (side walls without friction): phi and Z of the bulk
region of nscd (REPORT), of Bullet at its time limit (SETTLED), of Bullet at nscd's time (REPORT)
and Z of Bullet brought to rest (SETTLED), each the mean ± standard error over the seeds, as
settle_table.py gives them, then the largest force ratio of Bullet's runs at nscd's time, lowest to
highest. A last line gives the time each width's Bullet runs were given [t0], lowest to highest.
"""
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from settle_table import family_runs, report_tables, stat, table_order, width_label, width_name  # noqa: E402

HEADER = ("| W | phi, nscd | phi, Bullet 20 t0 | phi, Bullet at nscd's time | Z, nscd | Z, Bullet 20 t0 "
          "| Z, Bullet at nscd's time | Z, Bullet at rest (settled) "
          "| force ratio, Bullet at nscd's time |")


def span(values, text):
    """'lowest to highest' of `values`, each written by `text`; one value alone."""
    low, high = text(min(values)), text(max(values))
    return low if low == high else f"{low} to {high}"


def ratio(v):
    return f"{v:.2f}" if v >= 0.01 else f"{v:.1e}"


def main(argv):
    if len(argv) not in (5, 6):
        sys.exit("usage: " + __doc__.strip().splitlines()[2].strip())
    sweep, report, settled, family = (pathlib.Path(argv[1]), pathlib.Path(argv[2]), pathlib.Path(argv[3]),
                                      argv[4])
    xs = float(argv[5]) if len(argv) == 6 else 0.0

    (phi, z), (settle_phi, settle_z) = report_tables(report, family, xs), report_tables(settled, family, xs)
    runs = family_runs(sweep, "bullet", family, xs)
    print(HEADER)
    print("|---" * 9 + "|")
    times = []
    for where in table_order(phi):
        # A width SETTLED lacks reads as one without seeds: stat() gives '-'.
        phi_s, z_s = settle_phi.get(where, {}), settle_z.get(where, {})
        cells = [width_label(where, phi[where], "bullet"), stat(phi[where], "nscd", 4), stat(phi_s, "bullet", 4),
                 stat(phi[where], "bullet", 4), stat(z[where], "nscd", 3), stat(z_s, "bullet", 3),
                 stat(z[where], "bullet", 3), stat(z_s, "bullet_settled", 3)]
        mine = runs.get(where, [])
        # A pile with no force (none yet touching) has no ratio: null in result.json.
        ratios = [r["equilibrium/max_force_ratio"] for r in mine if r["equilibrium/max_force_ratio"] is not None]
        cells.append(span(ratios, ratio) if ratios else "-")
        print("| " + " | ".join(cells) + " |")
        if mine:
            given_time = [r["timing/stages/dynamic/simulated_time"] for r in mine]
            times.append(f"{width_name(where)}: {span(given_time, lambda t: f'{t:.0f}')}")
    if times:
        print("Bullet's time at nscd's [t0]: " + "; ".join(times))


if __name__ == "__main__":
    try:
        main(sys.argv)
    except (OSError, KeyError, ValueError, RuntimeError) as e:
        sys.exit(f"equal_time_table.py: {e} (EQUAL and REPORT: an equal-time sweep's folder and its report's; "
                 "SETTLED: a settle sweep's report)")
