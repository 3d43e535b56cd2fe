"""experiments/report.py checks every hand-written finding against its table
(experiments/findings.py): the committed tables support every sentence, a
changed table fails the report naming the sentence and the row, and the
checker's assertions mean what the format says. Runs no simulation.

    /usr/bin/python3 -m pytest -q tests/test_report_claims.py
"""
import glob
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tomllib

import pytest

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
sys.path.insert(0, os.path.join(ROOT, "experiments"))
import findings  # noqa: E402
import pumasim_io  # noqa: E402
import report  # noqa: E402

PY = "/usr/bin/python3"
RESULTS = os.path.join(ROOT, "results")
HYBRID = "paper_slow_6dof_hybrid"
FIXED = ["euler", "ab2", "ab3", "ab4", "rk4"]


def committed(name):
    """(summary, raw CSV rows) of a committed sweep."""
    path = glob.glob(os.path.join(RESULTS, "*", name + "_summary.json"))[0]
    return pumasim_io.read_json(path), report.read_csv(path.replace("_summary.json", ".csv"))


def problems_of(summary, rows):
    checks = report.Checks(RESULTS, omit=False)
    report.sweep_findings(summary, rows, checks)
    return checks.problems


def sweep_names():
    return sorted(os.path.splitext(os.path.basename(p))[0] for p in glob.glob(os.path.join(ROOT, "experiments",
                                                                                             "sweeps", "*.toml")))


@pytest.mark.parametrize("name", sweep_names())
def test_every_sweep_states_checked_findings_and_its_committed_table_supports_them(name):
    found = findings.sweep_findings(os.path.join(ROOT, "experiments", "sweeps", name + ".toml"))
    assert found, f"{name}: no findings"
    assert all(f.get("assert") for f in found if "unchecked" not in f)
    assert problems_of(*committed(name)) == []


def test_the_planning_findings_hold_on_the_committed_table():
    checks = report.Checks(RESULTS, omit=False)
    lines = report.planning_findings(report.read_csv(os.path.join(RESULTS, "planning", "planning.csv")), checks)
    assert checks.problems == [] and lines and "time-optimal" in lines[0]


def test_the_committed_results_readme_is_what_the_report_writes(tmp_path):
    """The report passes on the committed tables, and results/README.md is its
    output (up to the links, relative to where it is written)."""
    out = tmp_path / "README.md"
    p = subprocess.run([PY, os.path.join(ROOT, "experiments", "report.py"), "--out", str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    rel = os.path.relpath(RESULTS, tmp_path) + "/"
    with open(os.path.join(RESULTS, "README.md")) as f:
        assert out.read_text().replace(rel, "") == f.read()


def test_the_6_joint_hybrid_sentence_the_issue_quotes_fails_against_its_table():
    """Issue 31: 'no fixed-step method reaches the target' beside a table that
    lists ab2, ab3, ab4 and euler within it. As a checked finding it fails,
    naming the sentence and a fixed-step row within the target."""
    summary, rows = committed(HYBRID)
    old = [{"text": "Fixed-step methods see each event only at the end of a step: their error stalls far above the "
                    "target at every step tried, so none reaches it.",
            "assert": [{"rows": {"integrator": FIXED}, "none": "within"}]}]
    (problem,) = findings.check(old, report.sweep_tables(summary, rows), "issue 31")
    assert "none reaches it" in problem and "within" in problem
    assert any(f" {n} dt=" in problem for n in FIXED), problem


def changed(rows, integrator, setting, **cells):
    """A copy of rows with one run's cells replaced."""
    out = [dict(r) for r in rows]
    hit = [r for r in out if r["integrator"] == integrator and r["setting"] == setting]
    assert len(hit) == 1
    hit[0].update(cells)
    return out


def test_a_changed_table_fails_the_finding_it_contradicts_naming_sentence_and_row():
    summary, rows = committed(HYBRID)
    bad = changed(rows, "euler", "dt=0.0005", max_tool_position_error_mm="0.02")
    problems = problems_of(summary, bad)
    assert len(problems) == 1, problems
    assert "every one reaches the target at 0.5 ms and less" in problems[0]
    assert "euler dt=0.0005" in problems[0] and "within=False" in problems[0]
    # An adaptive method that no longer reaches the target anywhere fails the first sentence.
    bad = [dict(r, max_tool_position_error_mm="1") if r["integrator"] == "cvode-bdf" else r for r in rows]
    (problem,) = problems_of(summary, bad)
    assert "every one reaches the accuracy target" in problem and "integrator=cvode-bdf" in problem


def test_a_changed_reference_or_creep_table_fails_too():
    summary, rows = committed("saturation")
    weak = json.loads(json.dumps(summary))
    weak["agreement"]["1.2m/s"]["max_tool_position_error_mm"] = 4e-3
    (problem,) = problems_of(weak, rows)
    assert "less than a thousandth of the target" in problem and "1.2m/s" in problem
    summary, rows = committed("stick_slip")
    still = json.loads(json.dumps(summary))
    still["creep"]["karnopp"]["rad"] = 0.0
    problems = problems_of(still, rows)
    assert any("every other friction law lets it move" in p and "karnopp" in p for p in problems), problems


def test_a_dropped_row_fails_instead_of_passing_vacuously():
    summary, rows = committed(HYBRID)
    problems = problems_of(summary, [r for r in rows if r["integrator"] != "ab4"])
    assert problems and all("ab4" in p and "matches no row" in p for p in problems), problems


def sha256(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def test_the_report_exits_non_zero_and_writes_nothing_when_a_table_contradicts_a_finding(tmp_path):
    """report.py itself, on a results folder whose 6-joint table is changed
    (its summary's hashes updated, as a real merge would write them)."""
    res = tmp_path / "results"
    folder = res / "work_precision"
    folder.mkdir(parents=True)
    for ext in (".csv", ".png", "_summary.json"):
        shutil.copy(os.path.join(RESULTS, "work_precision", HYBRID + ext), folder)
    csv = folder / (HYBRID + ".csv")
    text = csv.read_text()
    old = "base,0,ab2,dt=0.0005,True,,0.000961997,"
    assert old in text
    csv.write_text(text.replace(old, "base,0,ab2,dt=0.0005,True,,0.0961997,"))
    summary_path = folder / (HYBRID + "_summary.json")
    summary = json.loads(summary_path.read_text())
    summary["outputs"][HYBRID + ".csv"] = sha256(csv)
    summary_path.write_text(json.dumps(summary))
    out = tmp_path / "README.md"
    cmd = [PY, os.path.join(ROOT, "experiments", "report.py"), "--results", str(res), "--out", str(out)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    assert p.returncode == 1 and not out.exists()
    assert "Traceback" not in p.stderr
    assert f"experiments/sweeps/{HYBRID}.toml: finding 3" in p.stderr and "ab2 dt=0.0005" in p.stderr, p.stderr
    assert "every one reaches the target at 0.5 ms and less" in p.stderr
    # --omit-findings (tables the findings were not written about): the report is written, without them.
    p = subprocess.run(cmd + ["--omit-findings"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert "Fixed-step methods see each event" not in out.read_text()


RUNS = [{"variant": "v", "integrator": n, "setting": s, "ok": ok, "failure": fail, "err": e, "rhs_evaluations": rhs}
        for n, s, ok, fail, e, rhs in [
            ("a", "dt=0.002", "False", "non-finite state at t = 0.5 s", "nan", "10"),
            ("a", "dt=0.001", "True", "", "0.004", "200"),
            ("a", "dt=0.0005", "True", "", "0.001", "400"),
            ("b", "rtol=0.001", "True", "", "0.02", "50"),
            ("b", "rtol=0.0001", "True", "", "0.003", "90"),
            ("b", "rtol=1e-06", "False", "b: step budget of 10 steps exhausted at t = 2.5", "nan", "999")]]


def verdict(**assertion):
    """check_assertion's answer on RUNS (target 0.005 in the column err)."""
    table = [findings.run_row(r, "err", 0.005) for r in RUNS]
    return findings.check_assertion(assertion, table, "test")


def test_the_assertions_mean_what_the_format_says():
    assert verdict(rows={"integrator": "a"}, per="integrator", some="within") is None
    assert verdict(all="within or not ok or rhs_evaluations < 100") is None
    assert "fails at v a dt=0.0005" in verdict(rows={"ok": True}, all="error > 0.002")
    assert verdict(rows={"ok": False}, all="failed_at in (0.5, 2.5)") is None
    assert verdict(none="within and rtol == 1e-3") is None
    assert verdict(most="ok") is None and "holds for 1 of 6" in verdict(most="within and dt is None")
    assert "no row of integrator=b" in verdict(per="integrator", some="within and dt is not None")
    # pick: the cheapest run within the target per integrator; than/match: pairs.
    assert verdict(pick="cheapest", all="rhs_evaluations in (200, 90)") is None
    assert verdict(rows={"integrator": "b"}, pick="cheapest", than={"integrator": "a"},
                   all="rhs_evaluations < other.rhs_evaluations") is None
    assert verdict(rows={"integrator": "a", "ok": True}, match="integrator",
                   all="not (dt < other.dt) or error < other.error") is None
    assert verdict(group="integrator", values={"spread": "max(rhs_evaluations) / min(rhs_evaluations)"},
                   all="spread > 8") is None
    # Vacuous selections fail.
    assert "matches no row" in verdict(rows={"integrator": ["a", "c"]}, all="True")
    assert "selects no row" in verdict(rows={"integrator": "b", "rtol": 1e-6}, pick="cheapest", all="True")
    assert "no row to compare" in verdict(rows={"integrator": "a"}, than={"integrator": "b"}, match="setting",
                                          all="True")


@pytest.mark.parametrize("assertion", [
    {"all": "__import__('os')"}, {"all": "error.real > 0"}, {"all": "open('x')"}, {"all": "within", "none": "ok"},
    {"some": "ok", "rows": "a"}, {"all": "ok", "colour": "red"}, {"all": "ok", "rows": {"no_such_column": 1}},
    {"all": "ok", "pick": "dearest"}])
def test_malformed_assertions_are_refused_not_evaluated(assertion):
    with pytest.raises(findings.FindingsError):
        verdict(**assertion)


def test_every_finding_needs_assertions_or_a_reason_it_has_none():
    table = {"runs": [findings.run_row(r, "err", 0.005) for r in RUNS]}
    for bad in ["a plain string", [{"text": "no assertion"}], [{"text": "both", "unchecked": "why",
                                                                 "assert": [{"all": "ok"}]}]]:
        with pytest.raises(findings.FindingsError):
            findings.check(bad, table, "test")
    assert findings.check([{"text": "A remark.", "unchecked": "on the sweep's design"}], table, "test") == []


def test_a_sweep_file_with_findings_still_loads_in_sweep_py():
    """The findings sit in [sweep] (sweep.py's known key 'findings'), and
    sweep.py still reads every sweep file."""
    import sweep
    for name in sweep_names():
        path = os.path.join(ROOT, "experiments", "sweeps", name + ".toml")
        with open(path, "rb") as f:
            assert isinstance(tomllib.load(f)["sweep"]["findings"], list)
        s, _ = sweep._sweep_table(path, sweep._read_toml(path))
        assert s["findings"], name
