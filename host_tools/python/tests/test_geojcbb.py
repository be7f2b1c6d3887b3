"""The Python bindings: the same answers as the C++ pipeline (python_overhead_cpp --reference) on
generated scenes for every strategy, every bad input raising its Status, the SLAM step and the
simulator end to end, and the example script writing its figure to a temporary directory."""
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import geojcbb

sys.path.insert(0, os.path.dirname(__file__))
from scenes import make_scene, scene_text  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
SCENARIOS = os.environ.get("GEOJCBB_SCENARIO_DIR", os.path.join(HERE, "..", "..", "scenarios"))


@pytest.mark.skipif("GEOJCBB_PY_REFERENCE" not in os.environ, reason="needs the C++ reference program")
@pytest.mark.parametrize("strategy", geojcbb.STRATEGIES)
def test_same_answers_as_cpp(strategy):
    rng = np.random.default_rng(7)
    scenes, text = [], []
    for _ in range(40):
        n = int(rng.integers(1, 51))
        m = int(rng.integers(0, 25))
        sc = make_scene(rng, n, m)
        scenes.append(sc)
        text.append(scene_text(strategy, 12.0, *sc))
    out = subprocess.run([os.environ["GEOJCBB_PY_REFERENCE"], "--reference"], input="".join(text),
                         capture_output=True, text=True, check=True).stdout.splitlines()
    assert len(out) == len(scenes)
    for (z, R, h, C, ids), line in zip(scenes, out):
        ref = line.split()
        assert ref[0] == "ok"
        m = len(z)
        r = geojcbb.associate(z, R, h, C, ids, strategy=strategy, local_radius_m=12.0)
        assert [int(x) for x in ref[1:1 + m]] == r["feature"].tolist()
        assert [float(x) for x in ref[1 + m:1 + 2 * m]] == r["d2"].tolist()  # exact, inf included
        assert float(ref[1 + 2 * m]) == r["joint_d2"]
        assert int(ref[2 + 2 * m]) == r["pairings"]
        assert int(ref[3 + 2 * m]) == r["diagnostics"]["jcbb_nodes"]


def test_result_fields_and_pairs_true_landmarks():
    rng = np.random.default_rng(1)
    z, R, h, C, ids = make_scene(rng, 10, 10, p_true=1.0)
    r = geojcbb.associate(z, R, h, C, ids, strategy="JCBB")
    assert r["feature"].dtype == np.int32 and r["feature"].shape == (10,)
    assert r["pairings"] == int(np.sum(r["feature"] >= 0))
    assert r["jointly_compatible"]
    assert set(r["diagnostics"]) >= {"jcbb_nodes", "compatible_pairs", "groups", "declined"}
    assert np.sum(r["feature"] == ids[:10]) >= 8


def test_non_contiguous_and_float32_inputs_give_the_same_answer():
    rng = np.random.default_rng(2)
    z, R, h, C, ids = make_scene(rng, 8, 8)
    a = geojcbb.associate(z, R, h, C, ids, strategy="JCBB")
    zf = np.asfortranarray(z)
    b = geojcbb.associate(zf, R, h, np.asfortranarray(C), ids.astype(np.int32), strategy="JCBB")
    assert a["feature"].tolist() == b["feature"].tolist()
    assert a["d2"].tolist() == b["d2"].tolist()


def status_of(call):
    with pytest.raises(geojcbb.GeojcbbError) as e:
        call()
    return e.value.status


def test_every_bad_input_raises_its_status():
    rng = np.random.default_rng(3)
    z, R, h, C, ids = make_scene(rng, 4, 4)

    def assoc(z=z, R=R, h=h, C=C, ids=ids, **kw):
        kw.setdefault("strategy", "JCBB")
        return lambda: geojcbb.associate(z, R, h, C, ids, **kw)

    bad = z.copy(); bad[0, 0] = np.nan
    assert status_of(assoc(z=bad)) == "kNonFinite"
    bad = z.copy(); bad[0, 0] = -1.0
    assert status_of(assoc(z=bad)) == "kInvalidInput"
    badR = R.copy(); badR[0, 0, 1] = 1e-3
    assert status_of(assoc(R=badR)) == "kNotSymmetric"
    badR = R.copy(); badR[0, 0, 0] = -1.0
    assert status_of(assoc(R=badR)) == "kNotPositiveDefinite"
    badC = C.copy(); badC[0, 1] += 0.5
    assert status_of(assoc(C=badC)) == "kNotSymmetric"
    badC = C.copy(); badC[0, 2] += 0.5  # a cross block: refused as the dense C is packed
    assert status_of(assoc(C=badC)) == "kNotSymmetric"
    badC = C.copy(); badC[0, 0] = -1.0
    assert status_of(assoc(C=badC)) == "kNotPositiveDefinite"
    assert status_of(assoc(ids=-ids)) == "kInvalidInput"
    assert status_of(assoc(z=z[:, :1])) == "kInvalidInput"  # shape
    assert status_of(assoc(strategy="NOPE")) == "kInvalidInput"
    assert status_of(assoc(strategy="GEOJCBB", local_radius_m=0.0)) == "kInvalidInput"  # r + d must be > 0
    assert status_of(assoc(confidence=1.5)) in ("kInvalidInput", "kNoConvergence")
    zz, RR, hh, CC, ii = make_scene(rng, 4, geojcbb.MAX_OBSERVATIONS + 1)
    assert status_of(lambda: geojcbb.associate(zz, RR, hh, CC, ii, strategy="JCBB")) == "kCapacityExceeded"
    zz, RR, hh, CC, ii = make_scene(rng, geojcbb.MAX_CANDIDATES + 1, 2)
    assert status_of(lambda: geojcbb.associate(zz, RR, hh, CC, ii, strategy="JCBB")) == "kCapacityExceeded"
    with pytest.raises(TypeError):
        geojcbb.associate(z, R, h, C, ids, strategy="JCBB", no_such_option=1)


def test_slam_on_the_simulator():
    sim = geojcbb.Simulator(os.path.join(SCENARIOS, "env1.json"), seed=3)
    slam = geojcbb.Slam("GEOJCBB", local_radius_m=sim.max_range_m + 5.0, max_range_m=sim.max_range_m,
                        half_fov_rad=sim.fov_rad / 2)
    first = None
    paired = 0
    for k in range(2000):
        s = sim.step()
        if s is None:
            break
        if first is None:
            first = s
            slam.reset(np.array(s["true_pose"]), np.eye(3) * 1e-6)
        slam.predict(s["v_mps"], s["w_radps"], sim.dt_s, sim.sigma_v_mps, sim.sigma_w_radps)
        if s["scan"]:
            r = slam.step(s["z"], s["R"])
            paired += r["outcome"].count("paired")
    ids, xy = slam.landmarks
    assert len(ids) > 0 and xy.shape == (len(ids), 2)
    assert paired > 100
    x = slam.pose
    assert math.hypot(x[0] - s["true_pose"][0], x[1] - s["true_pose"][1]) < 5.0
    P = slam.covariance
    assert P.shape == (3 + 2 * len(ids),) * 2
    with pytest.raises(geojcbb.GeojcbbError) as e:
        slam.predict(float("nan"), 0.0, 0.1, 0.1, 0.1)
    assert e.value.status == "kNonFinite"
    with pytest.raises(geojcbb.GeojcbbError) as e:
        slam.reset(np.zeros(3), -np.eye(3))
    assert e.value.status == "kNotPositiveDefinite"
    with pytest.raises(geojcbb.GeojcbbError) as e:
        geojcbb.Slam("GEOJCBB", local_radius_m=10.0, max_range_m=0.0)
    assert e.value.status == "kInvalidInput"


def test_bad_scenario_file(tmp_path):
    p = tmp_path / "bad.json"
    p.write_text("{")
    with pytest.raises(RuntimeError):
        geojcbb.Simulator(str(p))


def test_example_writes_png(tmp_path):
    pytest.importorskip("matplotlib")
    ex = os.path.join(HERE, "..", "examples", "plot_association.py")
    subprocess.run([sys.executable, ex, "--out", str(tmp_path / "a.png")], check=True, env=dict(os.environ))
    assert (tmp_path / "a.png").stat().st_size > 1000


def test_options_are_the_table_and_the_stubs_list_them():
    import ast
    names = [o["name"] for o in geojcbb.OPTIONS]
    assert names[0] == "strategy" and len(names) == len(set(names))
    stub = ast.parse(open(os.path.join(os.path.dirname(geojcbb.__file__), "_core.pyi")).read())
    cls = next(n for n in stub.body if isinstance(n, ast.ClassDef) and n.name == "Options")
    stubbed = [n.target.id for n in cls.body if isinstance(n, ast.AnnAssign)]
    assert stubbed == names[1:]
    py = {"F64": "float", "REAL": "float", "F32": "float", "INT": "int", "U32": "int", "BOOL": "bool"}
    types = {n.target.id: n.annotation.id for n in cls.body if isinstance(n, ast.AnnAssign)}
    for o in geojcbb.OPTIONS[1:]:
        assert types[o["name"]] == py[o["type"]], o["name"]
    for o in geojcbb.OPTIONS[1:]:  # every option documented in both docstrings
        assert o["name"] in geojcbb.associate.__doc__ and o["name"] in geojcbb.Slam.__init__.__doc__


def test_diagnostics_are_the_table_and_the_stubs_list_them():
    import ast
    rng = np.random.default_rng(2)
    z, R, h, C, ids = make_scene(rng, 6, 6)
    diag = geojcbb.associate(z, R, h, C, ids, strategy="PCJCBB")["diagnostics"]
    stub = ast.parse(open(os.path.join(os.path.dirname(geojcbb.__file__), "_core.pyi")).read())
    cls = next(n for n in stub.body if isinstance(n, ast.ClassDef) and n.name == "Diagnostics")
    types = {n.target.id: n.annotation.id for n in cls.body if isinstance(n, ast.AnnAssign)}
    assert list(diag) == list(types)  # every diagnostic of core/diagnostics.h, in its order
    for name, value in diag.items():
        assert type(value).__name__ == types[name], name


def test_every_option_is_a_keyword_and_its_range_is_enforced():
    rng = np.random.default_rng(5)
    z, R, h, C, ids = make_scene(rng, 4, 4)
    geojcbb.associate(z, R, h, C, ids, strategy="JCBB+V", confidence=0.95, rjc=True, rjc_tries=4)
    assert status_of(lambda: geojcbb.associate(z, R, h, C, ids, strategy="JCBB", rjc_tries=0)) == "kInvalidInput"
    assert status_of(lambda: geojcbb.Slam("JCBB", landmark_delete_nats=0.5)) == "kInvalidInput"
    geojcbb.Slam("jcbb+v", landmark_delete_nats=-6.0, static_gate_level=0.99, occlusion_rad=0.03)
    with pytest.raises(TypeError):
        geojcbb.Slam("JCBB", strategy="ICNN")


def test_preset_suffixes_as_the_tools_read_them():
    # One grammar (core/presets.hpp): every suffix the command-line tools accept, alone and together,
    # in either case and any order; bad names refused with kInvalidInput.
    assert set(geojcbb.PRESET_SUFFIXES) == set("VRLTHC")
    for letter in geojcbb.PRESET_SUFFIXES:
        geojcbb.Slam("PCJCBB+" + letter)
        geojcbb.Slam("jcbb+" + letter.lower())
    geojcbb.Slam("PCJCBB+RL")
    geojcbb.Slam("PCJCBB+CHTLRV")
    for bad in ["PCJCBB+", "PCJCBB+X", "PCJCBB+RR", "PCJCBB+R+L", "+RL", "PCJCBBX", "PCJCBB+VRLTHCV"]:
        assert status_of(lambda: geojcbb.Slam(bad)) == "kInvalidInput", bad
