"""Tests of experiments/mode_sequence.py on hand-made event sequences.

    /usr/bin/python3 -m pytest -q tests/test_mode_sequence.py
"""
import math
import os
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "experiments"))
import mode_sequence as ms  # noqa: E402

FS = 0.146


def ev(t, joint, mode, applied=0.0):
    return {"t": t, "joint": joint, "mode": mode, "applied": applied, "fs": FS}


# Joint 1: stuck, slips forward, sticks at a reversal, slips back, sticks.
# Joint 2: stuck, slips forward, stops for good.
REF = [ev(0, 1, "stick"), ev(0.1, 1, "slip+", FS), ev(0.5, 1, "stick", 0.05), ev(0.6, 1, "slip-", -FS),
       ev(0.9, 1, "stick", 0.01), ev(0, 2, "stick"), ev(0.2, 2, "slip+", FS), ev(0.8, 2, "stick", 0.02)]


def test_the_same_sequence_matches_with_no_time_error():
    c = ms.compare(REF, REF)
    assert c["match"] and math.isnan(c["first_divergence_s"])
    assert c["max_event_time_error_s"] == 0 and c["rms_event_time_error_s"] == 0
    assert c["matched_events"] == c["reference_events"] == 6  # the modes at t = 0 left out
    assert (c["reversal_sticks"], c["missed_reversal_sticks"]) == (1, 0)


def test_shifted_events_give_their_shifts_as_errors():
    run = [dict(e, t=e["t"] + (0.002 if e["joint"] == 1 and e["t"] > 0 else 0)) for e in REF]
    run = [dict(e, t=e["t"] + 0.001) if e["joint"] == 2 and e["t"] > 0.5 else e for e in run]
    c = ms.compare(REF, run)
    assert c["match"]
    assert c["max_event_time_error_s"] == pytest.approx(0.002, abs=1e-15)
    # four shifts of 2 ms (joint 1), one of 1 ms and one of 0 (joint 2)
    assert c["rms_event_time_error_s"] == pytest.approx(math.sqrt((4 * 0.002**2 + 0.001**2) / 6), rel=1e-12)


def test_a_run_that_passes_through_the_reversal_misses_the_stick():
    run = [e for e in REF if not (e["joint"] == 1 and e["t"] == 0.5)]
    run = [dict(e, t=0.55) if e["joint"] == 1 and e["mode"] == "slip-" else e for e in run]
    c = ms.compare(REF, run)
    assert not c["match"]
    assert (c["first_divergence_s"], c["first_divergence_joint"]) == (0.5, 1)
    assert (c["reversal_sticks"], c["missed_reversal_sticks"]) == (1, 1)
    # matched: the events before the sequences part, slip+ 0.1 on joint 1 and joint 2's two; the slip-
    # at 0.55 is not paired with the reference's at 0.6
    assert c["matched_events"] == 3
    assert c["max_event_time_error_s"] == 0


def test_modes_shorter_than_the_minimum_duration_are_not_modes():
    blip = REF[:2] + [ev(0.3, 1, "stick"), ev(0.3005, 1, "slip+")] + REF[2:]
    assert [e["t"] for e in ms.lasting(ms.by_joint(blip)[1])] == [0, 0.1, 0.5, 0.6, 0.9]
    assert ms.compare(REF, blip)["match"]
    # a short stick at a reversal (the exact model sticks and is released at once) is a direct reversal
    quick = [ev(0, 1, "slip+"), ev(0.5, 1, "stick"), ev(0.5002, 1, "slip-")]
    assert [e["mode"] for e in ms.lasting(quick)] == ["slip+", "slip-"]


def test_marginal_decisions_by_check_and_by_torque_margin():
    near = [dict(e, applied=FS - 0.001) if e["joint"] == 2 and e["mode"] == "stick" and e["t"] > 0 else e
            for e in REF]
    check = [e for e in near if not (e["joint"] == 1 and e["t"] == 0.9)]
    marks = ms.marginal(near, check)
    assert marks == {(1, 0.9): "check", (2, 0.8): "torque"}  # 0.001 < 1 % of Fs; break-aways never
    run = [e for e in near if not (e["joint"] == 2 and e["t"] == 0.8)]
    c = ms.compare(near, run)
    assert (c["first_divergence_s"], c["first_divergence_joint"]) == (0.8, 2)
    assert ms.divergence_marginal(c, marks, near) is True
    cols = ms.columns(near, marks, run)
    assert (cols["mode_sequence_match"], cols["divergence_marginal"], cols["missed_reversal_sticks"]) == \
        ("no", "yes", "0/1")


def test_events_csv_is_read_and_malformed_files_are_named():
    text = "t,joint,mode,applied_torque,static_torque\n0,1,stick,0,0.146\n0.25,1,slip-,-0.146,0.146\n"
    assert ms.parse_events(text) == [ev(0, 1, "stick"), ev(0.25, 1, "slip-", -FS)]
    with pytest.raises(ms.EventsError, match="line 2"):
        ms.parse_events("t,joint,mode,applied_torque,static_torque\n0,1,stuck,0,0.146\n", "x/events.csv")
    with pytest.raises(ms.EventsError, match="header"):
        ms.parse_events("t,joint\n")
