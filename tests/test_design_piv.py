"""scripts/design_piv.py on any robot file: gains against the joint model's closed
form on the two non-PUMA arms, the scenes' committed gains current, and a
clean refusal (exit status 2, a message, no traceback) of what it cannot do.

Run by CTest (Python.DesignPiv) with $PUMASIM set to the built binary.
"""
import math
import os
import re
import subprocess
import sys
import tomllib

import pytest

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
SCRIPT = os.path.join(ROOT, "scripts", "design_piv.py")
SCENES = os.path.join(ROOT, "experiments", "scenes")
ROBOTS = os.path.join(ROOT, "models", "robots")


def design(*args, env=None):
    return subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True, env=env, timeout=120)


def gains(stdout):
    """{key: [values]} of the printed gain lines."""
    out = {}
    for line in stdout.splitlines():
        m = re.match(r"(kp|ki|kv|kvff|kaff) = \[(.*)\]$", line)
        if m:
            out[m.group(1)] = [float(v) for v in m.group(2).split(",")]
    return out


def load(path):
    with open(path, "rb") as f:
        return tomllib.load(f)


def per_joint(v, n):
    return v if isinstance(v, list) else [v] * n


def expected(m_jj, z, scene, j, bandwidth, damping):
    """The docstring's pole placement for joint j from its M_jj, by hand."""
    amp, mot = scene["amplifier"], scene["motor"]
    n = scene["scene"]["joints"]
    ka, r0 = per_joint(amp["gain"], n)[j], per_joint(amp.get("output_resistance", 0.0), n)[j]
    k, r = per_joint(mot["torque_constant"], n)[j], per_joint(mot["resistance"], n)[j]
    J, rt, wn = m_jj / z ** 2, r0 + r, 2 * math.pi * bandwidth
    b = k * ka / rt
    kp = J * wn ** 2 / b
    kv = max(0.0, (2 * damping * wn * J - k ** 2 / rt) / b)
    return {"kp": kp, "ki": kp * wn / 10, "kv": kv, "kvff": kv + k / ka, "kaff": J / b}


def check_joint(got, want, j):
    for key, v in want.items():
        # The script prints 6 significant digits.
        assert got[key][j] == pytest.approx(v, rel=1e-5, abs=1e-12), (key, j, got[key][j], v)


def test_stanford_boom_has_its_closed_form():
    # A prismatic joint's M_jj is the mass it carries: every link from it to the
    # tip translates with it, whatever the pose, plus its rotor's reflected mass
    # Z^2 Im (models/robots/stanford.toml: Z = 1, Im the reflected 0.782 kg).
    scene_file = os.path.join(SCENES, "stanford_tracking.toml")
    r = design(scene_file, "--bandwidth", "4")
    assert r.returncode == 0, r.stderr
    joints = load(os.path.join(ROBOTS, "stanford.toml"))["joint"]
    boom = joints[2]
    assert boom["type"] == "prismatic"
    m33 = sum(j["mass"] for j in joints[2:]) + boom["gear_ratio"] ** 2 * boom["rotor_inertia"]
    check_joint(gains(r.stdout), expected(m33, boom["gear_ratio"], load(scene_file), 2, 4.0, 0.8), 2)


def planar_piv_scene(tmp_path):
    """planar2_tracking under the PIV law instead (its drive and reference kept)."""
    text = open(os.path.join(SCENES, "planar2_tracking.toml")).read()
    text = text.replace('law = "computed_torque"', 'law = "piv"')
    text = re.sub(r"kp = 400\.0.*\nkd = 40\.0.*\n", "kp = 0.0\nki = 0.0\nkv = 0.0\nkvff = 0.0\nkaff = 0.0\n", text)
    path = tmp_path / "planar2_piv.toml"
    path.write_text(text.replace('robot = "planar2"', f'robot = "{os.path.join(ROBOTS, "planar2.toml")}"'))
    return str(path)


def test_planar_arm_has_its_closed_form(tmp_path):
    # The planar two-link arm's inertia matrix in closed form (Siciliano et al.
    # 2009, sec. 7.3.2, with its rotors on the diagonal only, as the robot file
    # models them; models/robots/planar2.toml): with l_i the centres of mass,
    #   M11 = I1 + m1 l1^2 + I2 + m2 (a1^2 + l2^2 + 2 a1 l2 cos q2) + Z1^2 Im1
    #   M22 = I2 + m2 l2^2 + Z2^2 Im2
    path = planar_piv_scene(tmp_path)
    r = design(path, "--bandwidth", "5", "--damping", "0.7")
    assert r.returncode == 0, r.stderr
    q2 = float(re.search(r"start pose q = \[[-0-9.]+, ([-0-9.]+)\]", r.stdout).group(1))
    j1, j2 = load(os.path.join(ROBOTS, "planar2.toml"))["joint"]
    l1, l2 = -j1["com"][0], -j2["com"][0]  # the centre of mass a_i - l_i behind frame i's origin
    assert (j1["a"] - l1, j2["a"] - l2) == (0.5, 0.5)
    m11 = (j1["inertia"][2] + j1["mass"] * (j1["a"] - l1) ** 2 + j2["inertia"][2] +
           j2["mass"] * (j1["a"] ** 2 + (j2["a"] - l2) ** 2 + 2 * j1["a"] * (j2["a"] - l2) * math.cos(q2)) +
           j1["gear_ratio"] ** 2 * j1["rotor_inertia"])
    m22 = j2["inertia"][2] + j2["mass"] * (j2["a"] - l2) ** 2 + j2["gear_ratio"] ** 2 * j2["rotor_inertia"]
    scene, got = load(path), gains(r.stdout)
    # q2 as printed (4 decimals): M11's cos q2 term moves by at most 50 * 5e-5 kg m^2 of ~300.
    check_joint(got, expected(m22, j2["gear_ratio"], scene, 1, 5.0, 0.7), 1)
    want1 = expected(m11, j1["gear_ratio"], scene, 0, 5.0, 0.7)
    for key in ("kp", "kaff"):
        assert got[key][0] == pytest.approx(want1[key], rel=1e-5), key


def test_committed_gains_are_current():
    # Every scene whose gains say "designed by scripts/design_piv.py S --bandwidth B
    # --damping D" holds the lines that command prints today.
    seen = {}
    for name in sorted(os.listdir(SCENES)):
        if not name.endswith(".toml"):
            continue
        lines = open(os.path.join(SCENES, name)).read().splitlines()
        for i, line in enumerate(lines):
            m = re.match(r"# designed by scripts/design_piv.py (\S+) --bandwidth (\S+) --damping (\S+)$", line)
            if not m:
                continue
            if m.groups() not in seen:
                r = design(os.path.join(ROOT, m.group(1)), "--bandwidth", m.group(2), "--damping", m.group(3))
                assert r.returncode == 0, (name, r.stderr)
                seen[m.groups()] = r.stdout.splitlines()
            assert lines[i:i + 7] == seen[m.groups()], name
    assert len(seen) >= 2  # the PUMA's scenes and the Stanford arm's


def refused(r, *words):
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert "Traceback" not in r.stderr, r.stderr
    assert r.stdout == "", r.stdout
    for w in words:
        assert w in r.stderr, (w, r.stderr)


def test_a_scene_without_a_drive_is_refused():
    path = os.path.join(SCENES, "stanford_passive.toml")
    refused(design(path), path, "[amplifier], [motor]: expected a drive")


def test_a_computed_torque_scene_is_refused():
    path = os.path.join(SCENES, "planar2_tracking.toml")
    refused(design(path), path, 'controller.law: expected "piv"', '"computed_torque"')


def test_what_pumasim_refuses_is_refused_with_its_message(tmp_path):
    missing = str(tmp_path / "no_such_scene.toml")
    refused(design(missing), "no_such_scene.toml", "pumasim check refused it (exit 2)")
    bad = tmp_path / "bad_key.toml"
    bad.write_text(open(os.path.join(SCENES, "stanford_tracking.toml")).read().replace(
        'backend = "crba"', 'backend = "crba"\nspeed = 3.0'))
    refused(design(str(bad)), str(bad) + ":", "speed")


def test_bad_arguments_are_refused():
    scene = os.path.join(SCENES, "stanford_tracking.toml")
    refused(design(scene, "--bandwidth", "0"), "--bandwidth", "expected a finite number > 0")
    refused(design(scene, "--damping", "fast"), "--damping", "expected a number")
    refused(design(scene, "--pumasim", "/nonexistent/pumasim"), "cannot run pumasim")


def test_a_urdf_robot_gets_the_gains_of_its_toml_twin(tmp_path):
    # paper_slow on models/robots/puma560.urdf (with its side file) instead of puma560.toml: the same
    # arm (tests/test_urdf.cpp checks the two models' dynamics agree), so the same gains to the six
    # digits printed. The script once read every robot file as TOML and crashed on a URDF; it now asks
    # `pumasim robot`. The URDF's PUMA has a base transform, so its path takes the numerical inverse
    # kinematics, started at the closed form's start pose (the same branch).
    with open(os.path.join(SCENES, "paper_slow.toml")) as f:
        text = f.read()
    text = text.replace('robot = "puma560"', f'robot = "{os.path.join(ROBOTS, "puma560.urdf")}"')
    text = re.sub(r"\narm = .*", "\nik_guess = [-0.2349, 0.6706, -3.5105]", text)
    text = re.sub(r"\nelbow = .*", "", text)
    scene = tmp_path / "paper_slow_urdf.toml"
    scene.write_text(text)
    toml_run = design(os.path.join(SCENES, "paper_slow.toml"), "--bandwidth", "15")
    urdf_run = design(str(scene), "--bandwidth", "15")
    assert toml_run.returncode == 0, toml_run.stderr
    assert urdf_run.returncode == 0, urdf_run.stderr
    want, got = gains(toml_run.stdout), gains(urdf_run.stdout)
    assert set(got) == {"kp", "ki", "kv", "kvff", "kaff"}
    for k in want:
        assert got[k] == pytest.approx(want[k], rel=1e-5), k
