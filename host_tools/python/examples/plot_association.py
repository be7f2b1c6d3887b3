"""Plots one association: observations and predicted candidates in the robot frame, with a line
for each pairing GEOJCBB makes. Usage: plot_association.py [--out FILE.png] (default: a temp dir)."""
import argparse
import os
import sys
import tempfile

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import geojcbb  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from scenes import make_scene  # noqa: E402


def xy(rb):
    return rb[:, 0] * np.cos(rb[:, 1]), rb[:, 0] * np.sin(rb[:, 1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=os.path.join(tempfile.mkdtemp(prefix="geojcbb_"), "association.png"))
    ap.add_argument("--strategy", default="PCJCBB", choices=geojcbb.STRATEGIES)
    a = ap.parse_args()
    z, R, h, C, ids = make_scene(np.random.default_rng(4), 20, 20)
    r = geojcbb.associate(z, R, h, C, ids, strategy=a.strategy, local_radius_m=20.0)
    zx, zy = xy(z)
    hx, hy = xy(h)
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.scatter(hx, hy, marker="s", facecolors="none", edgecolors="tab:blue", label="candidates h")
    ax.scatter(zx, zy, marker="x", color="tab:red", label="observations z")
    for i, c in enumerate(r["candidate"]):
        if c >= 0:
            ax.plot([zx[i], hx[c]], [zy[i], hy[c]], color="tab:green", lw=1)
    ax.plot([0], [0], "k^", label="robot")
    ax.set_xlabel("x [m] (robot frame)")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal")
    ax.set_title(f"{a.strategy}: {r['pairings']} pairings, joint d2 {r['joint_d2']:.1f}")
    ax.legend(loc="upper right", fontsize=8)
    fig.savefig(a.out, dpi=100)
    print(a.out)


if __name__ == "__main__":
    main()
