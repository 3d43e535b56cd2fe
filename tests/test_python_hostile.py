"""Hostile arguments to the Python module (issue 32), property-based (Debian python3-hypothesis).

Every function and method of `pumasim` that takes arguments (python/pumasim_module.cpp: dynamics,
Scene.load with its overrides and unset, Scene.time_events, rhs and jacobian, run with every keyword)
is called with nan, +-inf, negative, zero, huge (1e308) and tiny (5e-324) numbers, integers too large
for a float, booleans where numbers go, wrong types (strings, bytes, lists, None, dicts, sets,
objects), huge, deeply nested and self-containing lists, NUL characters and long strings.

Property: each call either returns finite results, or raises ValueError or TypeError whose message
names the argument (as Python or the command line spells it: `dt` or `--dt`, an override's key) and
is at most MAX_MESSAGE characters long; never another exception (MemoryError, RuntimeError,
SystemError, OverflowError), pybind11's generic messages ("Unable to cast Python instance",
"incompatible function arguments"), a crash or a hang. A hypothesis deadline bounds each call, and
so do the runs' own budgets: max_wall, max_steps and t_end are small unless one of them is the
argument under attack, and then the others bound the run. The process's address space is capped
(ADDRESS_SPACE), so that an allocation gone wild is a MemoryError here rather than the machine's memory.
(backends() and integrators() take no argument: given one, they raise Python's own arity TypeError.)

Profiles (environment PUMASIM_HYPOTHESIS_PROFILE): "ci", the default (CTest Python.HostileArguments,
derandomized, about half a minute), and "long" (40 times the examples, random, no deadline). By hand:

    PYTHONPATH=build/release/python /usr/bin/python3 -m pytest -q tests/test_python_hostile.py
    PUMASIM_HYPOTHESIS_PROFILE=long PYTHONPATH=build/release/python /usr/bin/python3 -m pytest -q tests/test_python_hostile.py
"""
import contextlib
import math
import os
import resource
import shutil
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import pumasim

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
SCENES = os.path.join(ROOT, "experiments", "scenes")
PASSIVE = os.path.join(SCENES, "passive_arm.toml")        # no controller: rhs is the plant
DRIVEN = os.path.join(SCENES, "paper_slow_viscous.toml")   # a reference and continuous PIV
SAMPLED = os.path.join(SCENES, "sampled_control.toml")     # made sampled: a time event every servo period
HYBRID = os.path.join(SCENES, "stick_slip.toml")           # stick-slip modes: discrete state, no rhs
MAX_MESSAGE = 300_000  # [characters]: an override's TOML text may be 128 KiB (one command-line argument)
ADDRESS_SPACE = 6 << 30  # [bytes]

settings.register_profile("ci", max_examples=400, deadline=10_000, derandomize=True, database=None,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.register_profile("long", max_examples=16_000, deadline=None, database=None,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.load_profile(os.environ.get("PUMASIM_HYPOTHESIS_PROFILE", "ci"))


@pytest.fixture(scope="module", autouse=True)
def bounded_memory():
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    cap = ADDRESS_SPACE if hard == resource.RLIM_INFINITY else min(ADDRESS_SPACE, hard)
    resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    yield
    resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """A folder to run in: a run given a relative `out` writes there, not in the project."""
    d = tmp_path_factory.mktemp("hostile")
    with contextlib.chdir(d):
        yield d


# ---------------------------------------------------------------- hostile values

class Named(list):
    """A list shown by a name (hypothesis shows the examples it tries)."""
    def __init__(self, name, items):
        super().__init__(items)
        self.name = name

    def __repr__(self):
        return self.name


NAN, INF = float("nan"), float("inf")
SELF = []
SELF.append(SELF)  # a list that holds itself
DEEP = [1.0]
for _ in range(100_000):
    DEEP = [DEEP]
DEEP = Named("<a list nested 100,000 deep>", DEEP)
HUGE = Named("<a list of 1,000,000 zeros>", [0.0] * 1_000_000)


class RaisingNumber:
    """Claims to be a number and raises when asked for its value."""
    def __float__(self):
        raise RuntimeError("no value")

    def __index__(self):
        raise RuntimeError("no value")


SPECIAL = [NAN, INF, -INF, -1.0, -0.0, 0.0, 1e308, -1e308, 5e-324, -5e-324, 1e-300, 1e-9, 1e-3, 0.5, 1.0, 3.0, 1e6,
           10 ** 400, -10 ** 400, 2 ** 63, 2 ** 64, True, False, np.float64(NAN), np.float32(1e-3),
           np.int64(-1), np.uint64(2 ** 64 - 1), np.array(2e-3), np.bool_(True)]
NUMBERS = st.sampled_from(SPECIAL) | st.floats() | st.integers(min_value=-2 ** 70, max_value=2 ** 70)
WRONG = st.sampled_from([None, "", "x", "nan", "1e-3", "qz", "\x00", "a\x00b", "x" * 100_000, b"x", b"", [], [1e-3],
                         [NAN] * 3, (1.0, 2.0), {}, {"a": 1}, {1, 2}, SELF, DEEP, object(), RaisingNumber(), 1j,
                         np.zeros((2, 2)), np.array(["a"]), HUGE, ["x"] * 3, [None], [[1.0, 2.0]]])
HOSTILE = NUMBERS | WRONG | st.text(max_size=20) | st.lists(NUMBERS, max_size=8)


def mostly(valid):
    """`valid` two times in three, else a hostile value."""
    return st.sampled_from([0, 1, 2]).flatmap(lambda k: valid if k < 2 else HOSTILE)


def refused_or(call, names, check):
    """Calls `call()`: a ValueError or TypeError naming one of `names`, or a result `check` accepts."""
    try:
        result = call()
    except (ValueError, TypeError) as e:
        message = str(e)
        for generic in ("Unable to cast", "incompatible function arguments", "Unable to convert"):
            assert generic not in message, message[:2000]
        assert any(n in message for n in names), (names, message[:2000])
        assert len(message) <= MAX_MESSAGE, (names, len(message), message[:500])
        event(f"refused: {type(e).__name__}: {message[:50]}")
        return None
    check(result)
    event("returned")
    return result


def finite(a):
    a = np.asarray(a, dtype=float)
    assert np.all(np.isfinite(a)), a
    return a


def as_path(v):
    """The file a message about path `v` names, if `v` is one."""
    return [os.fsdecode(v)] if isinstance(v, (str, bytes)) and v and b"\0" not in os.fsencode(v) else []


def values(kwargs):
    """The texts given (a message may name an argument by its value: "crba-symbolic-puma560 has ...")."""
    return [v for v in kwargs.values() if isinstance(v, str) and len(v) >= 3]


def spelled(name):
    """How messages name an argument: as Python spells it, or the command line (dt, --dt)."""
    return [name, "--" + name.replace("_", "-")] + (["back-end"] if name == "backend" else [])


# ---------------------------------------------------------------- dynamics

SIX = st.lists(NUMBERS, min_size=6, max_size=6)  # the PUMA's six joints, each hostile
DYNAMICS_ARGS = {
    "robot": mostly(st.sampled_from(["puma560", "stanford", "planar2", "/", "/dev/zero", "no_such_robot",
                                     os.path.join(ROOT, "models", "robots", "puma560.toml")])),
    "backend": mostly(st.sampled_from(pumasim.backends())),
    "q": mostly(st.sampled_from(["qz", "qn", "qr"]) | SIX),
    "qd": mostly(SIX),
    "qdd": mostly(SIX),
    "tau": mostly(SIX),
    "rotor_inertia": mostly(st.booleans()),
}


def check_dynamics(d):
    assert isinstance(d, dict) and d["n"] > 0
    for key, value in d.items():
        if isinstance(value, np.ndarray):
            finite(value)


@given(st.lists(st.sampled_from(sorted(DYNAMICS_ARGS)), min_size=1, max_size=3, unique=True).flatmap(
    lambda names: st.fixed_dictionaries({n: DYNAMICS_ARGS[n] for n in names})))
def test_dynamics(kwargs):
    kwargs.setdefault("q", "qz")
    names = [n for name in kwargs for n in spelled(name)] + as_path(kwargs.get("robot")) + values(kwargs)
    refused_or(lambda: pumasim.dynamics(**kwargs), names, check_dynamics)


# ---------------------------------------------------------------- scenes

KEYS = ["scene.duration", "scene.output_interval", "scene.name", "scene.joints", "scene.backend", "scene.rotor_inertia",
        "integrator.name", "integrator.dt", "integrator.rtol", "integrator.atol", "friction.model", "friction.viscous",
        "motor.inductance", "motor.resistance", "amplifier.gain", "controller.mode", "controller.servo_period",
        "controller.setpoint_interval", "controller.kp", "reference.max_speed", "reference.height", "initial.pose"]
KEY = st.sampled_from(KEYS) | st.text(max_size=12)
VALUE = mostly(NUMBERS | st.lists(NUMBERS, min_size=3, max_size=3)) | st.dictionaries(st.text(max_size=5), NUMBERS,
                                                                                     max_size=3)
OVERRIDES = mostly(st.dictionaries(KEY, VALUE, max_size=3)
                   | st.lists(st.builds(lambda k, v: f"{k}={v}", KEY, st.text(max_size=12) | st.sampled_from(
                       ["nan", "inf", "-1", "0", "1e308", "5e-324", "[1, 2]", "{a = 1}", '"x"', "", "=", "1e400"])),
                       max_size=3))
UNSET = mostly(st.sampled_from([None, []]) | st.lists(KEY, max_size=2))


def check_scene(s):
    assert isinstance(s, pumasim.Scene) and s.size > 0
    assert 0 < s.duration < INF and 0 < s.output_interval < INF
    finite(s.initial_state())
    assert np.all(finite(s.tolerance_scales) > 0)


@given(path=mostly(st.sampled_from([PASSIVE, DRIVEN, PASSIVE, DRIVEN, "/", "/dev/zero", "no_such.toml",
                                    PASSIVE + "\x00x", os.path.join(ROOT, "README.md")])),
       overrides=OVERRIDES, unset=UNSET)
def test_scene_load(path, overrides, unset):
    def names():
        keys = list(overrides) if isinstance(overrides, dict) else []
        keys += [k.split("=")[0] for k in overrides if isinstance(k, str)] if isinstance(overrides, list) else []
        keys += [k for k in unset if isinstance(k, str)] if isinstance(unset, list) else []
        return ["path", "overrides", "unset", "--set", "--unset", *[k for k in keys if k]] + as_path(path)
    refused_or(lambda: pumasim.Scene.load(path, overrides, unset), names(), check_scene)


@pytest.fixture(scope="module")
def scenes():
    sampled = {"controller.mode": "sampled", "controller.servo_period": 1e-3}  # a time event every 1 ms
    return {"passive": pumasim.Scene.load(PASSIVE), "driven": pumasim.Scene.load(DRIVEN),
            "sampled": pumasim.Scene.load(SAMPLED, overrides=sampled), "hybrid": pumasim.Scene.load(HYBRID)}


@given(which=st.sampled_from(["passive", "driven", "sampled"]), t_end=st.none() | HOSTILE)
def test_time_events(scenes, which, t_end):
    def check(times):
        assert isinstance(times, list)
        finite(times)
        assert times == sorted(times)
    refused_or(lambda: scenes[which].time_events(t_end), ["t_end"], check)


STATE = (st.lists(NUMBERS, min_size=12, max_size=12)  # the passive arm's 12 states, each hostile
         | st.lists(st.floats(-1e3, 1e3), min_size=12, max_size=12)  # or plausible
         | st.lists(st.floats(-1e300, 1e300), min_size=12, max_size=12))  # or finite and absurd


@given(which=st.sampled_from(["passive", "passive", "driven", "hybrid"]), t=mostly(st.floats(-10, 10)),
       x=mostly(STATE), exact=mostly(st.booleans()), method=st.sampled_from(["rhs", "jacobian"]))
def test_rhs_and_jacobian(scenes, which, t, x, exact, method):
    s = scenes[which]  # 12 states but the hybrid scene's, which refuses rhs (discrete state)
    if method == "rhs":
        refused_or(lambda: s.rhs(t, x), ["t", "x"], lambda f: finite(f).shape == (s.size,))
    else:
        refused_or(lambda: s.jacobian(t, x, exact), ["t", "x", "exact"],
                   lambda J: finite(J).shape == (s.size, s.size))


# ---------------------------------------------------------------- runs

BUDGETS = {"t_end": 0.02, "max_wall": 0.5, "max_steps": 20_000}  # each run's bound unless under attack
ADAPTIVE = [n for n in pumasim.integrators() if n.startswith(("cvode", "arkode", "odeint"))]
FIXED = [n for n in pumasim.integrators() if n not in ADAPTIVE]
RUN_ARGS = {
    "integrator": mostly(st.sampled_from(pumasim.integrators())),
    "backend": mostly(st.sampled_from(pumasim.backends())),
    "jacobian": mostly(st.sampled_from(["exact", "differences"])),
    "rtol": NUMBERS | HOSTILE,
    "atol": NUMBERS | HOSTILE,
    "dt": NUMBERS | HOSTILE,
    "force": mostly(st.booleans()),
    "late_events": mostly(st.booleans()),
    "stop_at_outputs": mostly(st.booleans()),
    "t_end": NUMBERS | HOSTILE,
    "max_wall": NUMBERS | HOSTILE,
    "max_steps": NUMBERS | HOSTILE,
    "out": st.sampled_from([5, [], b"\x00", "\x00", "", "run", "run\x00x", "x" * 5000]) | HOSTILE,
}


def check_run(r):
    assert isinstance(r, pumasim.Run)
    assert r.x.shape[0] == r.t.shape[0] >= 1
    finite(r.t)
    finite(r.x)
    assert isinstance(r.stats, dict)
    assert r.ok or r.failure


@given(data=st.data())
def test_run(scenes, workdir, data):
    # One or two keywords under attack, the rest valid; one budget at most (the other two bound the run).
    attacked = data.draw(st.lists(st.sampled_from(sorted(RUN_ARGS)), min_size=0, max_size=2, unique=True)
                         .filter(lambda a: sum(k in BUDGETS for k in a) <= 1), label="attacked")
    scene = data.draw(mostly(st.sampled_from(["passive", "driven", "sampled", "hybrid", "path"])), label="scene")
    target = dict(scenes, path=PASSIVE).get(scene, scene) if isinstance(scene, str) else scene
    args = dict(BUDGETS)
    if {"rtol", "atol"} & set(attacked):  # the tolerances are read only by an adaptive method
        args["integrator"] = data.draw(st.sampled_from(ADAPTIVE), label="adaptive")
    elif "dt" in attacked:
        args["integrator"] = data.draw(st.sampled_from(FIXED), label="fixed")
    for name in attacked:
        args[name] = data.draw(RUN_ARGS[name], label=name)
    names = [n for name in attacked for n in spelled(name)] + ["scene"] + as_path(target) + \
        values({k: v for k, v in args.items() if k in attacked})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # what a run warns of before it starts
        refused_or(lambda: pumasim.run(target, **args), names, check_run)
    for leftover in os.listdir(workdir):  # a run folder written (out="run") is removed for the next example
        path = os.path.join(workdir, leftover)
        if os.path.isdir(path):
            shutil.rmtree(path)


# ---------------------------------------------------------------- what it found, kept as examples

FOUND = [  # (call, the exception, a fragment of its message); each failed as described before the fix
    # RuntimeError "Unable to cast Python instance to C++ type" (issue 32)
    (lambda: pumasim.Scene.load(PASSIVE, [1, 2]), TypeError, "overrides: expected a dict"),
    # loaded passive_arm.toml: the path ended at the NUL
    (lambda: pumasim.Scene.load(PASSIVE + "\x00junk"), ValueError, "path: a path with a NUL character"),
    # a crash (SIGSEGV): the override's conversion recursed without end
    (lambda: pumasim.Scene.load(PASSIVE, {"friction.viscous": SELF}), ValueError, "nested at most 32 deep"),
    # TypeError "incompatible function arguments", naming no argument
    (lambda: pumasim.Scene.load(PASSIVE, unset="scene.duration"), TypeError, "unset: expected a list"),
    # TypeError "expected str, bytes or os.PathLike object, not NoneType"
    (lambda: pumasim.Scene.load(None), TypeError, "path: expected a path"),
    # ValueError ": cannot be read (no such file)"
    (lambda: pumasim.Scene.load(""), ValueError, "path: expected a path, got an empty one"),
    # TypeError "only size-1 arrays can be converted to Python scalars"
    (lambda: pumasim.Scene.load(PASSIVE, {"scene.duration": 10 ** 5000}), ValueError, "within +-2^63"),
    # slow, and a huge message echoing the list (measured: commit f1e0871)
    (lambda: pumasim.Scene.load(PASSIVE, {"friction.viscous": HUGE}), ValueError, "at most 131072 characters"),
    # returned bias = inf (pumasim dynamics printed null, exit status 0)
    (lambda: pumasim.dynamics(q="qz", qd=[1e200] * 6), ValueError, "bias h(q, qd) is not finite"),
    # rotor_inertia=None was False, and "no" a TypeError naming no argument
    (lambda: pumasim.dynamics(q="qz", rotor_inertia=None), TypeError, "rotor_inertia: expected True or False"),
    # returned nan
    (lambda: pumasim.Scene.load(PASSIVE).rhs(0.0, [NAN] * 12), ValueError, "x: expected finite numbers"),
    # returned a state derivative of nan
    (lambda: pumasim.Scene.load(PASSIVE).rhs(0.0, [1e308] * 12), ValueError, "x: f(t, x) is not finite"),
    # returned f at t = nan
    (lambda: pumasim.Scene.load(PASSIVE).rhs(NAN, [0.0] * 12), ValueError, "t: expected a finite time >= 0"),
    # RuntimeError "reference: the path point ... at t = -5.000000 s is out of reach"
    (lambda: pumasim.Scene.load(DRIVEN).rhs(-5.0, [0.0] * 12), ValueError, "t: expected a finite time >= 0"),
    # exact="no": TypeError naming no argument; exact=None was False
    (lambda: pumasim.Scene.load(PASSIVE).jacobian(0.0, [0.0] * 12, None), TypeError, "exact: expected True or False"),
    # TypeError "incompatible function arguments"
    (lambda: pumasim.Scene.load(PASSIVE).time_events("1"), TypeError, "t_end: expected a number"),
    # dt=True was a step of 1 s
    (lambda: pumasim.run(PASSIVE, dt=True), TypeError, "dt: expected a number, got a bool"),
    # TypeError "incompatible function arguments"
    (lambda: pumasim.run(PASSIVE, max_wall=10 ** 400), ValueError, "max_wall: expected a number, got an integer"),
    (lambda: pumasim.run(PASSIVE, integrator=5), TypeError, "integrator: expected a str"),
    # force=nan was True
    (lambda: pumasim.run(PASSIVE, force=NAN), TypeError, "force: expected True or False"),
    # TypeError "expected str, bytes or os.PathLike object, not int"
    (lambda: pumasim.run(PASSIVE, out=5), TypeError, "out: expected a path"),
    (lambda: pumasim.run(5), TypeError, "scene: expected a pumasim.Scene or a scene file's path"),
    # "controller.servo_period: 0.001 s over 21 s is 21000 stops, more than the step budget": not
    # saying that the 21 s came from t_end
    (lambda: pumasim.run(pumasim.Scene.load(SAMPLED, {"controller.mode": "sampled", "controller.servo_period": 1e-3}),
                         t_end=21, max_steps=20_000), ValueError, "over 21 s (the run's end time (t_end))"),
]


@pytest.mark.parametrize("case", range(len(FOUND)))
def test_found(case, workdir):
    call, exception, fragment = FOUND[case]
    with pytest.raises(exception) as e:
        call()
    assert fragment in str(e.value), str(e.value)[:500]


def test_a_numpy_array_is_an_override_as_a_list_is():
    # TypeError "only size-1 arrays can be converted to Python scalars" before
    viscous = [1e-3, 2e-3, 3e-3, 4e-5, 5e-5, 6e-5]
    a = pumasim.Scene.load(PASSIVE, {"friction.viscous": np.array(viscous)})
    assert a.resolved_toml() == pumasim.Scene.load(PASSIVE, {"friction.viscous": viscous}).resolved_toml()
