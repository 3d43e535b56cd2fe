"""The experiments package: what experiments/*.py share, built on the
pumasim binary's run folders and JSON documents; the one text of pumasim's
it reads, `pumasim check`'s resolved scene, goes into a run's key as it is
(paths left out), no number taken from it.

    io        run folders and sweep tables (with files' primitives re-exported)
    files     atomic writes, JSON, locks, output sets, a private copy of pumasim
    specs     a sweep file read and validated; its runs
    runner    running a sweep's runs (keys, locks, CPU pinning, summaries)
    measures  the error measures of a run against its reference
    merge     a sweep's runs against their references, into rows
    plots     a sweep's plots
    report    a sweep's table, precision and mode tables, and summary

Scripts in experiments/ import it as `from pumasim_exp import io as pumasim_io`;
from scripts/ or tests/, experiments/ goes first on sys.path.
"""
