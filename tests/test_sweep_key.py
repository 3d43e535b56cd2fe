"""experiments/sweep.py reuses a finished run only while everything that
determines it is unchanged: a tiny sweep (passive_arm, 20 ms, three runs) is
run, re-run (nothing runs), then re-run after each change -- t_end, the scene
file, a variant's --set, a method's setting, the program -- and each change
runs again exactly the runs it concerns; --merge refuses a stale summary.
Every other file a scene reads is in the key by its content too: a URDF
robot's side file and the URDF itself, a joint-space reference CSV and an
open-loop input CSV (the footer of `pumasim check`: issue 31's stale sweep).

    PUMASIM=build/release/bin/pumasim /usr/bin/python3 -m pytest -q tests/test_sweep_key.py
"""
import os
import re
import shutil
import subprocess
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "experiments"))
from pumasim_exp import io as pumasim_io  # noqa: E402
from pumasim_exp import merge, runner, specs  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_input_files  # noqa: E402  (its urdf_scene)

SWEEP = """
[sweep]
name = "tiny"
scene = "passive_arm"
t_end = {t_end}
repeats = 1
target_mm = 1.0

[reference]
integrator = "cvode-bdf"
options = ["--rtol", "1e-8", "--atol", "1e-10"]

[check]
integrator = "rk4"
options = ["--dt", "5e-4"]

[[variant]]
label = "base"
set = [{variant_set}]

[[method]]
integrator = ["rk4"]
dt = [{dt}]
"""


SCENES = os.path.join(pumasim_io.ROOT, "experiments", "scenes")


def _tiny_sweep(tmp_path, monkeypatch, scene):
    """A counter of `pumasim run` processes, and a function that loads the
    tiny sweep over `scene` and runs what is not complete, returning the ids
    of the runs it ran."""
    monkeypatch.setattr(runner, "scene_file", lambda s: str(scene))
    ran = []
    real_run = subprocess.run

    def counting_run(cmd, *args, **kwargs):
        if len(cmd) > 1 and cmd[1] == "run":
            ran.append(cmd[cmd.index("--out") + 1])
        return real_run(cmd, *args, **kwargs)

    monkeypatch.setattr(runner.subprocess, "run", counting_run)
    work = str(tmp_path / "work")

    def run_sweep(t_end=0.02, dt=0.002, variant_set=""):
        path = tmp_path / "tiny.toml"
        path.write_text(SWEEP.format(t_end=t_end, dt=dt, variant_set=variant_set))
        runner.resolved_scene.cache_clear()  # a sweep reads its scene once; this test edits it in between
        s = specs.load_sweep(str(path), reduced=False)
        ran.clear()
        summaries = [runner.execute(s, work, r) for r in specs.run_list(s)]
        assert all(sm["stats"]["ok"] for sm in summaries), [sm["stats"]["failure"] for sm in summaries]
        return s, sorted(os.path.relpath(d, work) for d in ran)

    return work, run_sweep


@pytest.fixture
def setup(tmp_path, monkeypatch):
    """A copy of passive_arm.toml the test may edit, and the tiny sweep over it."""
    scene = tmp_path / "passive_arm.toml"
    shutil.copy(os.path.join(SCENES, "passive_arm.toml"), scene)
    return (scene,) + _tiny_sweep(tmp_path, monkeypatch, scene)


ALL = ["base/check", "base/reference", "base/rk4_dt0.002"]


def test_a_finished_run_is_reused_only_while_nothing_that_determines_it_changed(setup):
    scene, work, run_sweep = setup
    s, ran = run_sweep()
    assert ran == ALL
    assert run_sweep()[1] == [], "nothing changed: every run reused"
    # t_end: every run again, and its trajectory ends at the new horizon.
    assert run_sweep(t_end=0.03)[1] == ALL
    assert pumasim_io.read_stats(os.path.join(work, "base", "reference"))["t_end"] == 0.03
    assert run_sweep(t_end=0.03)[1] == []
    # The scene file itself (a value the sweep does not set).
    scene.write_text(scene.read_text().replace("output_interval = 0.01", "output_interval = 0.005"))
    assert run_sweep(t_end=0.03)[1] == ALL
    assert run_sweep(t_end=0.03)[1] == []
    # A variant's --set: that variant's runs (here all of them).
    assert run_sweep(t_end=0.03, variant_set='"friction.viscous=1e-3"')[1] == ALL
    # A method's setting: a new run; the reference and check are reused.
    assert run_sweep(t_end=0.03, variant_set='"friction.viscous=1e-3"', dt=0.001)[1] == ["base/rk4_dt0.001"]


def test_another_program_reruns_and_merge_refuses_stale_runs(setup, monkeypatch):
    scene, work, run_sweep = setup
    s, ran = run_sweep()
    assert ran == ALL
    # The summaries record the program's identity: pumasim --version (its revision, compiler, flags).
    version = subprocess.run([pumasim_io.PUMASIM, "--version"], capture_output=True, text=True, check=True).stdout
    assert pumasim_io.read_json(os.path.join(work, "base", "reference.json"))["program"].startswith(version.strip())
    # The scene changes after the runs: --merge refuses to mix them in.
    scene.write_text(scene.read_text().replace("duration = 2.0", "duration = 1.5"))
    runner.resolved_scene.cache_clear()
    with pytest.raises(specs.SweepError, match="base/check .* was made from another scene, setting or program"):
        merge.merge(s, work, str(os.path.dirname(work) + "/out"))
    assert run_sweep()[1] == ALL
    # Another build of pumasim: everything again.
    monkeypatch.setattr(runner, "program_identity", lambda pumasim: "pumasim 0000000 (another build)")
    assert run_sweep()[1] == ALL
    assert run_sweep()[1] == []


def _urdf_scene(tmp_path):
    """passive_arm on a copy of the shipped PUMA URDF and its side file (the
    input-file tests' scene)."""
    return test_input_files.urdf_scene(tmp_path)


def _copied_scene(name, csv):
    def make(tmp_path):
        shutil.copy(os.path.join(SCENES, csv), tmp_path / csv)
        shutil.copy(os.path.join(SCENES, name), tmp_path / name)
        return tmp_path / name
    return make


def _bump_last_digit(path):
    """Changes the last digit of the CSV's first value after a comma (the
    first row's first joint value): still a valid file."""
    text = path.read_text()
    m = re.search(r"(?<=,)-?\d+\.\d+", text)
    assert m, f"{path}: no value to change"
    d = m.end() - 1
    path.write_text(text[:d] + str((int(text[d]) + 1) % 10) + text[d + 1:])


def _rotor_inertia_times_100(path):
    """The side file's rotor inertias x 100 (the issue's reproducer)."""
    text, n = re.subn(r"(rotor_inertia\s*=\s*)([0-9.e+-]+)", lambda m: m.group(1) + repr(float(m.group(2)) * 100),
                      path.read_text())
    assert n > 0, f"{path}: no rotor_inertia"
    path.write_text(text)


def _urdf_mass_changed(path):
    """The first link with mass: its mass x 1.01."""
    text = path.read_text()
    m = next(m for m in re.finditer(r'<mass value="([^"]*)"', text) if float(m.group(1)) > 0)
    path.write_text(text[:m.start(1)] + repr(float(m.group(1)) * 1.01) + text[m.end(1):])


# (scene maker, file edited, edit): every kind of file a scene reads besides
# the scene file (tested above) re-runs the sweep when its content changes.
EDITS = {
    "urdf side file": (_urdf_scene, "puma560.urdf.toml", _rotor_inertia_times_100),
    "urdf": (_urdf_scene, "puma560.urdf", _urdf_mass_changed),
    "joint-space reference csv": (_copied_scene("joint_space_csv.toml", "joint_space_csv.csv"),
                                  "joint_space_csv.csv", _bump_last_digit),
    "open-loop input csv": (_copied_scene("open_loop_voltage.toml", "open_loop_voltage.csv"),
                            "open_loop_voltage.csv", _bump_last_digit),
}


@pytest.mark.parametrize("kind", sorted(EDITS))
def test_editing_any_file_the_scene_reads_reruns_and_merge_refuses_the_old_runs(tmp_path, monkeypatch, kind):
    make, edited, edit = EDITS[kind]
    scene = make(tmp_path)
    work, run_sweep = _tiny_sweep(tmp_path, monkeypatch, scene)
    s, ran = run_sweep()
    assert ran == ALL
    assert run_sweep()[1] == []
    edit(tmp_path / edited)
    runner.resolved_scene.cache_clear()
    with pytest.raises(specs.SweepError, match="was made from another scene, setting or program"):
        merge.merge(s, work, str(tmp_path / "out"))
    assert run_sweep()[1] == ALL, f"{kind} edited: every run again"
    assert run_sweep()[1] == []


def test_relative_work_and_out_folders_are_the_callers(tmp_path):
    """Issue 32: `sweep.py --work <relative>` wrote its runs under the project
    root (pumasim runs there) and then found no run folder. Both folders are
    taken relative to the caller's working directory."""
    (tmp_path / "tiny.toml").write_text(SWEEP.format(t_end=0.02, dt=0.002, variant_set=""))
    env = dict(os.environ, PUMASIM=pumasim_io.PUMASIM)
    p = subprocess.run([sys.executable, os.path.join(pumasim_io.ROOT, "experiments", "sweep.py"), "tiny.toml",
                        "--work", "rel_work", "--out", "rel_out", "--jobs", "1"],
                       cwd=tmp_path, env=env, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "rel_work" / "base" / "reference" / "stats.json").exists()
    assert (tmp_path / "rel_out" / "tiny.csv").exists()
    assert not os.path.exists(os.path.join(pumasim_io.ROOT, "rel_work"))
