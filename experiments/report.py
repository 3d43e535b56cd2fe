#!/usr/bin/python3
"""Writes results/README.md from the sweeps' and the stiffness tables' outputs.

    /usr/bin/python3 experiments/report.py [--results DIR] [--out FILE] [--minutes M]

Reads every <sweep>_summary.json and <sweep>.csv under DIR (default results/)
and results/stiffness/*.csv; every number in the report is read from those
files. The sweeps' findings (the prose under each table) come from the sweep
files ([[sweep.findings]]) and the planning comparison's from
experiments/planning_findings.toml, where they were written after reading the
tables, each sentence with assertions that say what in the table makes it true
(experiments/findings.py). Every assertion is checked against the table before
anything is written: if a table contradicts a sentence the report exits with
status 1, naming the sentence, the assertion and the rows, and writes nothing.
Runs no simulation. --minutes: how long the whole regeneration took, for the
header (scripts/results.sh passes it). --omit-findings: leave the findings out
unchecked (tables they were not written about: the reduced sweeps of
scripts/check_sweep_pipeline.sh).
"""
import argparse
import glob
import math
import os
import tomllib

import findings
import mode_table
from pumasim_exp import io as pumasim_io
from pumasim_exp.io import ROOT

PLANNING_FINDINGS = os.path.join(ROOT, "experiments", "planning_findings.toml")
STANDARD_TABLES = ("runs", "references", "creep", "limit")


class Checks:
    """The run's findings settings and the contradictions found so far."""

    def __init__(self, results, omit):
        self.results, self.omit, self.problems = results, omit, []

    def lines(self, found, tables, where):
        """The findings' paragraph (lines) after checking them against tables
        (their problems kept for the end); nothing if omitted or none."""
        if self.omit or not found:
            return []
        try:
            for name in {a.get("table", "runs") for f in findings.validated(found, where)
                         for a in f.get("assert", [])} - set(tables):
                path = os.path.join(self.results, name)
                if not os.path.exists(path):
                    raise findings.FindingsError(f"{where}: table {name}: no {path}")
                tables[name] = findings.plain_rows(read_csv(path))
            self.problems += findings.check(found, tables, where)
        except findings.FindingsError as e:
            raise SystemExit(f"report: {e}")
        return [findings.text(found), ""]


def sweep_tables(summary, rows):
    """The tables a sweep's findings can name: its runs (with the derived
    names), its references, creep and distance to the limit variant."""
    rank = summary["rank_by"]
    values = {v["label"]: v["value"] for v in summary["variants"]}

    def labelled(per_variant):
        return [findings.Row({"variant": lab, "value": values.get(lab), "target": rank["target"], **x})
                for lab, x in (per_variant or {}).items()]
    return {"runs": [findings.run_row(r, rank["column"], rank["target"]) for r in rows],
            "references": labelled(summary["agreement"]), "creep": labelled(summary.get("creep")),
            "limit": labelled(summary.get("distance_to_limit"))}


def sweep_findings(summary, rows, checks):
    """Lines: the sweep's checked findings, from its sweep file."""
    path = os.path.join(ROOT, summary["file"])
    if checks.omit or not os.path.exists(path):
        return []
    return checks.lines(findings.sweep_findings(path), sweep_tables(summary, rows), summary["file"])


def read_csv(path):
    """The rows of a sweep table (dicts of strings)."""
    return pumasim_io.read_table(path).rows


def fmt_int(x):
    return f"{int(float(x)):,}"


def fmt_num(x):
    """A CSV/summary number as the report prints it (3 significant digits; '–' for nan/empty)."""
    if x is None or x == "":
        return "–"
    x = float(x)
    return "–" if math.isnan(x) else f"{x:.3g}"


def fmt_wall_ms(r):
    """'median [min–max] ms' of a CSV row's wall times."""
    def ms(x):
        return f"{x:,.0f}" if x >= 100 else f"{x:.3g}"
    med, lo, hi = (1e3 * float(r[k]) for k in ("wall_time_median_s", "wall_time_min_s", "wall_time_max_s"))
    return f"{ms(med)} [{ms(lo)}–{ms(hi)}] ms"


def references_table(summary):
    """Lines: each variant's reference against its cross-check in every
    measure, with the verdict, and the too-weak warning if any."""
    measures, agree = summary["measures"], summary["agreement"]
    judged = [spec for spec in measures.values() if spec["target"] is not None]
    targets = ", ".join(f"{spec['target']:g} {spec['unit']} for the {spec['label']}" for spec in judged)
    out = [f"References: per variant, the reference against a cross-check by a different method, in every error "
           f"measure; a reference is too weak where the difference exceeds 1/{summary['weak_reference_factor']} of "
           f"the target ({targets}).", "",
           "| variant | " + " | ".join(f"{spec['label']} [{spec['unit']}]" for spec in measures.values())
           + " | final state | tracking [mm] | reference |",
           "|---|" + "---:|" * (len(measures) + 2) + "---|"]
    for lab, a in agree.items():
        verdict = ("**too weak** for " + ", ".join(measures[m]["label"] for m in a["reference_too_weak"])
                   if a["reference_too_weak"] else "ok")
        out.append(f"| {lab} | " + " | ".join(fmt_num(a[spec["column"]]) for spec in measures.values())
                   + f" | {fmt_num(a['final_state_error'])} | {fmt_num(a['tracking_mm'])} | {verdict} |")
    out.append("")
    if summary["reference_too_weak"]:
        cells = "; ".join(f"{lab}: " + ", ".join(f"{col} {w['difference']:.3g} > {w['limit']:.3g}"
                                                 for col, w in ws.items())
                          for lab, ws in summary["reference_too_weak"].items())
        out += [f"**Reference too weak** ({cells}): errors near the target are not resolved by it; "
                "the comparisons with the target below are not conclusive for these variants.", ""]
    return out


def limit_and_creep(summary, checks):
    """Lines: each variant's reference against the limit variant's, and the
    creep table (sweeps without a limit or a stuck variant: nothing)."""
    out = []
    if summary.get("distance_to_limit"):
        lim = summary["limit_variant"]
        cells = ", ".join(f"{lab} {d['max_tool_position_error_mm']:.3g} mm"
                          for lab, d in summary["distance_to_limit"].items() if lab != lim)
        out += [f"Distance of each variant's reference solution to the `{lim}` one (max tool position "
                f"distance): {cells}.", ""]
    if summary.get("creep"):
        st = summary["stuck_variant"]
        if summary["creep"][st]["rad"] != 0.0:  # what the sentence below says of it
            checks.problems.append(f"{summary['file']}: the creep table's `{st}` moves "
                                   f"{summary['creep'][st]['rad']:.3g} rad while stuck; the report says zero")
        out += [f"Creep while stuck: over the intervals in which the `{st}` model holds a joint at exactly zero "
                f"speed (the outputs 2 samples in from each end; {summary['creep'][st]['stuck_time_s']:.3g} s of "
                "joint-time in all), the largest motion of that joint in each other variant's reference solution "
                f"(`{st}` itself is not listed: while stuck its speed is zero by construction, so its motion is "
                "zero and says nothing):", "",
                "| variant | motion [rad] | joint | interval [s] |", "|---|---:|---|---|"]
        for lab, c in summary["creep"].items():
            if lab == st:
                continue
            out.append(f"| {lab} | {c['rad']:.3g} | {c['joint'] or '–'} | "
                       + (f"{c['from_s']:.2f}–{c['to_s']:.2f}" if c["joint"] else "–") + " |")
        out.append("")
    return out


def judged_on_every_target(rows):
    """True if the sweep's table says which runs are within every target the
    sweep sets (the columns within_targets and disqualified_by, which
    experiments/sweep.py writes since issue 31); a table without them is
    judged on the ranking measure alone."""
    return bool(rows) and "within_targets" in rows[0]


def within_ranking(r, rank):
    """The run finished within the ranking measure's target (a CSV row)."""
    return r["ok"] == "True" and float(r[rank["column"]]) <= rank["target"]


def qualifies(r, rank, judged):
    """The report's criterion: within the ranking target and, where the table
    is judged on every target (judged), within_targets too."""
    return within_ranking(r, rank) and (not judged or r["within_targets"] == "True")


def cheapest_caption(summary, judged, weak):
    """The cheapest-run table's caption: on a table judged on every target,
    the targets and what the lines under it show; else the ranking measure's
    criterion (the words of the tables before within_targets)."""
    rank = summary["rank_by"]
    rcol, runit, rlabel, target = rank["column"], rank["unit"], rank["label"], rank["target"]
    def dagger(error):
        return (f"; † its {error} is within {summary['below_reference_factor']}× of the reference-vs-check "
                "difference (below the reference's accuracy)")
    if not judged:
        return (f"Cheapest run per integrator and variant whose {rlabel} stays within {target:g} {runit} of the "
                "reference (ranked by that measure): RHS evaluations (setting; wall time median [min–max] of the "
                "repeats); `fail` if every setting failed, `–` if none was accurate enough" + dagger("error")
                + ("; (weak ref.) the variant's reference is too weak in this measure." if weak else "."))
    targets = ", ".join(f"{spec['label']} {spec['target']:g} {spec['unit']}"
                        for spec in summary["measures"].values() if spec["target"] is not None)
    return (f"Cheapest run per integrator and variant within every target the sweep sets ({targets}): a run "
            f"qualifies only if it finished and is within each of them (the CSV's `within_targets`; ranked by "
            f"the {rlabel}, `{rcol}`): RHS evaluations (setting; wall time median [min–max] of the repeats); "
            "`fail` if every setting failed, `–` if none qualified" + dagger("ranking error")
            + ("; (weak ref.) the variant's reference is too weak in one of these measures" if weak else "")
            + f". Under the table: each run cheaper than the one shown that is within the {rlabel} target but "
            "misses another (its `disqualified_by`), with its error and the target.")


def disqualified_lines(summary, rows):
    """Lines under the cheapest-run table (a table judged on every target):
    per integrator and variant whose cheapest run within the ranking target
    misses another target, that run, each measure it misses (its
    disqualified_by) with its error and the target (the summary's
    disqualified_cheapest, from the same rows); nothing if there is none."""
    rank, measures = summary["rank_by"], summary["measures"]
    out = []
    for n in sorted({r["integrator"] for r in rows}):
        for v in [v["label"] for v in summary["variants"]]:
            alone = [r for r in rows if r["integrator"] == n and r["variant"] == v and within_ranking(r, rank)]
            b = min(alone, key=lambda r: float(r["rhs_evaluations"])) if alone else None
            if b is None or b["within_targets"] == "True":
                continue
            missed = "; ".join(f"{measures[m]['label']} {fmt_num(b[measures[m]['column']])} {measures[m]['unit']} "
                               f"> target {measures[m]['target']:g} {measures[m]['unit']}"
                               for m in b["disqualified_by"].split())
            out.append(f"- {n}, {v}: {b['setting']} ({fmt_int(b['rhs_evaluations'])} RHS; {rank['label']} "
                       f"{fmt_num(b[rank['column']])} {rank['unit']}) misses {missed} "
                       f"(`disqualified_by` = `{b['disqualified_by']}`)")
    if not out:
        return []
    return ["", f"Cheaper on the {rank['label']} alone, but past another target (not counted above):", ""] + out


def cheapest_runs(summary, rows):
    """(lines: per integrator and variant the cheapest run that qualifies,
    within every target the sweep sets where the table says so
    (within_targets) and else within the ranking measure's, with the runs
    disqualified by another measure under it; the runs chosen)."""
    rank = summary["rank_by"]
    judged = judged_on_every_target(rows)
    variants = [v["label"] for v in summary["variants"]]
    weak = {lab for lab, a in summary["agreement"].items()
            if (a["reference_too_weak"] if judged else rank["measure"] in a["reference_too_weak"])}
    out = [cheapest_caption(summary, judged, weak), "",
           "| integrator | " + " | ".join(v + (" (weak ref.)" if v in weak else "") for v in variants) + " |",
           "|---|" + "---:|" * len(variants)]
    chosen = []
    for n in sorted({r["integrator"] for r in rows}):
        cells = []
        for v in variants:
            rs = [r for r in rows if r["integrator"] == n and r["variant"] == v]
            good = [r for r in rs if qualifies(r, rank, judged)]
            if good:
                b = min(good, key=lambda r: float(r["rhs_evaluations"]))
                chosen.append(b)
                cells.append(f"{fmt_int(b['rhs_evaluations'])} ({b['setting']}; {fmt_wall_ms(b)})"
                             + (" †" if b["below_reference_accuracy"] == "True" else ""))
            elif rs and all(r["ok"] != "True" for r in rs):
                cells.append("fail")
            else:
                cells.append("–")
        out.append(f"| {n} | " + " | ".join(cells) + " |")
    return out + (disqualified_lines(summary, rows) if judged else []), chosen


def chosen_runs_table(summary, chosen):
    """Lines: the cheapest runs (chosen) in every error measure (nothing if none)."""
    if not chosen:
        return []
    measures = summary["measures"]
    out = ["", f"Those runs (ranked by {summary['rank_by']['label']}) in every error measure against the reference; "
           f"† below the reference's accuracy in the ranking measure (within {summary['below_reference_factor']}× "
           "of reference vs check):", "",
           "| integrator | variant | setting | " + " | ".join(f"{spec['label']} [{spec['unit']}]"
                                                       for spec in measures.values())
           + " | RMS tool position [mm] | final state |", "|---|---|---|" + "---:|" * (len(measures) + 2)]
    for r in chosen:
        out.append(f"| {r['integrator']} | {r['variant']} | {r['setting']}"
                   + (" †" if r["below_reference_accuracy"] == "True" else "") + " | "
                   + " | ".join(fmt_num(r[spec["column"]]) for spec in measures.values())
                   + f" | {fmt_num(r['rms_tool_position_error_mm'])} | {fmt_num(r['final_state_error'])} |")
    return out


def ledger_table(rows):
    """Lines: the energy ledger's residual per successful run (sweeps whose
    scene has the ledger; else nothing)."""
    if not (rows and "max_ledger_residual_J" in rows[0]):
        return []
    out = ["", "Energy ledger: largest residual of the balance (mechanical + magnetic energy change = input − "
           "copper − friction) over the run, against the largest energy term [J]:", "",
           "| integrator | setting | residual [J] | scale [J] |", "|---|---|---:|---:|"]
    for r in rows:
        if r["ok"] == "True" and r.get("max_ledger_residual_J"):
            out.append(f"| {r['integrator']} | {r['setting']} | {float(r['max_ledger_residual_J']):.3g} | "
                       f"{float(r['ledger_energy_scale_J']):.3g} |")
    return out


def modes_section(summary, folder, rel):
    """Lines on the friction mode sequences and event times (a sweep whose
    summary has them: its stuck variant's reference recorded events)."""
    m = summary.get("modes")
    if not m:
        return []
    name = summary["name"]
    marg = ", ".join(f"joint {x['joint']} at {x['t']:.4g} s ({x['why']})" for x in m["marginal"]) or "none"
    out = ["", "#### Mode sequences and event times", "",
           f"Each run's stick/slip sequence (its run folder's `events.csv`: the hybrid model's events, or the "
           f"other treatments' accepted steps classified, stuck at |w_m| <= 1e-3 rad/s where the law's stick "
           f"branch holds) against the exact model's ({m['variant']}) reference run, {m['reference_events']} "
           f"events, modes held under {m['min_duration_s']:g} s dropped on both sides "
           f"(`experiments/mode_sequence.py`). Marginal decisions of that reference (its cross-check disagrees, "
           f"or within {m['torque_margin']:g} Fs of the static level): {marg}. Every run: `{rel}/{name}_modes.md`.",
           "", "Each treatment as finely integrated as the sweep has it (its own reference run):", ""]
    out += mode_table.treatments_table(m)
    out += ["", f"Per treatment and integrator, how many finished runs have the reference's mode sequence (and how "
            f"many of them have every event within {1e3 * mode_table.ON_TIME:g} ms of the reference's), and the "
            "cheapest of the latter:", ""]
    out += mode_table.summary_table(m)
    if os.path.exists(os.path.join(folder, "filippov.md")):
        out += ["", f"The paper's rule in Filippov terms (applied torque, static level, why adaptive methods "
                f"grind): `{rel}/filippov.md`."]
    if summary.get("skipped_variants"):
        out += ["", f"Left out: {', '.join(summary['skipped_variants'])}."]
    return out


def decision_section(folder, rel):
    """A sweep folder's decision table (decision.md, experiments/friction_decision.py), its headings
    moved under the sweep's."""
    path = os.path.join(folder, "decision.md")
    if not os.path.exists(path):
        return []
    with open(path) as f:
        lines = f.read().splitlines()
    out = ["", f"#### Which method for which law (`{rel}/decision.md`)"]
    for line in lines[1:]:
        out.append("#####" + line[2:] if line.startswith("## ") else line)
    return out


def sweep_section(summary, folder, rel, checks):
    """The report's section on one sweep (its summary, its CSV in folder; rel:
    folder relative to the report, for links; checks: its findings')."""
    name = summary["name"]
    if "rank_by" not in summary:
        raise SystemExit(f"report: {folder}/{name}_summary.json predates the error measures (no rank_by): "
                         f"re-run `experiments/sweep.py {summary['file']} --merge`")
    try:  # the table and plots the summary was written with (a merge interrupted, or another one, leaves others)
        pumasim_io.check_outputs(folder, summary)
    except pumasim_io.OutputsMismatch as e:
        raise SystemExit(f"report: {folder}/{name}_summary.json: {e}; re-run "
                         f"`experiments/sweep.py {summary['file']} --merge`")
    rows = read_csv(os.path.join(folder, name + ".csv"))
    rank = summary["rank_by"]
    runit, rlabel, target = rank["unit"], rank["label"], rank["target"]
    out = [f"### {summary['title']}", "",
           f"Sweep `{summary['file']}` on scene `experiments/scenes/{summary['scene']}.toml`; "
           f"table `{rel}/{name}.csv` ({summary['runs']} runs, {summary['failed']} failed, each with its reason), "
           f"summary `{rel}/{name}_summary.json` (the references, counts and distances below). "
           f"Runs are ranked by the {rlabel} [{runit}] against the variant's reference, target {target:g} {runit}.",
           ""]
    out += sweep_findings(summary, rows, checks)
    out += references_table(summary)
    out += limit_and_creep(summary, checks)
    cheapest, chosen = cheapest_runs(summary, rows)
    out += cheapest
    out += chosen_runs_table(summary, chosen)
    pin = summary["pinning"]
    out += ["", f"Wall times: {pin['pinned_runs']} of {pin['runs']} runs pinned to one CPU"
            + (f" ({', '.join(pin['methods'])})" if pin["methods"] else "") + "; each repeat's time is in the CSV."]
    out += ledger_table(rows)
    out += modes_section(summary, folder, rel)
    out += decision_section(folder, rel)
    out += ["", f"![{name}: {rlabel} against cost; hollow markers below the reference's accuracy]({rel}/{name}.png)",
            ""]
    if summary.get("has_cost_plot"):
        out += [f"![{name} cost to reach the target {rlabel}]({rel}/{name}_cost.png)", ""]
    return out


def scenes_stiff_problems(rows):
    """What contradicts the scenes table's sentences: stiff when the median
    ratio is at least 100; named stiff_* only when stiff."""
    bad = []
    for r in rows:
        stiff = r["stiff"] == "yes"
        if stiff != (float(r["median_stiffness_ratio"]) >= 100):
            bad.append(f"{r['scene']}: stiff = {r['stiff']} with median stiffness ratio {r['median_stiffness_ratio']}")
        if r["scene"].startswith("stiff_") and not stiff:
            bad.append(f"{r['scene']}: named stiff_* but not stiff")
    return [f"stiffness/scenes.csv: {b}" for b in bad]


def stiffness_section(folder, rel, checks):
    files = sorted(f for f in glob.glob(os.path.join(folder, "*.csv"))
                   if os.path.basename(f) not in ("conditioning.csv", "scenes.csv"))
    if not files:
        return []
    out = ["## Stiffness diagnostics", ""]
    scenes = os.path.join(folder, "scenes.csv")
    if os.path.exists(scenes):
        out += ["### Every shipped scene", "",
                "From `pumasim stiffness <scene> --samples 40 --t-end <its duration>` (experiments/stiffness_table.py, "
                "`scenes.csv`): the largest spectral radius of the plant Jacobian along the whole run, and the "
                "stiffness ratio, the spectral radius over the slowest decay rate, that rate floored at 1/duration "
                "(a mode slower than the run, or an undamped one, hardly moves within it); the median over the "
                "samples classifies the scene (stiff when at least 100), since while a hybrid-friction joint is "
                "stuck near-zero modes make single samples meaningless. Scenes are named `stiff_*` only when stiff "
                "by this measure.", "",
                "| scene | duration [s] | max spectral radius [1/s] | fastest state | stiffness ratio: median "
                "(min … max) | stiff |", "|---|---:|---:|---|---|---|"]
        checks.problems += scenes_stiff_problems(read_csv(scenes))
        for r in read_csv(scenes):
            out.append(f"| {r['scene']} | {float(r['t_end_s']):.3g} | {float(r['max_spectral_radius_per_s']):.4g} | "
                       f"{r['fastest_state']} | {float(r['median_stiffness_ratio']):.3g} "
                       f"({float(r['min_stiffness_ratio']):.3g} … {float(r['max_stiffness_ratio']):.3g}) | "
                       f"{r['stiff']} |")
        out.append("")
    out += ["From `pumasim stiffness <scene> --bisect` (experiments/stiffness_table.py): the largest eigenvalue "
            "modulus of the plant Jacobian along the run, the stiffness ratio, and for each explicit fixed-step "
            "method the largest stable step its stability region predicts beside the one found by bisection on "
            "the scene.", ""]
    for path in files:
        rows = read_csv(path)
        name = os.path.splitext(os.path.basename(path))[0]
        methods = sorted({r["integrator"] for r in rows})
        out += [f"### {name}", "", f"Table `{rel}/{name}.csv`:", "",
                "| case | spectral radius [1/s] | stiffness ratio | fastest mode | "
                + " | ".join(f"{m} predicted / measured [s]" for m in methods) + " |",
                "|---|---:|---:|---|" + "---:|" * len(methods)]
        cases = []
        for r in rows:
            if r["case"] not in cases:
                cases.append(r["case"])
        for c in cases:
            rc = [r for r in rows if r["case"] == c]
            r0 = rc[0]
            cells = []
            for m in methods:
                rm = [r for r in rc if r["integrator"] == m]
                cells.append(f"{float(rm[0]['predicted_s']):.3g} / {float(rm[0]['measured_s']):.3g}" if rm else "")
            out.append(f"| {c} | {float(r0['spectral_radius']):.4g} | {float(r0['stiffness_ratio']):.3g} | "
                       f"{r0['fastest_state']} (tau {float(r0['fastest_tau_s']):.3g} s) | " + " | ".join(cells) + " |")
        ratios = [(float(r["measured_over_predicted"]), r["integrator"], r["case"]) for r in rows
                  if r.get("measured_over_predicted")]
        if ratios:
            lo, hi = min(ratios), max(ratios)
            # the cases off named with their values rather than counted: every figure here is one of the table's
            off = [f"{m}, {c} ({x:.3g})" for x, m, c in ratios if abs(x - 1) > 0.05]
            out += ["", f"Measured over predicted stable step: from {lo[0]:.3g} ({lo[1]}, {lo[2]}) to {hi[0]:.3g} "
                        f"({hi[1]}, {hi[2]}); "
                        + (f"more than 5 % off: {'; '.join(off)}." if off else "every case within 5 %.")]
        png = os.path.join(folder, name + ".png")
        if os.path.exists(png):
            out += ["", f"![{name}]({rel}/{name}.png)"]
        out.append("")
    return out


def conditioning_section(folder, rel):
    path = os.path.join(folder, "conditioning.csv")
    if not os.path.exists(path):
        return []
    rows = read_csv(path)
    backends = [k[len("qdd_error_"):] for k in rows[0] if k.startswith("qdd_error_")]
    out = ["## Singular and ill-conditioned poses", "",
           "From `pumasim conditioning` (experiments/stiffness_table.py, `conditioning.csv`): the largest "
           "cond(H) along each path, the smallest eigenvalue of H, the closest approach of the wrist to q5 = 0, "
           "and each back-end's worst forward-dynamics error (relative to max(|qdd|, 1 rad/s^2)) for the "
           "torque that produces the reference's acceleration.", "",
           "| case | max cond(H) | min eig(H) | min abs(q5) [rad] | " + " | ".join(backends) + " |",
           "|---|---:|---:|---:|" + "---:|" * len(backends)]
    for r in rows:
        out.append(f"| {r['case']} | {float(r['max_cond_H']):.3g} | {float(r['min_eig_H']):.3g} | "
                   f"{r['min_abs_q5_rad'] or '–'} | " + " | ".join(r[f"qdd_error_{b}"] for b in backends) + " |")
    if os.path.exists(os.path.join(folder, "conditioning.png")):
        out += ["", f"![conditioning]({rel}/conditioning.png)"]
    return out + [""]


def planning_section(folder, rel, checks):
    path = os.path.join(folder, "planning.csv")
    if not os.path.exists(path):
        return []
    rows = read_csv(path)
    summary = pumasim_io.read_json(os.path.join(folder, "summary.json"))
    joints = sorted({k.rsplit("_j", 1)[1] for k in rows[0] if k.startswith("peak_voltage_V_j")})
    out = ["## Trajectory planning methods", "",
           f"`experiments/planning.py` on `experiments/scenes/planning.toml` (the paper's path, arm, drives and "
           f"controller; RK4 at 0.5 ms); table `{rel}/planning.csv`. The time-optimal timing under the drives' "
           f"limits takes T_opt = {summary['t_opt_s']:.3g} s; every other method runs at the times listed and at "
           f"T_opt. Joint-space splines pass through {summary['via_segments']} + 1 via-points timed by the "
           "trapezoid. Tracking error: distance to where the reference is at that instant; path error: distance to "
           "the geometric path. Peak amplifier voltage and motor current per joint (limit 40 V); saturated: the "
           "largest share of outputs at which a joint's controller or amplifier is at its limit.", "",
           *planning_findings(rows, checks),
           "| method | T [s] | max tracking [mm] | max path [mm] | RMS path [mm] | peak e_a [V] | peak i [A] | "
           "saturated |", "|---|---:|---:|---:|---:|---|---|---:|"]
    for r in rows:
        if r["ok"] != "True":
            out.append(f"| {r['method']} | {float(r['traversal_time_s']):.3g} | fail: {r['failure']} | | | | | |")
            continue
        volts = " / ".join(f"{float(r['peak_voltage_V_j' + j]):.3g}" for j in joints)
        amps = " / ".join(f"{float(r['peak_current_A_j' + j]):.3g}" for j in joints)
        sat = max(float(r["saturated_share_j" + j]) for j in joints)
        out.append(f"| {r['method']} | {float(r['traversal_time_s']):.3g} | {float(r['max_tracking_error_mm']):.3g} | "
                   f"{float(r['max_path_deviation_mm']):.3g} | {float(r['rms_path_deviation_mm']):.3g} | {volts} | "
                   f"{amps} | {100 * sat:.3g} % |")
    out += ["", f"![planning]({rel}/planning.png)", "", f"![along the path]({rel}/planning_along_path.png)", ""]
    return out


def planning_findings(rows, checks):
    """Lines: the planning comparison's checked findings."""
    with open(PLANNING_FINDINGS, "rb") as f:
        found = tomllib.load(f)["findings"]
    return checks.lines(found, {"runs": findings.plain_rows(rows)}, os.path.relpath(PLANNING_FINDINGS, ROOT))


def minutes_of_last_run(res, minutes):
    """The minutes the header quotes: those given (--minutes), else the last
    full run's, kept in res/report_run.json (None if neither)."""
    path = os.path.join(res, "report_run.json")
    if minutes is None and os.path.exists(path):
        minutes = pumasim_io.read_json(path).get("minutes_of_last_full_run")
    return minutes


def header(minutes, omit_findings):
    """The report's first lines."""
    return ["# pumasim results", "",
            "Generated by `scripts/results.sh` (sweeps, stiffness tables, then `experiments/report.py`); "
            "do not edit by hand."
            + (f" Its last run took {minutes:.0f} min on this machine (2 cores; runs already complete "
               "under build/sweeps/ are skipped)." if minutes else ""),
            "Wall times are medians of repeated runs, with their range, on a shared machine (each run pinned to "
            "one CPU where the platform allows): compare them within one table; right-hand-side evaluations do "
            "not depend on the machine."
            + ("" if omit_findings else " The findings under each table are written by hand, each sentence with "
               "assertions beside it (in its sweep file; the planning comparison's in "
               "`experiments/planning_findings.toml`) that this report checks against the table's rows when it is "
               "written: a table that contradicts one fails the report."), "",
            "Other results: `paper/README.md` (the paper's experiment), `dynamics_backends.md` (the dynamics "
            "back-ends' cost), `energy_long_time/energy_growth.md` (the lossless arm's energy error over 10^4 s, the "
            "symplectic midpoint against the others), `implicit_form/README.md` (IDA on the implicit form against "
            "CVODE's BDF on the ODE).", ""]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--results", default=os.path.join(ROOT, "results"))
    ap.add_argument("--out", default=None)
    ap.add_argument("--minutes", type=float, default=None)
    ap.add_argument("--omit-findings", action="store_true",
                    help="leave the hand-written findings out, unchecked (tables they were not written about)")
    args = ap.parse_args()
    res = args.results
    checks = Checks(res, args.omit_findings)
    out_path = args.out or os.path.join(res, "README.md")
    out_dir = os.path.dirname(os.path.abspath(out_path))
    lines = header(minutes_of_last_run(res, args.minutes), args.omit_findings)
    summaries = []
    for path in sorted(glob.glob(os.path.join(res, "*", "*_summary.json"))):
        summaries.append((pumasim_io.read_json(path), os.path.dirname(path)))
    groups = [("Work-precision: the paper's scenes, the Stanford arm and the Panda", True),
              ("Stiff and extreme scenes: stiffness, events, sampling, saturation, long-time energy", False)]
    for title, paper in groups:
        chosen = [(s, d) for s, d in summaries if (os.path.basename(d) == "work_precision") == paper]
        if not chosen:
            continue
        lines += [f"## {title}", ""]
        for s, d in chosen:
            lines += sweep_section(s, d, os.path.relpath(d, out_dir), checks)
    plan_dir = os.path.join(res, "planning")
    lines += planning_section(plan_dir, os.path.relpath(plan_dir, out_dir), checks)
    stiff_dir = os.path.join(res, "stiffness")
    lines += stiffness_section(stiff_dir, os.path.relpath(stiff_dir, out_dir), checks)
    lines += conditioning_section(stiff_dir, os.path.relpath(stiff_dir, out_dir))
    if checks.problems:
        raise SystemExit(f"report: {len(checks.problems)} finding(s) contradicted by their tables; nothing written "
                         "(correct the sentence and its assertion, or the table):\n" + "\n".join(checks.problems))
    pumasim_io.write_text_atomic(out_path, "\n".join(lines) + "\n")
    if args.minutes:  # the figure the header quotes, kept beside the tables it describes
        pumasim_io.write_json_atomic(os.path.join(res, "report_run.json"),
                                     {"minutes_of_last_full_run": round(args.minutes), "cores": os.cpu_count()},
                                     newline=True)
    print(f"report: {os.path.relpath(out_path, ROOT)}")


if __name__ == "__main__":
    main()
