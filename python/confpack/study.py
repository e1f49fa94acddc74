"""A finished (or partly finished) sweep folder as a table (docs/sweeps.md): one row per run of
its run table, read by the C++ study code that the report uses.

    runs = confpack.study.load("out/study", array=True)
    walls = runs[(runs["status"] == "done") & ~runs["biperiodic"]]
    plt.plot(1 / walls["W"], walls["solid_fraction"], "o")

Configuration columns: run, deposit, family, status, shape, x_S (the small grains' volume
percentage, 25 for 25 %), W (wall gap, or the period when biperiodic), biperiodic, mu_w, seed,
backend. Result columns: every numeric leaf of result.json (booleans as 0/1), named by its path
joined with "/" ("solid_fraction", "coordination/Z", "equilibrium/reached"), None (NaN in the
array) where a run has no value.
"""
import json

import numpy as np

from . import _confpack

CONFIG_COLUMNS = ["run", "deposit", "family", "status", "shape", "x_S", "W", "biperiodic", "mu_w", "seed",
                  "backend"]


def _row(record):
    config = json.loads(record["config"])
    row = {
        "run": record["run"],
        "deposit": record["deposit"],
        "family": record["family"],
        "status": record["status"],
        "shape": config["population"]["shape"],
        "x_S": config["population"]["small_fraction"],
        "W": config["box"]["width"],
        "biperiodic": config["box"]["periodic_y"],
        # Studies written before the walls had their own object kept mu_w in the box.
        "mu_w": config["walls"]["friction"] if "walls" in config else config["box"]["wall_friction"],
        "seed": config["seed"],
        "backend": config["backend"],
    }
    row.update(record["values"])
    return row


def load(directory, array=False, details=False):
    """The runs of the sweep in `directory`, in run-table order: a list of dicts (array=False)
    or a numpy structured array (array=True; numbers as float64 with NaN for a missing value,
    text as str, biperiodic as bool). details=True adds, to the dicts only, "config" (the
    resolved configuration), "result" (result.json, None unless done) and "error" (of a failed
    run, else None)."""
    records = _confpack._load_study(str(directory))
    rows = [_row(r) for r in records]
    if details and not array:
        for row, r in zip(rows, records):
            row["config"] = json.loads(r["config"])
            row["result"] = json.loads(r["result"]) if r["result"] else None
            row["error"] = json.loads(r["error"]) if r["error"] else None
    if not array:
        return rows
    value_keys = sorted({k for r in records for k in r["values"]})
    dtype = [(c, _column_type(c, rows)) for c in CONFIG_COLUMNS] + [(k, "f8") for k in value_keys]
    table = np.zeros(len(rows), dtype=dtype)
    for i, row in enumerate(rows):
        for name, _ in dtype:
            value = row.get(name)
            table[name][i] = np.nan if value is None and name in value_keys else value
    return table


def _column_type(name, rows):
    if name == "biperiodic":
        return "?"
    if name in ("x_S", "W", "mu_w"):
        return "f8"
    if name == "seed":
        return "u8"
    width = max([len(str(r[name])) for r in rows] + [1])
    return f"U{width}"
