"""Friction mode sequences (stick, slip+, slip-) of runs and their comparison
with a reference run's.

A run folder's events.csv (simulation/mode_log.hpp) lists, per
joint, the mode at t = 0 and every change after: the hybrid model's own events,
or, for the laws without modes, the integrator's accepted steps classified
(stuck at |w_m| <= 1e-3 rad/s motor side where the law's stick branch holds,
changes kept when they last at least 1 ms). Both are read through lasting(),
which drops every mode held for less than MIN_DURATION, so that the exact
model's instantaneous sticks and a classified run's flicker count alike.

compare(reference, run) says, over the joints:
  match              the two sequences of modes are equal (yes/no);
  first_divergence   (time [s], joint) of the earliest place where they part;
  time errors        max and RMS |t_run - t_ref| over the matched events (per
                     joint, the events before the sequences part; the modes
                     at t = 0 left out);
  missed sticks      the reference's sticks at a speed reversal (a stick
                     between slips of opposite directions) during which the
                     run never sticks that joint.
marginal(reference, check) marks the reference's decisions that are marginal:
those its own cross-check (the sweep's [check] run) does not share (at or after
the place where the check's sequence parts from the reference's), and
those whose torque margin is within TORQUE_MARGIN of Fs: a stick (Fs - |applied|
just after it) and a reversal without a stick (|applied| - Fs there). A
break-away from a stick has |applied| = Fs by construction (the root); its
timing, not its outcome, is the decision there, and it is not marked.
"""
import csv
import io
import math
import os

MIN_DURATION = 1e-3   # [s], as kMinModeDuration in simulation/mode_log.hpp
TORQUE_MARGIN = 0.01  # relative to Fs: a decision closer than this to the static level is marginal
EVENTS = "events.csv"
# The hybrid model's run classified by speed alone, as the laws without modes
# and time-stepping are (simulation/scene_run.hpp): their yardstick.
EVENTS_SPEED = "events_speed.csv"
MODES = ("stick", "slip+", "slip-")


class EventsError(Exception):
    pass


def parse_events(text, path=EVENTS):
    """[{t, joint, mode, applied, fs}] of events.csv's text, in file order."""
    rows = list(csv.reader(io.StringIO(text)))
    if not rows or rows[0] != ["t", "joint", "mode", "applied_torque", "static_torque"]:
        raise EventsError(f"{path}: expected the header t,joint,mode,applied_torque,static_torque")
    out = []
    for k, r in enumerate(rows[1:], start=2):
        if len(r) != 5 or r[2] not in MODES:
            raise EventsError(f"{path}: line {k}: expected t,joint,mode (stick, slip+, slip-),applied,Fs")
        out.append({"t": float(r[0]), "joint": int(r[1]), "mode": r[2], "applied": float(r[3]),
                    "fs": float(r[4])})
    return out


def read_events(run_dir, name=EVENTS):
    """The run folder's events (events.csv, or name), or None when it has no
    such file (no joint with friction modes; events_speed.csv: not a hybrid-model run)."""
    path = os.path.join(run_dir, name)
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return parse_events(f.read(), path)


def by_joint(events):
    """{joint: [event, ...] in time order}."""
    out = {}
    for e in sorted(events, key=lambda e: (e["joint"], e["t"])):
        out.setdefault(e["joint"], []).append(e)
    return out


def lasting(seq, min_duration=MIN_DURATION):
    """One joint's events without the modes held for less than min_duration
    (the mode before them goes on), consecutive equal modes merged; the first
    (the mode at t = 0) and the last (held to the run's end) are kept."""
    out = []
    for k, e in enumerate(seq):
        held = seq[k + 1]["t"] - e["t"] if k + 1 < len(seq) else math.inf
        if out and (held < min_duration or e["mode"] == out[-1]["mode"]):
            continue
        out.append(e)
    return out


def _common(ref, run):
    """How many leading events two joint sequences share (equal modes, in order)."""
    k = 0
    while k < min(len(ref), len(run)) and ref[k]["mode"] == run[k]["mode"]:
        k += 1
    return k


def _aligned(ref, run):
    """[(i, i)] of matched events of two joint sequences: those before they
    part (after a divergence the pairing of events is ambiguous: an event the
    run lacks would pair with a later one, seconds away)."""
    return [(i, i) for i in range(_common(ref, run))]


def _divergence(ref, run):
    """Time of the first event where two joint sequences differ (None if equal)."""
    for k in range(max(len(ref), len(run))):
        a = ref[k] if k < len(ref) else None
        b = run[k] if k < len(run) else None
        if a is None or b is None or a["mode"] != b["mode"]:
            return min(e["t"] for e in (a, b) if e is not None)
    return None


def reversal_sticks(seq):
    """Indices of the sticks between slips of opposite directions."""
    return [k for k in range(1, len(seq) - 1)
            if seq[k]["mode"] == "stick" and {seq[k - 1]["mode"], seq[k + 1]["mode"]} == {"slip+", "slip-"}]


def _stuck_during(seq, t0, t1):
    """True if the joint sequence has a stick overlapping [t0, t1]."""
    for k, e in enumerate(seq):
        end = seq[k + 1]["t"] if k + 1 < len(seq) else math.inf
        if e["mode"] == "stick" and e["t"] <= t1 and end >= t0:
            return True
    return False


def compare(reference, run, min_duration=MIN_DURATION):
    """The run's event list against the reference's (module docstring)."""
    ref_j = {j: lasting(s, min_duration) for j, s in by_joint(reference).items()}
    run_j = {j: lasting(s, min_duration) for j, s in by_joint(run).items()}
    errors, first, missed, reversals = [], None, 0, 0
    for j in sorted(set(ref_j) | set(run_j)):
        a, b = ref_j.get(j, []), run_j.get(j, [])
        t = _divergence(a, b)
        if t is not None and (first is None or t < first[0]):
            first = (t, j)
        errors += [abs(b[k]["t"] - a[i]["t"]) for i, k in _aligned(a, b) if i > 0 or k > 0]
        for i in reversal_sticks(a):
            reversals += 1
            missed += not _stuck_during(b, a[i]["t"], a[i + 1]["t"])
    return {"match": first is None,
            "first_divergence_s": first[0] if first else math.nan,
            "first_divergence_joint": first[1] if first else None,
            "matched_events": len(errors),
            "reference_events": sum(len(s) - 1 for s in ref_j.values()),
            "max_event_time_error_s": max(errors) if errors else math.nan,
            "rms_event_time_error_s": math.sqrt(sum(e * e for e in errors) / len(errors)) if errors else math.nan,
            "reversal_sticks": reversals, "missed_reversal_sticks": missed}


def _torque_marginal(seq, k, tol):
    """True if the decision at event k of a joint sequence is within tol Fs of the static level."""
    e = seq[k]
    gap = abs(abs(e["applied"]) - e["fs"])
    if e["mode"] == "stick":
        return gap <= tol * e["fs"]
    return k > 0 and seq[k - 1]["mode"] not in ("stick", e["mode"]) and gap <= tol * e["fs"]


def marginal(reference, check, min_duration=MIN_DURATION, tol=TORQUE_MARGIN):
    """{(joint, time of the reference's event): why} of the reference's
    marginal decisions (module docstring); 'check' when the cross-check does
    not share it, 'torque' when its margin is within tol Fs, or both."""
    out = {}
    chk_j = {j: lasting(s, min_duration) for j, s in by_joint(check).items()}
    for j, s in by_joint(reference).items():
        a = lasting(s, min_duration)
        shared = {i for i, _ in _aligned(a, chk_j.get(j, []))}
        for i in range(1, len(a)):
            why = [w for w, c in (("check", i not in shared), ("torque", _torque_marginal(a, i, tol))) if c]
            if why:
                out[(j, a[i]["t"])] = "+".join(why)
    return out


def divergence_marginal(c, marks, reference, min_duration=MIN_DURATION):
    """True if compare()'s first divergence c lies at a marginal decision of
    the reference (its joint's event at that time, or the last before it);
    None when the sequences match."""
    if c["match"]:
        return None
    seq = lasting(by_joint(reference).get(c["first_divergence_joint"], []), min_duration)
    before = [e["t"] for e in seq if e["t"] <= c["first_divergence_s"]]
    return bool(before) and (c["first_divergence_joint"], before[-1]) in marks


def columns(reference, marks, run_events, min_duration=MIN_DURATION):
    """The CSV columns of a run's mode comparison with the reference (nan and
    empty where the run has no events: a failed run)."""
    if run_events is None:
        return {"mode_sequence_match": "", "first_divergence_s": math.nan, "first_divergence_joint": "",
                "divergence_marginal": "", "max_event_time_error_s": math.nan,
                "rms_event_time_error_s": math.nan, "missed_reversal_sticks": ""}
    c = compare(reference, run_events, min_duration)
    dm = divergence_marginal(c, marks, reference, min_duration)
    return {"mode_sequence_match": "yes" if c["match"] else "no",
            "first_divergence_s": c["first_divergence_s"],
            "first_divergence_joint": "" if c["first_divergence_joint"] is None else c["first_divergence_joint"],
            "divergence_marginal": "" if dm is None else ("yes" if dm else "no"),
            "max_event_time_error_s": c["max_event_time_error_s"],
            "rms_event_time_error_s": c["rms_event_time_error_s"],
            "missed_reversal_sticks": f"{c['missed_reversal_sticks']}/{c['reversal_sticks']}"}
