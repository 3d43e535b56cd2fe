"""Tests of the Python module `pumasim` (python/pumasim_module.cpp): against the pumasim binary (the
same numbers, statistics, files and messages), against the C++ right-hand side as the integrators
see it, and against scipy's solve_ivp. CTest runs them with the module's folder on PYTHONPATH and
the binary in PUMASIM_BIN (python/CMakeLists.txt); by hand:

    PYTHONPATH=build/release/python PUMASIM_BIN=build/release/bin/pumasim \
        /usr/bin/python3 -m pytest -q tests/test_python_module.py
"""
import json
import os
import re
import subprocess

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import pumasim

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
SCENES = os.path.join(ROOT, "experiments", "scenes")
PASSIVE = os.path.join(SCENES, "passive_arm.toml")      # no drive, no controller: f(t, x) is the plant
DRIVEN = os.path.join(SCENES, "paper_slow_viscous.toml")  # drive and continuous PIV following a reference
HYBRID = os.path.join(SCENES, "stick_slip.toml")        # stick-slip modes: discrete state
PUMASIM = os.environ.get("PUMASIM_BIN", os.path.join(ROOT, "build", "release", "bin", "pumasim"))


def cli(*args, cwd=None):
    return subprocess.run([PUMASIM, *args], capture_output=True, text=True, cwd=cwd)


def cli_error(*args, cwd=None):
    """The one line `pumasim` prints for bad input (exit status 2), without its "pumasim: " prefix."""
    r = cli(*args, cwd=cwd)
    assert r.returncode == 2, r.stderr
    assert r.stderr.startswith("pumasim: ") and r.stderr.count("\n") == 1, r.stderr
    return r.stderr[len("pumasim: "):].rstrip("\n")


PYTHON_FLAGS = ("force", "late_events", "stop_at_outputs", "keep_history")


def in_python_words(message):
    """The command line's message in the module's words: its keywords for the options ("--max-steps" is
    max_steps, "--force" force=True), "overrides" for --set (core/option_words.hpp: the library names an
    option neutrally and each front end phrases it)."""
    def word(m):
        name = m.group(1).replace("-", "_")
        return "overrides" if name == "set" else f"{name}=True" if name in PYTHON_FLAGS else name
    return re.sub(r"(?<![\w.-])--([a-z][a-z-]*)", word, message)  # not a path's "--"


# ---------------------------------------------------------------- registries and dynamics

def test_registries_are_the_command_lines():
    for command, names in (("backends", pumasim.backends()), ("integrators", pumasim.integrators())):
        r = cli(command)
        assert r.returncode == 0
        assert names == [line.split("\t")[0] for line in r.stdout.splitlines()]
        assert len(names) >= 5


CASES = [  # (command-line options, keyword arguments)
    (["--q=qn", "--qd=0.1,-0.2,0.3,0.4,-0.5,0.6", "--tau=1,2,3,0.1,0.2,0.3"],
     dict(q="qn", qd=[0.1, -0.2, 0.3, 0.4, -0.5, 0.6], tau=[1, 2, 3, 0.1, 0.2, 0.3])),
    (["--q=0.3,-0.7,1.1,0.2,0.9,-0.4", "--qd=1,0.5,-0.5,0,0.2,2", "--qdd=0.3,0.1,-2,1,0,0.5", "--no-rotor-inertia"],
     dict(q=np.array([0.3, -0.7, 1.1, 0.2, 0.9, -0.4]), qd=(1, 0.5, -0.5, 0, 0.2, 2), qdd=[0.3, 0.1, -2, 1, 0, 0.5],
          rotor_inertia=False)),
    (["--q=qz", "--qdd=1,1,1,1,1,1", "--tau=0,0,0,0,0,0"], dict(q="qz", qdd=np.ones(6), tau=np.zeros(6))),
]


@pytest.mark.parametrize("backend", pumasim.backends())
@pytest.mark.parametrize("case", range(len(CASES)))
def test_dynamics_gives_the_command_lines_numbers(backend, case):
    args, kwargs = CASES[case]
    r = cli("dynamics", "--robot", "puma560", "--backend", backend, *args)
    if r.returncode == 2:  # a back-end that cannot describe this robot (the folded closed form without rotors)
        with pytest.raises(ValueError) as e:
            pumasim.dynamics(robot="puma560", backend=backend, **kwargs)
        assert r.stderr == "pumasim: " + str(e.value) + "\n"
        return
    assert r.returncode == 0, r.stderr
    expected = json.loads(r.stdout)
    got = pumasim.dynamics(robot="puma560", backend=backend, **kwargs)
    assert list(got) == list(expected)  # the same keys in the same order
    for key, value in expected.items():
        if isinstance(value, list):
            want = np.array(value, dtype=float)
            assert got[key].shape == want.shape, key
            # The same library call: the same numbers to the last bit (JSON numbers read back exactly).
            np.testing.assert_array_equal(got[key], want, err_msg=key)
        else:
            assert got[key] == value, key


def test_dynamics_takes_a_robot_file_path():
    path = os.path.join(ROOT, "models", "robots", "puma560.toml")
    a = pumasim.dynamics(robot=path, q="qr")
    b = pumasim.dynamics(q="qr")
    np.testing.assert_array_equal(a["gravity"], b["gravity"])
    assert a["backend"] == "crba" and a["rotor_inertia_included"] is True


# ---------------------------------------------------------------- the scene's right-hand side

def test_scene_describes_its_plant():
    s = pumasim.Scene.load(DRIVEN)
    r = cli("check", DRIVEN)
    assert r.returncode == 0
    lines = r.stdout.splitlines()
    state = next(l for l in lines if l.startswith("# state ("))
    assert s.state_names == state.split(":", 1)[1].split()
    assert s.size == len(s.state_names)
    x0 = [float(v) for v in next(l for l in lines if l.startswith("# initial state:")).split(":", 1)[1].split()]
    np.testing.assert_allclose(s.initial_state(), x0, rtol=1e-9, atol=1e-300)  # `check` prints 10 digits
    assert r.stdout.startswith(s.resolved_toml())
    assert s.discrete_state is None and s.name == "paper_slow_viscous"


@pytest.mark.parametrize("scene", [PASSIVE, DRIVEN])
def test_rhs_is_the_integrators_right_hand_side(scene):
    # Two steps of forward Euler through the driver (x_{k+1} = x_k + h f(t_k, x_k), outputs at every
    # step from the method's end state) against the same two steps taken with Scene.rhs: the state
    # order, the time argument and the plant all have to agree. The driven scene's f depends on t
    # through its reference and the controller.
    h = 2.0 ** -14
    s = pumasim.Scene.load(scene, overrides={"scene.output_interval": h})
    run = pumasim.run(s, integrator="euler", dt=h, t_end=2 * h)
    assert run.ok and run.x.shape == (3, s.size) and run.t[2] == 2 * h
    x = s.initial_state()
    np.testing.assert_array_equal(run.x[0], x)
    for k in (1, 2):
        x = x + h * s.rhs((k - 1) * h, x)
        np.testing.assert_allclose(run.x[k], x, rtol=1e-14, atol=1e-14 * np.abs(x).max())
    # and f moves: a test that would pass with f = 0 tests nothing
    assert np.abs(run.x[2] - run.x[0]).max() > 1e3 * 1e-14 * np.abs(x).max()


def central_jacobian(f, t, x, scales):
    J = np.empty((x.size, x.size))
    for k in range(x.size):
        d = 1e-6 * max(scales[k], abs(x[k]))
        e = np.zeros(x.size)
        e[k] = d
        J[:, k] = (f(t, x + e) - f(t, x - e)) / (2 * d)
    return J


@pytest.mark.parametrize("scene,t", [(PASSIVE, 0.3), (DRIVEN, 0.7)])
def test_exact_jacobian_matches_differences_of_rhs(scene, t):
    s = pumasim.Scene.load(scene)
    x = pumasim.run(s, integrator="rk4", dt=1e-3, t_end=t).x[-1]  # a state in motion, not the start
    J = s.jacobian(t, x)
    assert J.shape == (s.size, s.size)
    Jc = central_jacobian(s.rhs, t, x, s.tolerance_scales)
    # per column (the entries of one derivative), and no smaller than a thousandth of the largest
    # entry: a column that is zero (q1, about the vertical axis) holds the differences' rounding
    scale = np.maximum(np.abs(J).max(axis=0), 1e-3 * np.abs(J).max())
    assert (np.abs(J - Jc) / scale).max() < 1e-5
    Jf = s.jacobian(t, x, exact=False)  # the integrators' forward differences
    assert (np.abs(J - Jf) / scale).max() < 1e-3
    assert np.abs(J - Jf).max() > 0  # differences, not the exact Jacobian again


@pytest.mark.parametrize("method", ["Radau", "LSODA"])
def test_solve_ivp_reproduces_a_builtin_run(method):
    # The passive arm falling from qz for the scene's 2 s: scipy on Scene.rhs (with the exact
    # Jacobian) and the built-in CVODE BDF, both far tighter than the comparison, agree at the end.
    s = pumasim.Scene.load(PASSIVE)
    builtin = pumasim.run(s, integrator="cvode-bdf", rtol=1e-12, atol=1e-14)
    assert builtin.ok and builtin.t[-1] == s.duration
    sol = solve_ivp(s.rhs, (0.0, s.duration), s.initial_state(), method=method, rtol=1e-10, atol=1e-12,
                    jac=s.jacobian)
    assert sol.success
    np.testing.assert_allclose(sol.y[:, -1], builtin.x[-1], rtol=0, atol=1e-8)
    assert np.abs(builtin.x[-1] - builtin.x[0]).max() > 0.1  # the arm has moved


# ---------------------------------------------------------------- runs

def test_run_is_pumasim_run(tmp_path):
    # The same run through the module and the command line: the same trajectory file, the same
    # statistics but for the wall times, and the module's arrays are that trajectory.
    opts = ["--integrator", "cvode-bdf", "--rtol", "1e-6", "--atol", "1e-9", "--t-end", "1.5"]
    r = cli("run", DRIVEN, *opts, "--out", str(tmp_path / "cli"))
    assert r.returncode == 0, r.stderr
    run = pumasim.run(pumasim.Scene.load(DRIVEN), integrator="cvode-bdf", rtol=1e-6, atol=1e-9, t_end=1.5,
                      out=tmp_path / "py")
    assert run.ok and run.out == str(tmp_path / "py")
    for name in ("trajectory.csv", "scene.resolved.toml", ".pumasim-run"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    cli_stats = json.loads(r.stdout)
    assert json.loads((tmp_path / "py" / "stats.json").read_text()) == run.stats
    timing = {"integration_wall_time_s", "wall_time_s"}
    assert list(run.stats) == list(cli_stats)
    assert {k: v for k, v in run.stats.items() if k not in timing} == \
        {k: v for k, v in cli_stats.items() if k not in timing}
    table = np.genfromtxt(tmp_path / "cli" / "trajectory.csv", delimiter=",", names=True)
    header = (tmp_path / "cli" / "trajectory.csv").read_text().splitlines()[0].split(",")
    assert [h.split(" [")[0] for h in header[1:1 + len(run.state_names)]] == run.state_names
    np.testing.assert_array_equal(run.t, table[table.dtype.names[0]])
    np.testing.assert_array_equal(run.x, np.column_stack([table[n] for n in table.dtype.names[1:1 + run.x.shape[1]]]))
    np.testing.assert_allclose(run.path_error_mm, table["path_error_mm"], rtol=1e-15, atol=0)
    assert run.path_error_mm.max() == pytest.approx(run.stats["max_path_error_mm"], rel=1e-15)


def test_run_writes_nothing_without_out(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # where the command line would write runs/passive_arm/
    run = pumasim.run(PASSIVE, t_end=0.05)  # a path is a scene too; the scene's integrator (rk4)
    assert run.ok and run.out is None and run.stats["integrator"] == "rk4"
    assert run.t[-1] == pytest.approx(0.05) and run.path_error_mm.size == 0
    assert os.listdir(tmp_path) == []


# ---------------------------------------------------------------- discrete state

def test_a_scene_with_discrete_state_refuses_rhs():
    s = pumasim.Scene.load(HYBRID)
    assert "friction.model" in s.discrete_state
    x = s.initial_state()
    for call in (lambda: s.rhs(0.0, x), lambda: s.jacobian(0.0, x)):
        with pytest.raises(ValueError, match="discrete state"):
            call()
    sampled = pumasim.Scene.load(DRIVEN, overrides={"controller.mode": "sampled", "controller.servo_period": 1e-3})
    assert "controller.mode" in sampled.discrete_state
    assert sampled.time_events(0.0105) == pytest.approx([0.001 * k for k in range(1, 11)])
    assert pumasim.run(sampled, integrator="cvode-bdf", t_end=0.05).ok  # run() takes it, with its events
    for bad in (float("inf"), float("nan"), -1.0):  # as --t-end: refused, not 16 GB or [] (issue 32)
        with pytest.raises(ValueError, match="t_end: expected a number > 0"):
            sampled.time_events(bad)


def test_the_drives_dae_refuses_rhs_and_runs_with_ida():
    # motor.current = "algebraic" (La = 0): an index-1 DAE, whose current rows hold residuals, not rates.
    s = pumasim.Scene.load(DRIVEN, overrides={"motor.inductance": 0.0, "motor.current": "algebraic"})
    x = s.initial_state()
    for call in (lambda: s.rhs(0.0, x), lambda: s.jacobian(0.0, x)):
        with pytest.raises(ValueError, match="index-1 DAE"):
            call()
    assert pumasim.run(s, integrator="ida", t_end=0.05).ok
    with pytest.raises(ValueError, match="integrates an ODE"):
        pumasim.run(s, integrator="cvode-bdf", t_end=0.05)


def test_the_papers_rule_warns_an_ode_solver_and_an_adaptive_run():
    """paper_slow's friction rule is discontinuous in the state: rhs warns
    (scipy's BDF failed obscurely on it, issue 31), as does pumasim.run with
    an adaptive method; a smooth scene gives no warning."""
    s = pumasim.Scene.load(os.path.join(SCENES, "paper_slow.toml"))
    x = s.initial_state()
    with pytest.warns(RuntimeWarning, match="discontinuous in the state"):
        s.rhs(0.0, x)
    with pytest.warns(RuntimeWarning, match="cvode-bdf is adaptive and friction.model"):
        pumasim.run(s, integrator="cvode-bdf", rtol=1e-6, t_end=0.01)
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pumasim.Scene.load(PASSIVE).rhs(0.0, pumasim.Scene.load(PASSIVE).initial_state())


# ---------------------------------------------------------------- bad input

def test_an_unknown_key_names_file_and_key(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(open(PASSIVE).read().replace("[friction]\n", "[friction]\nviscosity = 1.0\n"))
    with pytest.raises(ValueError) as e:
        pumasim.Scene.load(bad)
    assert str(bad) in str(e.value) and "viscosity" in str(e.value)
    assert str(e.value) == cli_error("check", str(bad))


def test_overrides_are_the_command_lines_set():
    with pytest.raises(ValueError) as e:
        pumasim.Scene.load(PASSIVE, overrides={"friction.viscosity": 1.0})
    assert str(e.value) == in_python_words(cli_error("check", PASSIVE, "--set", "friction.viscosity=1.0"))
    with pytest.raises(ValueError) as e:
        pumasim.Scene.load(PASSIVE, overrides={"scene.duration": -1})
    assert str(e.value) == in_python_words(cli_error("check", PASSIVE, "--set", "scene.duration=-1"))
    # every kind of value, and the command line's own strings
    s = pumasim.Scene.load(PASSIVE, overrides={"scene.duration": 0.25, "scene.rotor_inertia": False,
                                               "friction.viscous": [1e-3, 2e-3, 3e-3, 4e-5, 5e-5, 6e-5],
                                               "integrator.name": "cvode-bdf"})
    assert s.duration == 0.25 and s.integrator == "cvode-bdf"
    t = pumasim.Scene.load(PASSIVE, overrides=["scene.duration=0.25", "scene.rotor_inertia=false",
                                               "friction.viscous=[1e-3, 2e-3, 3e-3, 4e-5, 5e-5, 6e-5]",
                                               'integrator.name="cvode-bdf"'])
    assert s.resolved_toml() == t.resolved_toml()


def test_unset_is_the_command_lines_unset():
    # Switching the controller law: the PIV keys the new law does not read are removed first.
    piv_only = ["controller.ki", "controller.kv", "controller.kvff", "controller.kaff"]
    sets = {"controller.law": "computed_torque", "controller.kp": 900.0, "controller.kd": 60.0}
    s = pumasim.Scene.load(DRIVEN, overrides=sets, unset=piv_only)
    assert 'law = "computed_torque"' in s.resolved_toml() or "law = 'computed_torque'" in s.resolved_toml()
    assert not any(n.startswith("z_piv") for n in s.state_names)  # no PIV integrals
    with pytest.raises(ValueError) as e:
        pumasim.Scene.load(DRIVEN, overrides=sets)
    assert "controller.ki" in str(e.value) or "'ki'" in str(e.value)
    with pytest.raises(ValueError) as e:
        pumasim.Scene.load(DRIVEN, unset=["controller.no_such_key"])
    assert str(e.value) == in_python_words(cli_error("check", DRIVEN, "--unset", "controller.no_such_key"))


def test_bad_dynamics_input_is_a_value_error():
    with pytest.raises(ValueError) as e:
        pumasim.dynamics(backend="no-such-backend", q="qz")
    assert str(e.value) in cli_error("dynamics", "--robot", "puma560", "--backend", "no-such-backend", "--q=qz")
    assert "crba" in str(e.value)
    with pytest.raises(ValueError, match=r"^q: expected 6 values \(one per joint\), got 3$"):
        pumasim.dynamics(q=[0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="^tau: expected 6 values"):
        pumasim.dynamics(q="qz", tau=np.zeros(7))
    with pytest.raises(ValueError, match="qz"):
        pumasim.dynamics(q="no-such-pose")
    with pytest.raises(ValueError, match="1-D"):
        pumasim.dynamics(q=np.zeros((2, 3)))
    with pytest.raises(ValueError, match="^qd: expected finite numbers, got nan for joint 2$"):
        pumasim.dynamics(q="qz", qd=[0.0, float("nan"), 0.0, 0.0, 0.0, 0.0])
    with pytest.raises(ValueError) as e:
        pumasim.dynamics(robot="no_such_robot", q="qz")
    assert str(e.value) == cli_error("dynamics", "--robot", "no_such_robot", "--backend", "crba", "--q=qz")
    # a result that overflows (finite arguments of absurd size): refused by both, not printed as null
    with pytest.raises(ValueError, match=r"^bias h\(q, qd\) is not finite") as e:
        pumasim.dynamics(q="qz", qd=[1e200] * 6)
    assert str(e.value) == cli_error("dynamics", "--robot", "puma560", "--backend", "crba", "--q=qz",
                                     "--qd=" + ",".join(["1e200"] * 6))


def test_bad_state_and_run_options_are_value_errors(tmp_path):
    s = pumasim.Scene.load(PASSIVE)
    with pytest.raises(ValueError, match=r"^x: expected 12 values \(the scene's state\), got 11$"):
        s.rhs(0.0, np.zeros(11))
    with pytest.raises(ValueError, match="^x: expected 12 values"):
        s.jacobian(0.0, np.zeros(13))
    with pytest.raises(ValueError) as e:
        pumasim.run(s, integrator="cvode-bdf", dt=1e-3)
    assert str(e.value) == in_python_words(cli_error("run", PASSIVE, "--integrator", "cvode-bdf", "--dt", "1e-3",
                                                     "--out", str(tmp_path / "never")))
    with pytest.raises(ValueError) as e:
        pumasim.run(s, rtol=1e-6)
    assert str(e.value) == in_python_words(cli_error("run", PASSIVE, "--rtol", "1e-6", "--out", str(tmp_path / "never")))
    with pytest.raises(ValueError, match=r"^t_end: expected a number > 0, got '-1'$"):
        pumasim.run(s, t_end=-1.0)
    with pytest.raises(ValueError, match="unknown integrator"):
        pumasim.run(s, integrator="no-such-integrator")
    with pytest.raises(ValueError, match="^late_events=True excludes stop_at_outputs=True$"):
        pumasim.run(s, late_events=True, stop_at_outputs=True)
    # a folder pumasim did not write is never replaced, as by the command line
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep")
    with pytest.raises(ValueError) as e:
        pumasim.run(s, t_end=0.01, out=tmp_path / "mine", force=True)
    assert str(e.value) == in_python_words(cli_error("run", PASSIVE, "--t-end", "0.01", "--out", str(tmp_path / "mine"),
                                                     "--force"))
    assert (tmp_path / "mine" / "notes.txt").read_text() == "keep"
    assert not (tmp_path / "never").exists()


# ---------------------------------------------------------------- arms of any length

def random_passive_scene(tmp_path, n):
    """A passive random chain of n joints (`pumasim robot --random`), viscous friction, the ledger."""
    robot = tmp_path / f"random{n}.toml"
    r = cli("robot", "--random", str(n), "--seed", str(n))
    assert r.returncode == 0, r.stderr
    robot.write_text(r.stdout)
    q0 = np.random.default_rng(n).uniform(-1, 1, n)
    scene = tmp_path / f"random{n}_passive.toml"
    scene.write_text(
        f'[scene]\nname = "random{n}_passive"\nrobot = "{robot}"\njoints = {n}\nbackend = "crba"\n'
        f'duration = 0.5\noutput_interval = 0.05\nenergy_ledger = true\n\n'
        f'[integrator]\nname = "rk4"\ndt = 0.001\n\n'
        f'[friction]\nmodel = "viscous"\nviscous = [{", ".join(["1e-4"] * n)}]\n\n'
        f'[initial]\nq = [{", ".join(repr(float(v)) for v in q0)}]\n')
    return str(scene)


@pytest.mark.parametrize("n", [7, 12])
def test_a_long_random_chain_through_the_module(tmp_path, n):
    # Seven and twelve joints: the state is q, qd and the ledger's three energies; scipy's Radau on
    # Scene.rhs with the exact Jacobian and the built-in CVODE BDF agree; the exact Jacobian matches
    # central differences of rhs.
    s = pumasim.Scene.load(random_passive_scene(tmp_path, n))
    assert s.size == 2 * n + 3 and s.state_names[:n] == [f"q{j + 1}" for j in range(n)]
    builtin = pumasim.run(s, integrator="cvode-bdf", rtol=1e-12, atol=1e-14)
    assert builtin.ok and builtin.t[-1] == s.duration
    sol = solve_ivp(s.rhs, (0.0, s.duration), s.initial_state(), method="Radau", rtol=1e-10, atol=1e-12,
                    jac=s.jacobian)
    assert sol.success
    np.testing.assert_allclose(sol.y[:, -1], builtin.x[-1], rtol=0, atol=1e-8)
    assert np.abs(builtin.x[-1] - builtin.x[0]).max() > 0.01  # the arm has moved
    x = builtin.x[-1]
    J = s.jacobian(0.5, x)
    Jc = central_jacobian(s.rhs, 0.5, x, s.tolerance_scales)
    scale = np.maximum(np.abs(J).max(axis=0), 1e-3 * np.abs(J).max())
    assert (np.abs(J - Jc) / scale).max() < 1e-5


ENSEMBLE = os.path.join(ROOT, "experiments", "ensembles", "paper_slow_viscous_drive.toml")


def ensemble_rows(text):
    import csv
    import io
    rows = list(csv.DictReader(io.StringIO(text)))
    for r in rows:
        r.pop("wall_time")  # the one column that differs between re-runs
    return rows


def test_ensemble_is_the_command_lines_table_and_replays_a_sample(tmp_path):
    """pumasim.ensemble gives the table `pumasim ensemble` writes (but for the wall times), on any number
    of threads; sample=k is row k; given samples run instead of the draws; bad arguments raise."""
    spec = tmp_path / "e.toml"
    text = open(ENSEMBLE).read().replace("samples = 64", "samples = 6").replace("t_end = 4.0", "t_end = 0.2")
    spec.write_text(text.replace('"../scenes/', '"' + SCENES + "/"))
    r = cli("ensemble", str(spec), "--threads", "2", "-q")
    assert r.returncode == 0, r.stderr
    one = pumasim.ensemble(str(spec), threads=1)
    two = pumasim.ensemble(spec, threads=2)
    assert ensemble_rows(one["csv"]) == ensemble_rows(r.stdout) == ensemble_rows(two["csv"])
    assert one["meta"]["written_by"] == "pumasim ensemble" and one["meta"]["samples"] == 6
    assert [c["name"] for c in one["meta"]["columns"]] == r.stdout.splitlines()[0].split(",")
    assert ensemble_rows(pumasim.ensemble(spec, sample=4)["csv"]) == ensemble_rows(one["csv"])[4:5]
    rows = ensemble_rows(one["csv"])
    given = pumasim.ensemble(spec, samples=[{"motor.resistance": float(rows[2]["motor.resistance"]),
                                             "motor.inductance": float(rows[2]["motor.inductance"]),
                                             "amplifier.gain": float(rows[2]["amplifier.gain"])}])
    g = ensemble_rows(given["csv"])[0]
    assert g["seed"] == "0" and {k: v for k, v in g.items() if k not in ("sample", "seed")} == \
        {k: v for k, v in rows[2].items() if k not in ("sample", "seed")}
    with pytest.raises(ValueError, match="threads"):
        pumasim.ensemble(spec, threads=0)
    with pytest.raises(ValueError, match="sample"):
        pumasim.ensemble(spec, sample=6)
    with pytest.raises(TypeError, match="samples"):
        pumasim.ensemble(spec, samples={"motor.resistance": 2.0})


# ---------------------------------------------------------------- pickling

def _same_runs(a, b):
    """Two runs' values equal bit for bit, but for the wall times."""
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.path_error_mm, b.path_error_mm)
    timing = {"integration_wall_time_s", "wall_time_s"}
    assert {k: v for k, v in a.stats.items() if k not in timing} == \
        {k: v for k, v in b.stats.items() if k not in timing}


def test_a_pickled_scene_is_its_resolved_content_not_its_path(tmp_path):
    # Issue 35: a Scene pickles as what it resolved to (its overrides applied), so unpickled after its
    # file changed it still runs as the scene pickled; the changed file itself runs differently (else
    # the test could not fail).
    import pickle
    path = tmp_path / "s.toml"
    path.write_text(open(DRIVEN).read())
    scene = pumasim.Scene.load(path, overrides={"amplifier.gain": 3.8})
    blob = pickle.dumps(scene)
    before = pumasim.run(scene, integrator="cvode-bdf", rtol=1e-6, t_end=0.5)
    path.write_text(open(DRIVEN).read().replace("resistance = 2.0", "resistance = 3.1", 1))
    again = pickle.loads(blob)
    assert again.resolved_toml() == scene.resolved_toml()
    assert (again.name, again.file, again.state_names) == (scene.name, scene.file, scene.state_names)
    _same_runs(before, pumasim.run(again, integrator="cvode-bdf", rtol=1e-6, t_end=0.5))
    changed = pumasim.run(pumasim.Scene.load(path, overrides={"amplifier.gain": 3.8}), integrator="cvode-bdf",
                          rtol=1e-6, t_end=0.5)
    assert not np.array_equal(changed.x, before.x)


def test_an_unpickled_scene_refuses_a_robot_file_changed_since(tmp_path):
    # The robot file is read again on unpickling; changed, the scene would not be the one pickled.
    import pickle
    robot = tmp_path / "arm.toml"
    robot.write_text(open(os.path.join(ROOT, "models", "robots", "puma560.toml")).read())
    scene = pumasim.Scene.load(DRIVEN, overrides={"scene.robot": str(robot)})
    blob = pickle.dumps(scene)
    assert pickle.loads(blob).resolved_toml() == scene.resolved_toml()
    robot.write_text(robot.read_text() + "\n# edited\n")
    with pytest.raises(ValueError, match=re.escape(str(robot)) + ".*changed since"):
        pickle.loads(blob)


def test_a_run_pickles_with_its_values(tmp_path):
    import pickle
    run = pumasim.run(pumasim.Scene.load(DRIVEN), integrator="cvode-bdf", rtol=1e-6, t_end=0.2)
    back = pickle.loads(pickle.dumps(run))
    _same_runs(run, back)
    np.testing.assert_array_equal(run.path_deviation_mm, back.path_deviation_mm)
    assert (back.state_names, back.ok, back.failure, back.out) == (run.state_names, run.ok, run.failure, run.out)


def test_run_gives_the_sensitivities_as_arrays():
    """pumasim.run(sensitivity=[...]) is `pumasim run --sensitivity`: the same keys and final values as its
    stats, arrays shaped (rows, m, p), and a Run that pickles with them."""
    import pickle
    run = pumasim.run(DRIVEN, integrator="cvode-bdf", rtol=1e-6, t_end=0.5,
                      sensitivity=["motor.resistance", "motor.inductance"])
    assert run.ok
    s = run.sensitivity
    assert s["ok"], s["failure"]
    assert s["keys"] == ["motor.resistance", "motor.inductance"]
    rows, m = s["x"].shape
    assert s["s"].shape == (rows, m, 2) and s["t"][-1] == 0.5
    final = run.stats["sensitivity"]["final_state"]
    for k, key in enumerate(s["keys"]):
        for i, name in enumerate(run.state_names):
            assert s["s"][-1, i, k] == final[key][name]
    back = pickle.loads(pickle.dumps(run))
    assert np.array_equal(back.sensitivity["s"], s["s"])
    with pytest.raises(TypeError):
        pumasim.run(DRIVEN, sensitivity="motor.resistance")
