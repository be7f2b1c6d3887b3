"""geojcbb: data association for 2D EKF-SLAM (GEOJCBB, GEMJCBB and their baselines).

Bindings of the C++ library in double at host capacities (docs/python.md).
"""
from ._core import (  # noqa: F401
    MAX_CANDIDATES, MAX_GROUPS, MAX_JCBB_NODES, MAX_LANDMARKS, MAX_OBSERVATIONS, NEW_FEATURE,
    OPTIONS, PRESET_SUFFIXES, STRATEGIES, UNMATCHED, GeojcbbError, Simulator, Slam, associate)

__all__ = ["associate", "Slam", "Simulator", "GeojcbbError", "NEW_FEATURE", "UNMATCHED", "STRATEGIES",
           "PRESET_SUFFIXES", "OPTIONS", "MAX_OBSERVATIONS", "MAX_CANDIDATES", "MAX_GROUPS", "MAX_JCBB_NODES", "MAX_LANDMARKS"]
