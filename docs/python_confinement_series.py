#!/usr/bin/env python3
"""A small confinement series run from Python: monodisperse spheres between side walls W = 3,
4.5 and 6 d_L apart and the biperiodic reference (period 6), two seeds each, compacted with one
backend; prints phi per run and plots phi against d_L/W (biperiodic at d_L/W = 0).

    PYTHONPATH=build/python python3 docs/python_confinement_series.py --backend nscd --out phi.png

The boxes are those of `confpack reproduce --scale quick` (L_x = 4, h = 7). The short time limit
(--time-limit, 8 t0 by default, the Bullet limit of the quick scale) keeps the series to about a
minute on two cores and leaves the piles short of equilibrium: the numbers show the shape of the
study, not results. matplotlib is optional: without it the script prints the table only.
"""
import argparse

import confpack


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--backend", choices=["nscd", "bullet"], default="nscd")
    parser.add_argument("--time-limit", type=float, default=8.0, help="compaction time limit [t0]")
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--out", default="phi_vs_inverse_width.png", help="the figure (PNG)")
    args = parser.parse_args()

    series = [(w, False) for w in (3.0, 4.5, 6.0)] + [(6.0, True)]
    points = []  # (d_L / W, phi)
    print(f"{'W':>5} {'biperiodic':>10} {'seed':>4} {'grains':>6} {'phi':>8}  equilibrium")
    for width, periodic in series:
        for seed in range(1, args.seeds + 1):
            config = {
                "box": {"length_x": 4, "width": width, "periodic_y": periodic, "height": 7},
                "compaction": {"time_limit": args.time_limit},
                "seed": seed,
            }
            result = confpack.run(config, backend=args.backend)
            phi = result["solid_fraction"]
            points.append((0.0 if periodic else 1.0 / width, phi))
            print(f"{width:5.1f} {str(periodic):>10} {seed:4d} {result['n_grains']:6d} {phi:8.4f}  "
                  f"{'reached' if result['equilibrium']['reached'] else 'not reached'}")

    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no figure")
        return
    x, phi = zip(*points)
    plt.plot(x, phi, "o")
    plt.xlabel("d_L / W")
    plt.ylabel("solid fraction phi (bulk)")
    plt.title(f"confinement series, {args.backend}, {args.time_limit:g} t0")
    plt.savefig(args.out, dpi=120)
    print(f"figure -> {args.out}")


if __name__ == "__main__":
    main()
