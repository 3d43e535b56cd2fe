"""experiments/tune_piv.py (issue 37): PIV gains tuned on the full model.

- The instrument first: the gradient the search uses, d(RMS path error)/d(gain) from the forward
  sensitivities, against central differences of whole runs for two gains (paper_slow_viscous, 4 s).
- A short search's result keeps its constraints, checked independently of the search: the tuned scene
  file (tuned.toml) re-run gives tune.json's figures, its peak voltage is within the headroom, and the
  eigenvalues of its plant's exact Jacobian at t = 0 are left of -abscissa with the damping asked;
  the search never returns gains worse than its start.
- Bad input: a scene with discrete state, an existing folder the program did not write.
Run by ctest (python/CMakeLists.txt).
"""
import json
import os
import subprocess
import sys

import numpy as np
import pumasim

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TUNE = os.path.join(ROOT, "experiments", "tune_piv.py")
SLOW = os.path.join(ROOT, "experiments", "scenes", "paper_slow_viscous.toml")


def rms(scene, key, value):
    s = pumasim.Scene.load(scene, overrides={key: value})
    return pumasim.run(s, integrator="cvode-bdf", rtol=1e-9, atol=1e-12, t_end=4).stats["rms_path_error_mm"]


def test_the_sensitivity_gradient_is_the_runs_central_difference():
    keys = ["controller.ki[1]", "controller.kv[2]"]
    r = pumasim.run(pumasim.Scene.load(SLOW), integrator="cvode-bdf", rtol=1e-9, atol=1e-12, t_end=4,
                    sensitivity=keys)
    d = r.stats["sensitivity"]["d_rms_path_error_mm"]
    import tomllib

    ctl = tomllib.loads(pumasim.Scene.load(SLOW).resolved_toml())["controller"]
    scene_values = {"controller.ki": list(ctl["ki"]), "controller.kv": list(ctl["kv"])}
    for k in keys:
        name, j = k.split("[")[0], int(k.split("[")[1].rstrip("]"))
        v = scene_values[name][j]
        h = 1e-3 * v
        up, down = list(scene_values[name]), list(scene_values[name])
        up[j] += h
        down[j] -= h
        fd = (rms(SLOW, name, up) - rms(SLOW, name, down)) / (2 * h)
        # Central differences at h = 1e-3 v: truncation O(h^2) ~ 1e-6 relative, the runs' rtol 1e-9 over 2h
        # ~ 1e-6 / 1e-3 of the difference; 1e-3 relative leaves room for both and sees a wrong gradient.
        assert abs(d[k] - fd) <= 1e-3 * abs(fd), (k, d[k], fd)


def test_a_short_search_keeps_its_constraints(tmp_path):
    out = tmp_path / "tuned"
    r = subprocess.run([sys.executable, TUNE, SLOW, "--out", str(out), "--iterations", "4", "--quiet"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    doc = json.loads((out / "tune.json").read_text())
    tuned, start = doc["tuned"], doc["pole_placement"]
    assert tuned["rms_path_error_mm"] <= start["rms_path_error_mm"]
    scene = pumasim.Scene.load(str(out / "tuned.toml"))
    again = pumasim.run(scene, integrator="cvode-bdf", rtol=1e-6)
    # The same scene and options as the search's run: the same run, to rounding (tuned.toml's numbers are
    # written as the shortest text that reads back as the same double).
    assert abs(again.stats["rms_path_error_mm"] - tuned["rms_path_error_mm"]) <= 1e-12
    import tomllib

    limit = float(np.min(tomllib.loads(scene.resolved_toml())["amplifier"]["voltage_limit"]))
    assert max(again.stats["peak_voltage_V"]) <= doc["constraints"]["headroom"] * limit
    lam = np.linalg.eigvals(np.asarray(scene.jacobian(0.0, np.asarray(again.x)[0])))
    assert np.max(lam.real) <= -doc["constraints"]["abscissa_per_s"]
    osc = lam[np.abs(lam.imag) > 1e-9 * np.abs(lam)]
    assert np.min(-osc.real / np.abs(osc)) >= doc["constraints"]["damping"] - 1e-9


def test_bad_input(tmp_path):
    sampled = os.path.join(ROOT, "experiments", "scenes", "sampled_control.toml")
    r = subprocess.run([sys.executable, TUNE, sampled, "--out", str(tmp_path / "x"), "--set",
                        'controller.mode="sampled"'], capture_output=True, text=True)
    assert r.returncode == 2 and "tune_piv:" in r.stderr and not (tmp_path / "x").exists(), r.stderr
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    r = subprocess.run([sys.executable, TUNE, SLOW, "--out", str(theirs), "--force"], capture_output=True, text=True)
    assert r.returncode == 2 and "not a folder tune_piv wrote" in r.stderr
