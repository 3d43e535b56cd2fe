"""Mutation test of scripts/check_claims.py (issue 31): a changed figure is flagged at its line.

    /usr/bin/python3 -m pytest -q tests/test_claims_mutation.py

For every document the claims check reads (README.md, docs/**/*.md, the
checked results/*.md), it picks, with a fixed seed, up to 20 figures of each
kind among those the check finds backed by a results file: integers,
decimals, ratios ("1.73×") and times (ms, s, µs, ns, min). Each figure's last
shown digit is changed (up by one, a 9 down by one: the format stays), the
check runs on the mutated copy of the document in-process (the results and
input files read once) and must flag that figure's line, and no line that
was not mutated. The figures of one kind are mutated together in one copy
when they stand on different lines (the check classifies a figure by its own
value and what its sentence, paragraph and section name, so mutations on
different lines cannot mask each other; each one must be flagged all the
same). The documents as committed must have no unbacked figure; across the
documents at least 20 figures of each kind must have been mutated.
"""
import collections
import os
import random
import re
import sys

import pytest

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import check_claims  # noqa: E402

PER_KIND = 20
SEED = 31
KINDS = ("integer", "decimal", "ratio", "time")
TIME_UNITS = {"ns", "µs", "us", "ms", "s", "min", "h"}


@pytest.fixture(scope="module")
def claims():
    return check_claims.Claims(ROOT)


@pytest.fixture(scope="module")
def documents(claims):
    """{path relative to the root: (text, its figures)} of every checked document."""
    out = {}
    for path in claims.documents():
        drel = check_claims.rel(path, claims.root)
        with open(path, encoding="utf-8") as f:
            raw = f.read()
        out[drel] = (raw, claims.check(drel, raw))
    return out


def kind(fig, raw):
    """The figure's kind (KINDS), None for one the test does not mutate (a 10^k power)."""
    number = raw[fig.start:fig.end]
    if "^" in number:
        return None
    if fig.unit in ("×", "x"):
        return "ratio"
    if fig.unit in TIME_UNITS:
        return "time"
    return "decimal" if re.search(r"[.eE]", number) else "integer"


def mutated(raw, fig):
    """raw with the figure's last mantissa digit changed (+1; 9 -> 8)."""
    m = check_claims.NUM_RE.match(raw, fig.start)
    i = m.end("mant") - 1
    d = int(raw[i])
    return raw[:i] + str(d + 1 if d < 9 else d - 1) + raw[i + 1:]


def picks(raw, figures, rng):
    """{kind: up to PER_KIND backed figures of that kind, chosen with rng}."""
    by_kind = collections.defaultdict(list)
    for f in figures:
        k = kind(f, raw) if f.cls == "backed" else None
        if k:
            by_kind[k].append(f)
    return {k: (rng.sample(fs, PER_KIND) if len(fs) > PER_KIND else fs) for k, fs in by_kind.items()}


def test_committed_documents_have_no_unbacked_figure(documents):
    bad = [f"{f.doc}:{f.line}: {f.text} ({f.detail})"
           for _, figures in documents.values() for f in figures if f.cls == "UNBACKED"]
    assert not bad, "\n".join(bad)


def batches(figs):
    """figs split into lists with one figure per line each, in order."""
    out = []
    for f in figs:
        spot = next((b for b in out if all(g.line != f.line for g in b)), None)
        if spot is None:
            out.append(spot := [])
        spot.append(f)
    return out


def test_every_mutated_figure_is_flagged_at_its_line(claims, documents):
    rng = random.Random(SEED)
    mutated_per_kind, missed, extra = collections.Counter(), [], []
    for drel in sorted(documents):
        raw, figures = documents[drel]
        for k, figs in sorted(picks(raw, figures, rng).items()):
            for batch in batches(figs):
                text = raw
                for fig in batch:
                    text = mutated(text, fig)
                flagged = {f.line for f in claims.check(drel, text) if f.cls == "UNBACKED"}
                mutated_per_kind[k] += len(batch)
                missed += [f"{drel}:{fig.line}: {fig.text} -> {check_claims.NUM_RE.match(text, fig.start).group(0)} "
                           f"({k}) not flagged" for fig in batch if fig.line not in flagged]
                extra += [f"{drel}:{line}: flagged, not mutated ({k})" for line in flagged - {f.line for f in batch}]
    print(dict(mutated_per_kind))
    assert not missed, "\n".join(missed)
    assert not extra, "\n".join(extra)
    for k in KINDS:
        assert mutated_per_kind[k] >= PER_KIND, f"only {mutated_per_kind[k]} {k} figures to mutate"
