"""Call overhead of geojcbb.associate against the C++ call, same scene, same run (not a test).

Usage: bench_overhead.py --cpp PATH/TO/python_overhead_cpp [--calls N] [--strategy S]
Prints the median microseconds per call for a 20-observation, 50-candidate scene, both ways.
"""
import argparse
import os
import statistics
import subprocess
import sys
import time

import numpy as np

import geojcbb

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from scenes import make_scene, scene_text  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cpp", required=True)
    ap.add_argument("--calls", type=int, default=2000)
    ap.add_argument("--strategies", default="JCBB,GEOJCBB")
    a = ap.parse_args()
    z, R, h, C, ids = make_scene(np.random.default_rng(11), 50, 20, p_true=0.9)
    print(f"| strategy | C++ median [us] | Python median [us] | overhead [us] | ratio |")
    print(f"| --- | --- | --- | --- | --- |")
    for s in a.strategies.split(","):
        cpp = float(subprocess.run([a.cpp, "--bench", str(a.calls)], input=scene_text(s, 12.0, z, R, h, C, ids),
                                   capture_output=True, text=True, check=True).stdout)
        ts = []
        for _ in range(a.calls):
            t0 = time.perf_counter_ns()
            geojcbb.associate(z, R, h, C, ids, strategy=s, local_radius_m=12.0)
            ts.append((time.perf_counter_ns() - t0) / 1000.0)
        py = statistics.median(ts)
        print(f"| {s} | {cpp:.1f} | {py:.1f} | {py - cpp:.1f} | {py / cpp:.2f} |")


if __name__ == "__main__":
    main()
