"""Generated association scenes (NumPy), shared by the tests and bench_overhead.py: n landmarks
around a robot at the origin whose pose is uncertain, C = J Pp J^T + sl^2 I, and m observations,
most of them true landmarks seen with noise, the rest clutter."""
import numpy as np


def make_scene(rng, n, m, sp=(0.05, 0.05, 0.01), sr=0.05, sb=0.01, sl=0.03, p_true=0.8):
    l = rng.uniform(-10.0, 10.0, size=(n, 2))
    rr = np.hypot(l[:, 0], l[:, 1]) + 0.5
    h = np.stack([rr, np.arctan2(l[:, 1], l[:, 0])], axis=1)
    J = np.zeros((2 * n, 3))
    J[0::2, 0] = -l[:, 0] / rr
    J[0::2, 1] = -l[:, 1] / rr
    J[1::2, 0] = l[:, 1] / rr**2
    J[1::2, 1] = -l[:, 0] / rr**2
    J[1::2, 2] = -1.0
    C = J @ np.diag(np.square(sp)) @ J.T + sl**2 * np.eye(2 * n)
    C = 0.5 * (C + C.T)
    z = np.empty((m, 2))
    for i in range(m):
        if i < n and rng.uniform() < p_true:
            z[i] = h[i] + rng.normal(size=2) * (sr, sb)
        else:
            z[i] = (rng.uniform(1.0, 13.0), rng.uniform(-np.pi, np.pi))
    z[:, 1] = (z[:, 1] + np.pi) % (2 * np.pi) - np.pi
    R = np.tile(np.diag([sr**2, sb**2]), (m, 1, 1))
    ids = np.arange(100, 100 + n, dtype=np.int64)
    return z, R, h, C, ids


def scene_text(strategy, radius, z, R, h, C, ids):
    """The scene in python_overhead_cpp's stdin format (repr: shortest round-trip doubles)."""
    vals = [strategy, repr(float(radius)), str(len(z)), str(len(h))]
    for a in (z, R):
        vals += [repr(float(x)) for x in np.ravel(a)]
    vals += [str(int(x)) for x in ids]
    for a in (h, C):
        vals += [repr(float(x)) for x in np.ravel(a)]
    return " ".join(vals) + "\n"
