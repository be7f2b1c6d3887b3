"""docs/python.md's API example, run by CTest (docs.examples_current keeps the doc's block equal
to the lines between the doc markers). Argument: the scenario folder."""
import os
import sys

import numpy as np

SCENARIOS = sys.argv[1]

# [doc]
import geojcbb

z = np.array([[5.0, 0.1]])                      # (m, 2) range [m], bearing [rad]
R = np.array([np.diag([0.01, 1e-4])])           # (m, 2, 2)
h = np.array([[5.05, 0.1]])                     # (n, 2) predicted range, bearing
C = np.diag([0.02, 2e-4])                       # (2n, 2n) = H P H^T
ids = np.array([7])                             # (n,) >= 0
r = geojcbb.associate(z, R, h, C, ids, strategy="GEOJCBB", local_radius_m=12.0)
r["feature"]      # (m,) int32: feature id, geojcbb.NEW_FEATURE (-1) or geojcbb.UNMATCHED (-2)
r["candidate"], r["d2"], r["pairings"], r["joint_d2"], r["jointly_compatible"], r["diagnostics"]
geojcbb.associate(z, R, h, C, ids, strategy="JCBB+V")   # +V: the pairwise verification switched in

# every option of docs/options.md is a keyword (geojcbb.OPTIONS lists them)
slam = geojcbb.Slam("PCJCBB+RL", local_radius_m=35.0, max_range_m=30.0, half_fov_rad=1.57)
slam.reset(np.zeros(3), np.eye(3) * 1e-4)
slam.predict(0.5, 0.0, 0.1, 0.05, 0.01)        # v [m/s], w [rad/s], dt [s], their sigmas
out = slam.step(z, R)      # outcome (list of str), feature, d2, diagnostics
slam.pose, slam.landmarks, slam.covariance

sim = geojcbb.Simulator(os.path.join(SCENARIOS, "env1.json"), seed=1)
s = sim.step()             # None at the end; t_s, true_pose, v_mps, w_radps, scan, z, R, truth
# [/doc]
assert r["feature"][0] == 7
assert out["outcome"] == ["new_landmark"]
assert s is not None
print("python: observation 0 -> feature", int(r["feature"][0]))
