"""Drop a part made from a NumPy hull 200 times on a belt and print how often it comes to rest
in each stable pose (thesis §7.5): the quasi-static and perturbed estimates beside the drops.

    pip install ./crates/impulse-py        # once; matplotlib too for the plot
    python examples/python/drop_parts.py [--drops 200] [--shards 4] [--dask] [--plot poses.png]

With --dask the drops run as Dask tasks on a local cluster (impulse.distributed); the table is
the same, drop for drop, as in one process.
"""

import argparse

import numpy as np

import impulse


def wedge():
    """A 3 × 2 × 1 cm wedge with one corner cut off: a hull of 10 points, in metres."""
    return 0.01 * np.array([
        [0, 0, 0], [3, 0, 0], [3, 2, 0], [0, 2, 0],     # bottom
        [0, 0, 1], [0, 2, 1], [1.5, 0, 1], [1.5, 2, 1],  # top, cut back
        [3, 0, 0.3], [3, 2, 0.3],                        # the cut face's lower edge
    ])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--drops", type=int, default=200)
    ap.add_argument("--shards", type=int, default=4)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--dask", action="store_true", help="run the shards on a local Dask cluster")
    ap.add_argument("--plot", help="write a bar chart here (needs matplotlib)")
    args = ap.parse_args()

    part = impulse.PosePart.new("wedge", points=wedge(), density=1050.0)  # ABS plastic
    props = impulse.mass_properties(*impulse.convex_hull(wedge()), density=1050.0)
    print(f"part: {part.name}, {props.mass * 1e3:.2f} g, centre of mass {props.com * 100} cm, "
          f"{len(part.stable_facets())} stable facets")

    if args.dask:
        from dask.distributed import Client, LocalCluster

        from impulse.distributed import pose_study

        with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as c:
            study = pose_study(part, args.drops, args.shards, seed=args.seed, client=c)
    else:
        shards = [impulse.run_pose_shard(part, args.drops, seed=args.seed,
                                         shard=(k, args.shards)) for k in range(args.shards)]
        study = impulse.merge_pose_studies(shards)

    s = impulse.pose_summary(part, study)
    print(f"\n{s['drops']} drops, {s['uniform_drops']} from uniform starts\n")
    print("pose  normal (part frame)       quasi-static  perturbed  dynamic  95 % interval  belt-fed")
    for r in s["rows"]:
        n = r["normal"]
        lo, hi = r["interval"]
        belt = "    -" if r["belt_fed"] is None else f"{100 * r['belt_fed']:5.1f}"
        print(f"{r['pose']:>4}  ({n[0]:6.3f}, {n[1]:6.3f}, {n[2]:6.3f})  "
              f"{100 * r['quasi_static']:9.1f} %  {100 * r['perturbed']:7.1f} %  "
              f"{100 * r['uniform']:5.1f} %  [{100 * lo:4.1f}, {100 * hi:5.1f}]  {belt} %")
    print(f"not classified: {s['unsettled']} unsettled, {s['unclassified']} off every facet")

    if args.plot:
        try:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
        except ImportError:
            print("matplotlib is not installed: no plot (pip install matplotlib)")
            return
        rows = s["rows"]
        x = np.arange(len(rows))
        fig, ax = plt.subplots(figsize=(7, 3.5))
        ax.bar(x - 0.2, [100 * r["quasi_static"] for r in rows], 0.4, label="quasi-static")
        dyn = np.array([100 * r["uniform"] for r in rows])
        err = np.array([[dyn[i] - 100 * r["interval"][0], 100 * r["interval"][1] - dyn[i]]
                        for i, r in enumerate(rows)]).T
        ax.bar(x + 0.2, dyn, 0.4, yerr=err, capsize=3, label=f"{s['uniform_drops']} drops")
        ax.set_xticks(x, [f"pose {r['pose']}" for r in rows])
        ax.set_ylabel("share of drops (%)")
        ax.legend()
        fig.tight_layout()
        fig.savefig(args.plot)
        print(f"plot: {args.plot}")


if __name__ == "__main__":
    main()
