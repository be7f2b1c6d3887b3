"""Type stubs of geojcbb._core (host_tools/python/geojcbb_py.cpp). Units in each docstring."""
from typing import Any, Dict, List, Optional, Tuple, TypedDict

import numpy as np
import numpy.typing as npt

NEW_FEATURE: int  # -1: nothing compatible (a new landmark, or clutter)
UNMATCHED: int  # -2: compatible candidates but left unpaired (ambiguous)
MAX_OBSERVATIONS: int  # 64
MAX_CANDIDATES: int  # 128
MAX_GROUPS: int  # 8
MAX_JCBB_NODES: int  # 200000
MAX_LANDMARKS: int  # 500
STRATEGIES: List[str]  # ["ICNN", "JCBB", "KJCBB", "DFJCBB", "GEMJCBB", "GEOJCBB", "PCJCBB"]
PRESET_SUFFIXES: Dict[str, str]  # the tools' suffix letters ("V", "R", "L", "T", "H", "C") -> what each switches in
OPTIONS: List[Dict[str, str]]  # the option table (core/options.h): name, type, default, unit, meaning


class GeojcbbError(RuntimeError):
    """A library call returned a Status other than kOk; .status holds its name (e.g. "kNonFinite")."""
    status: str


class Diagnostics(TypedDict):
    """What one association call reports about itself, one key per line of
    firmware_lib/include/geojcbb/core/diagnostics.h."""
    jcbb_nodes: int
    candidates_in_region: int
    compatible_pairs: int
    node_budget_hit: bool
    groups: int
    cluster_iterations: int
    cluster_bound_hit: bool
    merge_conflicts: int
    recheck_failed: bool
    recheck_dropped: int
    declined: int
    verify_dropped: int
    seed_tried: bool
    seed_used: bool
    seed_pairings: int
    clique_graph_nodes: int
    clique_search_nodes: int
    clique_budget_hit: bool
    clique_nodes_truncated: bool
    rjc_used: bool


class Options(TypedDict, total=False):
    """The keyword options of associate() and Slam(), one per line of the option table
    (protocol/include/geojcbb/core/options.h; docs/options.md gives ranges and meanings).
    The keywords are generated from the table (geojcbb_options_doc; CTest options.stub_current)."""
    # BEGIN GENERATED: option keywords (cmake --build build/host-release --target options_docs; do not edit)
    confidence: float  # default 0.99
    new_landmark_level: float  # default 0.999
    local_radius_m: float  # default 10
    groups: int  # default 3
    condition_groups: bool  # default 0
    dbscan_eps_m: float  # default 1.5
    dbscan_min_points: int  # default 2
    node_budget: int  # default 0
    min_range_m: float  # default 0
    max_range_m: float  # default 10
    half_fov_rad: float  # default 3.14159265358979
    sensor_x_m: float  # default 0
    sensor_y_m: float  # default 0
    sensor_theta_rad: float  # default 0
    landmark_confirm_nats: float  # default 4.6
    landmark_delete_nats: float  # default -4
    landmark_reserve_nats: float  # default 1000
    max_tentative_reviews: int  # default 10
    tentative_isolated: bool  # default 0
    joint_recheck: bool  # default 1
    ambiguity_margin: float  # default 0
    new_if_candidates_taken: bool  # default 0
    verify: bool  # default 0
    full_covariance_check: bool  # default 0
    papers_em: bool  # default 0
    seed_min_position_var_m2: float  # default 4
    consistency_wide_d2: float  # default 23.025850929940457
    consistency_pair_d2: float  # default 10.827566170662733
    rjc: bool  # default 0
    rjc_tries: int  # default 8
    rjc_subset: int  # default 8
    occlusion_rad: float  # default 0
    static_gate_level: float  # default 0
    motion_false_alarm: float  # default 0
    detection_floor: float  # default 0
    learn_detection: bool  # default 0
    learn_clutter: bool  # default 0
    first_estimates_jacobians: bool  # default 1
    augment: bool  # default 1
    relocalise: bool  # default 0
    reloc_min_inliers: int  # default 5
    reloc_margin_nats: float  # default 10
    reloc_base_pairs: int  # default 4
    reloc_inflation: float  # default 4
    reloc_confirm_scans: int  # default 1
    reloc_lost_nats: float  # default 20
    loop_check: bool  # default 0
    loop_age: int  # default 100
    loop_min_inliers: int  # default 3
    loop_margin_nats: float  # default 3
    loop_confirm_scans: int  # default 2
    loop_inflation: float  # default 4
    loop_detection_probability: float  # default 0.9
    loop_unexplained_density: float  # default 0.003
    duplicate_merge_d2: float  # default 0
    hypothesis_rivals: int  # default 0
    hypothesis_window_scans: int  # default 5
    hypothesis_margin_nats: float  # default 3
    hypothesis_hold: bool  # default 0
    cluster_first: bool  # default 0
    evict_when_full: bool  # default 0
    submap_landmarks: int  # default 0
    submap_distance_m: float  # default 0
    submap_scans: int  # default 0
    submap_carry: bool  # default 1
    # END GENERATED: option keywords


class AssociationResult(TypedDict):
    feature: npt.NDArray[np.int32]  # (m,) feature id, NEW_FEATURE or UNMATCHED
    candidate: npt.NDArray[np.int32]  # (m,) index into h/ids, or -1
    d2: npt.NDArray[np.float64]  # (m,) individual Mahalanobis d2 (unpaired: nearest, or inf)
    pairings: int
    joint_d2: float  # joint Mahalanobis d2 of the hypothesis
    jointly_compatible: bool
    diagnostics: Diagnostics


def associate(z: npt.ArrayLike, R: npt.ArrayLike, h: npt.ArrayLike, C: npt.ArrayLike, ids: npt.ArrayLike,
              strategy: str = "PCJCBB", **options: Any) -> AssociationResult:
    """z (m, 2) [m, rad], R (m, 2, 2) [m^2, rad^2], h (n, 2) [m, rad], C (2n, 2n), ids (n,) >= 0.

    strategy: one of STRATEGIES, optionally with "+" and letters of PRESET_SUFFIXES ("PCJCBB+RL"). options: keywords of Options.
    Raises GeojcbbError with .status on bad input, TypeError on an unknown option.
    """


class StepResult(TypedDict):
    outcome: List[str]  # paired | new_landmark | new_dropped | unmatched | not_augmented
    feature: npt.NDArray[np.int32]  # landmark id, -1 when none
    d2: npt.NDArray[np.float64]
    diagnostics: Diagnostics


class Slam:
    """One EKF-SLAM step with data association (node::SlamStep<double, host bounds>)."""

    def __init__(self, strategy: str = "PCJCBB+RL", **options: Any) -> None:
        """strategy: one of STRATEGIES, optionally with "+" and letters of PRESET_SUFFIXES ("PCJCBB+RL"). options: keywords of Options."""
    def reset(self, x0: npt.ArrayLike, P0: npt.ArrayLike) -> None:
        """x0 = (x [m], y [m], theta [rad]); P0 (3, 3) [m^2, rad^2]."""
    def predict(self, v_mps: float, w_radps: float, dt_s: float, sigma_v_mps: float, sigma_w_radps: float) -> None: ...
    def step(self, z: npt.ArrayLike, R: npt.ArrayLike) -> StepResult: ...
    @property
    def pose(self) -> npt.NDArray[np.float64]:
        """(x [m], y [m], theta [rad])"""
    @property
    def landmarks(self) -> Tuple[npt.NDArray[np.int32], npt.NDArray[np.float64]]:
        """(ids (k,), positions (k, 2) [m])"""
    @property
    def covariance(self) -> npt.NDArray[np.float64]: ...


class SimStep(TypedDict):
    t_s: float
    true_pose: Tuple[float, float, float]  # (x [m], y [m], theta [rad])
    v_mps: float
    w_radps: float
    scan: bool
    z: npt.NDArray[np.float64]  # (k, 2) [m, rad]
    R: npt.NDArray[np.float64]  # (k, 2, 2)
    truth: npt.NDArray[np.int32]  # (k,) landmark index, -1 for clutter


class Simulator:
    def __init__(self, scenario_path: str, seed: int = 1) -> None: ...
    def step(self) -> Optional[SimStep]: ...
    @property
    def landmarks(self) -> npt.NDArray[np.float64]: ...
    @property
    def dt_s(self) -> float: ...
    @property
    def sigma_v_mps(self) -> float: ...
    @property
    def sigma_w_radps(self) -> float: ...
    @property
    def max_range_m(self) -> float: ...
    @property
    def fov_rad(self) -> float: ...
