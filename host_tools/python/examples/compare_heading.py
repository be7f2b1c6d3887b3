#!/usr/bin/env python3
"""Heading of a run with local maps against a single-map run of the same log, at each join.

Both runs written by `geojcbb_eval replay --write-path` (the second with `--submaps`, which also
writes joins.csv). For each local map: the heading difference (submaps - single) at the map's
start, just before its join and just after it. Standard library only.

    python3 host_tools/python/examples/compare_heading.py SINGLE_DIR SUBMAPS_DIR [STRATEGY]
"""
import bisect
import csv
import math
import sys


def read_path(directory, strategy):
    t, theta = [], []
    with open(directory + "/path.csv", newline="") as f:
        for row in csv.DictReader(f):
            if row["strategy"] == strategy:
                t.append(float(row["t_s"]))
                theta.append(float(row["theta_rad"]))
    if not t:
        sys.exit(f"{directory}/path.csv has no rows of {strategy}")
    return t, theta


def heading_at(path, t_s):
    t, theta = path
    return theta[min(bisect.bisect_left(t, t_s), len(t) - 1)]


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    single_dir, submaps_dir = sys.argv[1], sys.argv[2]
    strategy = sys.argv[3] if len(sys.argv) > 3 else "PCJCBB"
    single, submaps = read_path(single_dir, strategy), read_path(submaps_dir, strategy)

    def diff_deg(t_s):
        d = heading_at(submaps, t_s) - heading_at(single, t_s)
        return math.degrees((d + math.pi) % (2 * math.pi) - math.pi)

    with open(submaps_dir + "/joins.csv", newline="") as f:
        joins = [float(r["t_s"]) for r in csv.DictReader(f) if r["strategy"] == strategy]
    print("heading - single's [deg] of each local map: at its start, before its join, after it")
    print("map  closed [s]    start   before    after")
    start = single[0][0]
    for k, t in enumerate(joins):
        print(f"{k:3d}  {t:10.1f}  {diff_deg(start):+7.2f}  {diff_deg(t - 0.5):+7.2f}  {diff_deg(t + 0.5):+7.2f}")
        start = t + 0.5


if __name__ == "__main__":
    main()
