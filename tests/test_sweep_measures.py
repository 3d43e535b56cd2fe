"""A sweep's "cheapest within target" judges a run on every error measure
the sweep has a target for (but a measure a variant has no states for, as
the currents with La = 0), and names the measure that disqualifies a run
cheaper on the ranking measure alone; each adaptive run's error is reported
over its rtol, and per method the slope of log(error) against log(rtol)
(issue 31). On synthetic rows (experiments/sweep.py's merge step and
experiments/precision_table.py; no pumasim run):

    /usr/bin/python3 -m pytest -q tests/test_sweep_measures.py
"""
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "experiments"))
import precision_table  # noqa: E402
from pumasim_exp import measures  # noqa: E402

POSITION, CURRENT = "max_tool_position_error_mm", "max_current_error_A"


def _sweep(targets):
    """The parts of a loaded sweep the merge step's tables read."""
    return {"name": "tiny", "title": "Tiny", "file": "experiments/sweeps/tiny.toml", "rank_by": "tool_position",
            "targets": targets, "variants": [{"label": "base", "value": 1.0}]}


def _row(integrator, setting, rhs, position, current, ok=True, state=math.nan, targets=None):
    """A CSV row as _run_row makes it (the columns the tables read)."""
    r = {"variant": "base", "value": 1.0, "integrator": integrator, "setting": setting, "ok": ok,
         POSITION: position if ok else math.nan, "max_tool_orientation_error_rad": 1e-6 if ok else math.nan,
         "max_joint_error_rad": 1e-6 if ok else math.nan, CURRENT: current if ok else math.nan,
         "max_state_error": state if ok else math.nan, "rhs_evaluations": rhs, "below_reference_accuracy": False,
         "wall_time_median_s": 0.01, "wall_time_min_s": 0.01, "wall_time_max_s": 0.01}
    rtol = float(setting.split("=")[1].split("_")[0]) if setting.startswith("rtol=") else None
    r["error_over_rtol"] = "" if rtol is None else r["max_state_error"] / rtol
    missed = measures.disqualified_by(r, targets or {})
    r["within_targets"], r["disqualified_by"] = not missed, " ".join(missed)
    return r


TARGETS = {POSITION: 5e-3, CURRENT: 1.0}
AGREEMENT = {"base": {POSITION: 1e-6, CURRENT: 1e-6, "max_state_error": 1e-12, "reference_too_weak": []}}


def _ab3_rows(targets=TARGETS):
    """The committed paper_slow_6dof_hybrid's case: AB3 at dt = 0.5 ms within
    the position target (0.002 mm) with a 48 A current error; at 0.25 ms
    within both."""
    return [_row("ab3", "dt=0.001", 40_000, 0.3, 200.0, targets=targets),
            _row("ab3", "dt=0.0005", 80_971, 0.00202, 48.3, targets=targets),
            _row("ab3", "dt=0.00025", 160_000, 0.0004, 0.2, targets=targets),
            _row("ab3", "dt=0.002", 20_000, 0.0, 0.0, ok=False, targets=targets)]


def test_a_run_past_the_current_target_does_not_qualify():
    rows = _ab3_rows()
    by_setting = {r["setting"]: r for r in rows}
    assert by_setting["dt=0.0005"]["within_targets"] is False
    assert by_setting["dt=0.0005"]["disqualified_by"] == "current"
    assert by_setting["dt=0.001"]["disqualified_by"] == "tool_position current"
    assert by_setting["dt=0.002"]["disqualified_by"] == "failed"
    assert by_setting["dt=0.00025"]["within_targets"] is True
    cost = measures.cost_to_target(_sweep(TARGETS), rows, AGREEMENT, ["ab3"])
    assert [(c["setting"], c["rhs"]) for c in cost["ab3"]] == [("dt=0.00025", 160_000)]


def test_the_table_names_the_measure_that_disqualifies():
    s, rows = _sweep(TARGETS), _ab3_rows()
    disq = measures.disqualified_cheapest(s, rows, ["ab3"])
    assert disq == [{"integrator": "ab3", "variant": "base", "setting": "dt=0.0005", "rhs": 80_971,
                     "measures": [{"measure": "current", "error": 48.3, "target": 1.0}]}]
    cost = measures.cost_to_target(s, rows, AGREEMENT, ["ab3"])
    text = precision_table.markdown(s, rows, [], cost, disq, measures.MEASURES, measures.BELOW_REFERENCE_FACTOR)
    line = next(x for x in text.splitlines() if x.startswith("| ab3 |"))
    assert "160,000 (dt=0.00025)" in line
    assert "dt=0.0005 (80,971 RHS) misses max motor-current error 48.3 A > 1 A" in line
    assert "max motor-current error 1 A" in text  # the targets are listed


def test_without_a_current_target_position_alone_decides():
    targets = {POSITION: 5e-3}
    rows = _ab3_rows(targets)
    cost = measures.cost_to_target(_sweep(targets), rows, AGREEMENT, ["ab3"])
    assert [c["setting"] for c in cost["ab3"]] == ["dt=0.0005"]
    assert measures.disqualified_cheapest(_sweep(targets), rows, ["ab3"]) == []


def test_no_qualifying_run_is_a_dash_with_the_measure_named():
    s = _sweep(TARGETS)
    rows = [_row("ab2", "dt=0.001", 1000, 1e-3, 30.0, targets=TARGETS)]
    cost = measures.cost_to_target(s, rows, AGREEMENT, ["ab2"])
    disq = measures.disqualified_cheapest(s, rows, ["ab2"])
    text = precision_table.markdown(s, rows, [], cost, disq, measures.MEASURES, measures.BELOW_REFERENCE_FACTOR)
    line = next(x for x in text.splitlines() if x.startswith("| ab2 |"))
    assert line.startswith("| ab2 | –; dt=0.001 (1,000 RHS) misses max motor-current error 30 A > 1 A")


def test_error_over_rtol_and_its_slope_per_method():
    # cvode-bdf: error 15 x rtol at every tolerance (slope 1); the tightest run
    # within 10x of the reference's accuracy (1e-12): left out of the slope.
    rows = [_row("cvode-bdf", f"rtol={r:g}", 100, 1e-3, 1e-3, state=15 * r) for r in (1e-3, 1e-5, 1e-7, 1e-9)]
    rows.append(_row("cvode-bdf", "rtol=1e-12", 100, 1e-3, 1e-3, state=5e-12))
    # odeint-rodas4p with late events: error ~ rtol^0.8, two runs (a marked slope); a failed run.
    rows += [_row("odeint-rodas4p", f"rtol={r:g}_late-events", 100, 1e-3, 1e-3, state=r ** 0.8) for r in (1e-4, 1e-6)]
    rows.append(_row("odeint-rodas4p", "rtol=1e-08_late-events", 100, 1e-3, 1e-3, ok=False))
    rows.append(_row("rk4", "dt=0.001", 100, 1e-3, 1e-3, state=1e-9))  # fixed step: no ratio
    assert rows[0]["error_over_rtol"] == 15 and rows[-1]["error_over_rtol"] == ""
    slopes = {(m["integrator"], m["options"]): m for m in
              precision_table.tolerance_slopes(rows, AGREEMENT, measures.BELOW_REFERENCE_FACTOR)}
    assert set(slopes) == {("cvode-bdf", ""), ("odeint-rodas4p", "late-events")}
    bdf, rodas = slopes[("cvode-bdf", "")], slopes[("odeint-rodas4p", "late-events")]
    assert abs(bdf["slope"] - 1) < 1e-12 and bdf["used"] == 4 and bdf["mark"] == ""
    assert abs(rodas["slope"] - 0.8) < 1e-12 and rodas["used"] == 2 and rodas["mark"] == "fewer than 3 runs"
    text = "\n".join(precision_table.proportionality_section(list(slopes.values()), measures.BELOW_REFERENCE_FACTOR))
    assert "| base | cvode-bdf | – | 1e-03: 15, 1e-05: 15, 1e-07: 15, 1e-09: 15, 1e-12: 5* | 1.00 (4) |" in text
    assert "| base | odeint-rodas4p | late-events | 1e-04: 6.31, 1e-06: 15.8, 1e-08: –* | 0.80 (2) † |" in text


def test_a_variant_without_current_states_is_not_judged_on_currents():
    """stiff_armature's La=0 has no motor-current states (its current errors,
    and its reference vs check, nan): with target_current_A its runs are
    judged on the other targets, not all disqualified; a variant with
    currents keeps the current target, and the ranking one is always kept."""
    no_currents = {POSITION: 2e-9, CURRENT: math.nan}
    assert measures.variant_targets(TARGETS, no_currents, POSITION) == {POSITION: 5e-3}
    assert measures.variant_targets(TARGETS, AGREEMENT["base"], POSITION) == TARGETS
    assert measures.variant_targets(TARGETS, no_currents, CURRENT) == TARGETS
    run = _row("rk4", "dt=1e-05", 100, 1e-4, math.nan)
    assert measures.disqualified_by(run, TARGETS) == ["current"]
    assert measures.disqualified_by(run, measures.variant_targets(TARGETS, no_currents, POSITION)) == []
