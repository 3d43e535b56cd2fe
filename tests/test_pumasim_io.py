"""Tests of experiments/pumasim_exp/io.py on hand-made run folders and tables.

    /usr/bin/python3 -m pytest -q tests/test_pumasim_io.py
"""
import os
import socket
import subprocess
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "experiments"))
from pumasim_exp import io as pumasim_io  # noqa: E402

MARKER = ("# a pumasim run folder: the files pumasim wrote here (it replaces the folder only with --force,\n"
          "# and only while nothing else is in it)\n")  # as simulation/run_folder.cpp writes it
TRAJECTORY = ("t [s],q1 [rad],qd1 [rad/s],x [m],path_error [mm]\n"
              "0,0.5,0,0.1,0\n"
              "0.01,0.5001,0.02,0.1001,1e-05\n"
              "0.02,0.5004,0.04,0.1004,-2.5e-05\n")
STATS = '{\n  "scene": "hand_made",\n  "ok": true,\n  "steps": 20,\n  "wall_time_s": null\n}\n'
META = '{\n  "git_revision": "abc123"\n}\n'


def make_run(folder, trajectory=TRAJECTORY, marker=True, files=None):
    files = files if files is not None else {"trajectory.csv": trajectory, "stats.json": STATS, "meta.json": META,
                                             "scene.resolved.toml": "[scene]\n"}
    os.makedirs(folder)
    for name, text in files.items():
        with open(os.path.join(folder, name), "w") as f:
            f.write(text)
    if marker:
        with open(os.path.join(folder, pumasim_io.RUN_MARKER), "w") as f:
            f.write(MARKER + "".join(n + "\n" for n in files))
    return str(folder)


def test_loads_a_run_folder(tmp_path):
    run = pumasim_io.load_run(make_run(tmp_path / "run"))
    assert run.stats == {"scene": "hand_made", "ok": True, "steps": 20, "wall_time_s": None}
    assert run.meta == {"git_revision": "abc123"}
    tr = run.trajectory
    assert tr.names == ["t", "q1", "qd1", "x", "path_error"]
    assert tr.units == ["s", "rad", "rad/s", "m", "mm"]
    assert tr.header[1] == "q1 [rad]"
    assert len(tr) == 3 and tr.data.shape == (3, 5)
    np.testing.assert_array_equal(tr["t"], [0.0, 0.01, 0.02])
    assert tr.lists()["path_error"] == [0.0, 1e-05, -2.5e-05]
    assert list(tr.arrays()) == tr.names
    assert tr.text[-1] == ["0.02", "0.5004", "0.04", "0.1004", "-2.5e-05"]  # the cells as written
    with pytest.raises(KeyError, match="no column 'q2'"):
        tr["q2"]


def test_refuses_a_folder_without_the_marker(tmp_path):
    folder = make_run(tmp_path / "run", marker=False)
    for read in (pumasim_io.load_run, pumasim_io.read_stats, pumasim_io.read_meta, pumasim_io.read_trajectory):
        with pytest.raises(pumasim_io.RunFolderError, match="not a pumasim run folder"):
            read(folder)


def test_refuses_a_marker_that_is_not_pumasims(tmp_path):
    folder = make_run(tmp_path / "run")
    with open(os.path.join(folder, pumasim_io.RUN_MARKER), "w") as f:
        f.write("trajectory.csv\nstats.json\n")
    with pytest.raises(pumasim_io.RunFolderError, match="does not start with"):
        pumasim_io.load_run(folder)


def test_refuses_a_folder_missing_a_listed_file(tmp_path):
    folder = make_run(tmp_path / "run")
    os.remove(os.path.join(folder, "meta.json"))
    with pytest.raises(pumasim_io.RunFolderError, match="meta.json listed .* but absent"):
        pumasim_io.load_run(folder)


def test_refuses_a_marker_without_the_trajectory(tmp_path):
    folder = make_run(tmp_path / "run", files={"stats.json": STATS})
    assert pumasim_io.read_stats(folder)["steps"] == 20
    with pytest.raises(pumasim_io.RunFolderError, match="does not list trajectory.csv"):
        pumasim_io.load_run(folder)


@pytest.mark.parametrize("cut", [len(TRAJECTORY) - 1,   # the last line lost its end
                                 len(TRAJECTORY) - 6,   # a row cut in the middle of a number
                                 TRAJECTORY.index("0.01,") + 12])  # cut after a few cells
def test_detects_a_truncated_trajectory(tmp_path, cut):
    folder = make_run(tmp_path / "run", trajectory=TRAJECTORY[:cut])
    with pytest.raises(pumasim_io.RunFolderError, match="truncated"):
        pumasim_io.read_trajectory(folder)


def test_detects_a_short_row_and_a_cell_that_is_no_number(tmp_path):
    short = TRAJECTORY.replace("0.01,0.5001,0.02,0.1001,1e-05\n", "0.01,0.5001,0.02\n")
    with pytest.raises(pumasim_io.RunFolderError, match="row 2 has 3 cells, the header 5"):
        pumasim_io.parse_trajectory(short)
    with pytest.raises(pumasim_io.RunFolderError, match="not a number"):
        pumasim_io.parse_trajectory(TRAJECTORY.replace("0.5001", "0.50x1"))
    with pytest.raises(pumasim_io.RunFolderError, match="empty"):
        pumasim_io.parse_trajectory("")


def test_a_header_only_trajectory_has_no_rows(tmp_path):
    tr = pumasim_io.parse_trajectory(TRAJECTORY.splitlines(keepends=True)[0])
    assert len(tr) == 0 and tr.names[0] == "t" and tr["q1"].shape == (0,)


def test_sweep_table_round_trips(tmp_path):
    path = str(tmp_path / "sweep.csv")
    rows = [{"variant": "base", "integrator": "rk4", "setting": "dt=0.0005", "ok": True, "failure": "",
             "max_tool_position_error_mm": 0.0012345678, "rhs_evaluations": 192004},
            {"variant": "base", "integrator": "cvode-bdf", "setting": "rtol=1e-06", "ok": False,
             "failure": 'step size too small at t = 1.5, "q1", a, b', "max_tool_position_error_mm": float("nan"),
             "rhs_evaluations": 812, "extra": "only here"}]
    comments = ["sweep experiments/sweeps/x.toml: scene x", "ranked by max tool position error [mm]"]
    pumasim_io.write_table(path, rows, comments=comments, fmt=pumasim_io.fmt_6g)
    assert not os.path.exists(path + ".tmp")
    t = pumasim_io.read_table(path)
    assert t.comments == comments
    assert t.columns == list(rows[0]) + ["extra"]  # every key, in order of appearance
    assert len(t) == 2
    assert t.rows[0] == {"variant": "base", "integrator": "rk4", "setting": "dt=0.0005", "ok": "True", "failure": "",
                         "max_tool_position_error_mm": "0.00123457", "rhs_evaluations": "192004", "extra": ""}
    assert t.rows[1]["failure"] == rows[1]["failure"] and t.rows[1]["max_tool_position_error_mm"] == "nan"
    assert t.rows[1]["extra"] == "only here"
    # Written again from what was read: the same bytes.
    with open(path, "rb") as f:
        first = f.read()
    pumasim_io.write_table(path, t.rows, columns=t.columns, comments=t.comments)
    with open(path, "rb") as f:
        assert f.read() == first
    assert first.startswith(b"# sweep experiments/sweeps/x.toml: scene x\n# ranked by")
    assert b"\r\n" in first  # csv's row ends, as the committed tables have them


def test_table_columns_are_the_header(tmp_path):
    path = str(tmp_path / "t.csv")
    with open(path, "w") as f:
        f.write("# a comment\n# another\nscene,integrator,observed_slope\nsmooth,rk4,3.98\npaper,ab2,2.01\n")
    t = pumasim_io.read_table(path)
    assert t.columns == ["scene", "integrator", "observed_slope"]
    assert [r["integrator"] for r in t] == ["rk4", "ab2"]
    assert t.comments == ["a comment", "another"]
    assert pumasim_io.fnum(t.rows[0]["observed_slope"]) == 3.98 and np.isnan(pumasim_io.fnum(""))
    # Columns chosen by the writer, in its order; keys outside them are left out.
    pumasim_io.write_table(path, [{"b": 1, "a": 0.1, "c": "x"}], columns=["a", "b"], lineterminator="\n")
    with open(path) as f:
        assert f.read() == "a,b\n0.1,1\n"
    assert pumasim_io.read_table(path).columns == ["a", "b"]


def test_an_empty_table_has_no_columns():
    t = pumasim_io.parse_table("")
    assert t.columns == [] and t.rows == [] and t.comments == []


def test_list_in_marker_adds_only_new_names(tmp_path):
    folder = make_run(tmp_path / "run")
    pumasim_io.list_in_marker(folder, ["path_xy.png", "stats.json"])
    assert pumasim_io.marker_entries(folder) == ["trajectory.csv", "stats.json", "meta.json",
                                                 "scene.resolved.toml", "path_xy.png"]
    pumasim_io.list_in_marker(str(tmp_path), ["x.png"])  # no run folder: nothing written
    assert not os.path.exists(tmp_path / pumasim_io.RUN_MARKER)


def test_remove_run_folder_removes_only_a_pumasim_run_folder(tmp_path):
    run = make_run(tmp_path / "run")
    pumasim_io.remove_run_folder(run)
    assert not os.path.exists(run)
    pumasim_io.remove_run_folder(run)  # absent: nothing to do
    # A file the marker does not list, or no marker: nothing removed.
    run = make_run(tmp_path / "run")
    (tmp_path / "run" / "mine.txt").write_text("x")
    with pytest.raises(pumasim_io.RunFolderError, match="mine.txt, which pumasim did not write"):
        pumasim_io.remove_run_folder(run)
    assert sorted(os.listdir(run)) == sorted([*pumasim_io.RUN_FILES, pumasim_io.RUN_MARKER, "mine.txt"])
    other = make_run(tmp_path / "other", marker=False)
    with pytest.raises(pumasim_io.RunFolderError, match="not a pumasim run folder"):
        pumasim_io.remove_run_folder(other)
    # A removal killed half-way (files gone, the marker left; or only the empty folder): removable.
    half = make_run(tmp_path / "half")
    os.remove(os.path.join(half, "trajectory.csv"))
    pumasim_io.remove_run_folder(half)
    os.makedirs(half)
    pumasim_io.remove_run_folder(half)
    assert not os.path.exists(half)


def test_an_output_set_is_checked_against_its_summary(tmp_path):
    def writer(text):
        return lambda p: _write(p, text)
    (tmp_path / "notes.txt").write_text("not ours")
    s = pumasim_io.write_output_set(str(tmp_path), {"a.csv": writer("1,2\n"), "a.png": writer("png")},
                                    "a_summary.json", {"name": "a"})
    assert pumasim_io.read_json(tmp_path / "a_summary.json") == s and s["name"] == "a"
    pumasim_io.check_outputs(str(tmp_path), s)
    assert sorted(os.listdir(tmp_path)) == ["a.csv", "a.png", "a_summary.json", "notes.txt"]
    (tmp_path / "a.csv").write_text("1,3\n")  # another merge's table beside this summary
    with pytest.raises(pumasim_io.OutputsMismatch, match="a.csv is not the file the summary describes"):
        pumasim_io.check_outputs(str(tmp_path), s)
    os.remove(tmp_path / "a.png")
    with pytest.raises(pumasim_io.OutputsMismatch, match="a.png is missing"):
        pumasim_io.check_outputs(str(tmp_path), {"outputs": {"a.png": ""}})
    with pytest.raises(pumasim_io.OutputsMismatch, match="lists no hashes"):
        pumasim_io.check_outputs(str(tmp_path), {"name": "a"})


def test_a_failed_output_set_changes_nothing_and_dead_temporaries_go(tmp_path):
    (tmp_path / "a.csv").write_text("old\n")

    def fail(p):
        _write(p, "half")
        raise OSError(28, "No space left on device")
    with pytest.raises(OSError) as e:
        pumasim_io.write_output_set(str(tmp_path), {"a.csv": lambda p: _write(p, "new\n"), "a.png": fail},
                                    "a_summary.json", {})
    assert e.value.filename == str(tmp_path / "a.png")  # the file meant, not its temporary
    assert os.listdir(tmp_path) == ["a.csv"] and (tmp_path / "a.csv").read_text() == "old\n"
    # A killed writer's temporary (its process gone) is removed; a live one's and others' files stay.
    dead = _dead_pid()
    host = socket.gethostname()
    for pid in (dead, os.getpid()):
        (tmp_path / f".a.csv.{host}.{pid}.tmp").write_text("x")
    (tmp_path / f".b.csv.{host}.{dead}.tmp").write_text("x")
    pumasim_io.remove_dead_temporaries(str(tmp_path), ["a.csv"])
    assert sorted(os.listdir(tmp_path)) == sorted(["a.csv", f".a.csv.{host}.{os.getpid()}.tmp",
                                                   f".b.csv.{host}.{dead}.tmp"])


def _write(path, text):
    with open(path, "w") as f:
        f.write(text)


def _dead_pid():
    """The process id of a process that has ended."""
    p = subprocess.Popen(["true"])
    p.wait()
    return p.pid


def test_a_file_lock_excludes_another_holder_until_released(tmp_path):
    a, b = pumasim_io.FileLock(str(tmp_path / "x.lock")), pumasim_io.FileLock(str(tmp_path / "x.lock"))
    assert a.acquire(wait=False)
    assert not b.acquire(wait=False)
    a.release()
    assert b.acquire(wait=False)
    b.release()
