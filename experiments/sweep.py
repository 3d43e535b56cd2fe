#!/usr/bin/python3
"""Sweeps: variants of a scene x integrators x settings, as independent runs.

    /usr/bin/python3 experiments/sweep.py experiments/sweeps/<name>.toml
        [--jobs N] [--shard K/N] [--merge | --replot] [--reduced] [--out DIR] [--work DIR]

A sweep file (experiments/sweeps/README.md has the format) names a base scene,
its variants (scene overrides, as `pumasim run --set`), a reference and a
cross-check method, and the integrators with their settings. Every (variant,
method, setting) is one run of `pumasim run`, written by pumasim atomically
into build/sweeps/<sweep>/<variant>/<run>/ and repeated for the wall-time
median; then a summary <run>.json is written atomically (temporary file and
rename). A run with a summary is complete and is skipped on a re-run if its
key still matches: a SHA-256 over everything that determines the run -- the
scene as pumasim resolves it with the sweep's and the variant's --set values
(`pumasim check`: every default filled in, the robot file's hash), the
integrator and its options, t_end, the step budget, the repeats, and the
program (`pumasim --version`: revision, compiler, flags; for a build with
uncommitted changes also the binary's own SHA-256). A changed scene, robot
file, setting, horizon or program re-runs the run instead of reusing it, and
--merge refuses a summary whose key no longer matches. An interrupted run
leaves no summary and is redone. A run is run under its lock
(build/sweeps/<sweep>/<run>.lock, fcntl.flock, held by the sweep and the
pumasim it starts until the summary is written; a killed process leaves only
the empty file): two sweep.py processes on one sweep share its runs, each
run run once, and one that finds a run locked does the others first, then
waits and finds it complete. Each attempt first removes the run's folder an
earlier attempt left, so a pumasim that crashes is reported as a crash, never
read from an older folder. A folder that cannot be written (read-only, disk
full) is an error naming it.

Without --shard the runs go to N local processes (--jobs, default: the
number of cores) and the results are merged at the end. --shard K/N takes only
the runs whose index in the sorted run list is K-1 modulo N, so one sweep
splits over machines: as a Slurm job array

    #SBATCH --array=1-8
    python3 experiments/sweep.py S --shard $SLURM_ARRAY_TASK_ID/8 --jobs 1

or under GNU parallel: `parallel python3 experiments/sweep.py S --shard {}/8
--jobs 1 ::: 1 2 3 4 5 6 7 8`; then one `sweep.py S --merge` over the shared
build/sweeps/ writes the table. --merge compares each run with its variant's
reference at the output times in every error measure (tool position [mm],
tool orientation [rad], joint angles [rad], motor currents [A], RMS position,
final state), the reference with its cross-check in the same measures, and
writes results/<sweep>/: <sweep>.csv (every run, failures with their reason,
runs below the reference's accuracy flagged, whether each is within every
target the sweep sets and which it misses, each adaptive run's global error
over its rtol, the wall-time spread), <sweep>.png (the ranking error,
sweep.rank_by, against wall time and against right-hand-side evaluations, one
line per integrator and a panel row per variant, hollow markers below the
reference's accuracy), <sweep>_precision.md (experiments/precision_table.py:
per adaptive method its error over rtol and the slope of log error against
log rtol; per integrator and variant the cheapest run within every target,
and the measure that disqualifies a run cheaper on the ranking measure
alone), <sweep>_cost.png when the sweep has several variants (the RHS
evaluations each integrator needs to be within every target, against the
variant value) and
<sweep>_summary.json for the report (with each variant's reference verdict:
too weak where it differs from its check by more than target/100). These are
written to temporaries first and then renamed into place, the summary last,
carrying each file's SHA-256: a merge killed at any instant leaves the
earlier set or a summary that does not match the table beside it, which the
report refuses (re-run --merge); two merges of one sweep take turns.
Each worker pins its pumasim runs to a CPU of its own where the platform allows.

--reduced (CI): the first and last variants, two settings per method, one
repeat, short horizon, into build/sweeps-reduced/ and --out (default
build/sweeps-reduced/results/<folder>): checks the pipeline end to end,
writes nothing under results/.

The work is done by the experiments package, experiments/pumasim_exp/:
specs (the sweep file read and validated, its runs), runner (running them,
keys, locks, CPU pinning), measures (the error measures), merge (the runs
against their references, into rows), plots and report (the table, the
precision and mode tables, the summary); this file is its command line.
"""
import argparse
import os
import sys

from pumasim_exp.io import ROOT
from pumasim_exp.merge import merge
from pumasim_exp import report
from pumasim_exp.runner import run_share
from pumasim_exp.specs import SweepError, load_sweep, run_list, select_shard
# The measures' functions scripts/check_sweep_pipeline.sh checks as sweep.<name>.
from pumasim_exp.measures import below_reference_accuracy, reference_too_weak, rotation_angle  # noqa: F401
from pumasim_exp.specs import slug  # noqa: F401


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sweep")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--shard", default=None, help="K/N: run only the K-th of N shares of the runs")
    ap.add_argument("--merge", action="store_true", help="only merge finished runs into results/")
    ap.add_argument("--replot", action="store_true",
                    help="only redraw the plots from the table and summary in results/ (no run, no merge)")
    ap.add_argument("--reduced", action="store_true", help="CI: a small version, results outside results/")
    ap.add_argument("--out", default=None, help="results folder (default results/<sweep>)")
    ap.add_argument("--work", default=None, help="the runs' folder (default build/sweeps/<sweep>, "
                    "with --reduced build/sweeps-reduced/<sweep>)")
    args = ap.parse_args()
    # Relative to the caller's folder: pumasim runs with its working directory
    # at the project's root, where a relative --work would land otherwise.
    args.work = os.path.abspath(args.work) if args.work else None
    args.out = os.path.abspath(args.out) if args.out else None
    try:
        s = load_sweep(args.sweep, args.reduced)
        work = args.work or os.path.join(ROOT, "build", "sweeps-reduced" if args.reduced else "sweeps", s["name"])
        out_dir = args.out or os.path.join(ROOT, "build", "sweeps-reduced", "results", s["folder"]) \
            if args.reduced else (args.out or os.path.join(ROOT, "results", s["folder"]))
        if args.replot and (args.merge or args.shard):
            raise SweepError("--replot draws from the committed table alone: not with --merge or --shard")
        if args.replot:
            report.replot(s, work, out_dir)
            print(f"{s['name']}: plots redrawn -> {os.path.relpath(out_dir, ROOT)}/")
            return 0
        runs = run_list(s)
        if not args.merge:
            if args.shard:
                runs = select_shard(runs, args.shard)
            run_share(s, work, runs, args.jobs)
            if args.shard:
                return 0
        summary = merge(s, work, out_dir)
        print(f"{s['name']}: {summary['runs']} runs ({summary['failed']} failed) -> "
              f"{os.path.relpath(out_dir, ROOT)}/")
        return 0
    except SweepError as e:
        print(f"sweep: {e}", file=sys.stderr)
        return 2
    except OSError as e:  # a file or folder that cannot be read or written: the path, not a traceback
        print(f"sweep: {e.filename}: {e.strerror}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
