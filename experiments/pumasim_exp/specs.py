"""A sweep file (experiments/sweeps/README.md has the format) read and
validated: the [sweep] table (unknown keys refused, defaults filled in, an
accuracy target per error measure), the reference and its cross-check, the
variants, the integrators with their settings, the --reduced version of it,
and the sorted list of its runs. Every malformed key is a SweepError naming
the file and the key."""
import json
import os
import subprocess
import tomllib

from .io import PUMASIM, ROOT
from .measures import DEFAULT_RANK, MEASURES


class SweepError(Exception):
    """Bad input (a malformed sweep file, a run that cannot be run or
    merged): sweep.py prints it and exits with status 2."""


# The keys a [sweep] table may have.
SWEEP_KEYS = {"name", "title", "scene", "folder", "t_end", "reduced_t_end", "repeats", "x", "target_mm",
              "findings", "set", "max_steps", "limit_variant", "stuck_variant", "rank_by",
              *(m[2] for m in MEASURES.values())}


def _need(path, table, key, kind, where):
    """table[key], which must exist and be a `kind`; else a SweepError naming path and where."""
    if key not in table:
        raise SweepError(f"{path}: {where}: missing required key '{key}'")
    if not isinstance(table[key], kind):
        raise SweepError(f"{path}: {where}.{key}: expected {kind.__name__}, got {type(table[key]).__name__}")
    return table[key]


def _read_toml(path):
    """The sweep file's TOML document."""
    with open(path, "rb") as f:
        try:
            return tomllib.load(f)
        except tomllib.TOMLDecodeError as e:
            raise SweepError(f"{path}: TOML syntax error: {e}")


def _sweep_table(path, doc):
    """The [sweep] table's settings (unknown keys refused, defaults filled in),
    with the accuracy targets per measure; and the table itself."""
    known = {"sweep", "reference", "check", "variant", "method"}
    for k in doc:
        if k not in known:
            raise SweepError(f"{path}: unknown table '{k}'; expected one of: {', '.join(sorted(known))}")
    sw = _need(path, doc, "sweep", dict, "(top level)")
    for k in sw:
        if k not in SWEEP_KEYS:
            raise SweepError(f"{path}: unknown key 'sweep.{k}'")
    s = {
        "name": _need(path, sw, "name", str, "sweep"),
        "title": sw.get("title", sw["name"]),
        "scene": _need(path, sw, "scene", str, "sweep"),
        "t_end": float(sw["t_end"]) if "t_end" in sw else None,
        "repeats": int(sw.get("repeats", 3)),
        "x": sw.get("x", "variant"),
        "target_mm": float(sw.get("target_mm", 1e-3)),
        "findings": sw.get("findings", ""),
        "set": list(sw.get("set", [])),
        "folder": sw.get("folder", sw["name"]),
        "max_steps": int(sw.get("max_steps", 0)),
        "limit_variant": sw.get("limit_variant"),
        "stuck_variant": sw.get("stuck_variant"),
        "file": os.path.relpath(path, ROOT),
        "rank_by": sw.get("rank_by", DEFAULT_RANK),
    }
    if s["rank_by"] not in MEASURES:
        raise SweepError(f"{path}: sweep.rank_by: expected one of: {', '.join(MEASURES)}")
    # Accuracy targets per measure (the position one has always a value).
    s["targets"] = {col: (s["target_mm"] if key == "target_mm" else float(sw[key]))
                    for col, _, key, _ in MEASURES.values() if key == "target_mm" or key in sw}
    if MEASURES[s["rank_by"]][0] not in s["targets"]:
        raise SweepError(f"{path}: sweep.rank_by = \"{s['rank_by']}\" needs its target "
                         f"sweep.{MEASURES[s['rank_by']][2]}")
    return s, sw


def _method_of(path, t, where):
    """(integrator, options) of a [reference] or [check] table."""
    for k in t:
        if k not in ("integrator", "options"):
            raise SweepError(f"{path}: unknown key '{where}.{k}'; expected integrator, options")
    return (_need(path, t, "integrator", str, where), [str(o) for o in t.get("options", [])])


def _variants(path, doc, s):
    """The [[variant]] tables (default: one variant, 'base'), each with its
    reference and cross-check (default: the sweep's)."""
    variants = []
    for k, v in enumerate(doc.get("variant", [{"label": "base", "set": []}])):
        for key in v:
            if key not in ("label", "value", "set", "unset", "reference", "check", "methods", "if_integrator"):
                raise SweepError(f"{path}: unknown key 'variant[{k}].{key}'")
        lab = _need(path, v, "label", str, f"variant[{k}]")
        variants.append({"label": lab, "value": v.get("value", k), "set": list(v.get("set", [])),
                         # keys of the scene file removed before the --set values (pumasim run --unset):
                         # a law that has no use for one of the scene's keys
                         "unset": list(v.get("unset", [])),
                         "reference": _method_of(path, v["reference"], f"variant[{k}].reference")
                         if "reference" in v else s["reference"],
                         "check": _method_of(path, v["check"], f"variant[{k}].check") if "check" in v else s["check"],
                         # its own [[method]] list (default: the sweep's), and an integrator it needs
                         "methods": _methods(path, {"method": v["methods"]}, f"variant[{k}].methods")
                         if "methods" in v else None,
                         "if_integrator": v.get("if_integrator")})
    return variants


def _listed_integrators():
    """The integrators `pumasim integrators` lists."""
    p = subprocess.run([PUMASIM, "integrators", "--json"], capture_output=True, text=True)
    if p.returncode != 0:
        raise SweepError(f"{PUMASIM} integrators --json: exit status {p.returncode}: {p.stderr.strip()}")
    return {entry["name"] for entry in json.loads(p.stdout)}


def _guarded(s):
    """Leaves out, in place, the variants whose if_integrator pumasim does not
    list (an integrator not built yet: the variant runs once it is), naming
    them in s["skipped_variants"]."""
    needed = [v for v in s["variants"] if v["if_integrator"]]
    listed = _listed_integrators() if needed else set()
    s["skipped_variants"] = [f"{v['label']} (needs the integrator {v['if_integrator']}, which this pumasim "
                             "does not list)" for v in needed if v["if_integrator"] not in listed]
    s["variants"] = [v for v in s["variants"] if not v["if_integrator"] or v["if_integrator"] in listed]


def _methods(path, doc, where="method"):
    """(integrator, settings, extra options) per integrator of the [[method]]
    tables; a setting is (kind, value, pumasim options), kind 'dt' or 'rtol'."""
    methods = []
    for k, m in enumerate(_need(path, doc, "method", list, "(top level)")):
        names = _need(path, m, "integrator", list, f"{where}[{k}]")
        if "dt" in m:
            settings = [("dt", float(d), ["--dt", repr(float(d))]) for d in m["dt"]]
        elif "rtol" in m:
            fac = float(m.get("atol_factor", 1e-3))
            settings = [("rtol", float(r), ["--rtol", repr(float(r)), "--atol", repr(float(r) * fac)])
                        for r in m["rtol"]]
        else:
            raise SweepError(f"{path}: {where}[{k}]: expected 'dt' or 'rtol'")
        extra = [str(o) for o in m.get("options", [])]
        for name in names:
            methods.append((name, settings, extra))
    return methods


def _reduce(s, sw):
    """--reduced, in place: the first and last variants, two settings per
    method, one repeat, the reduced horizon if the sweep names one."""
    s["variants"] = [s["variants"][0]] + ([s["variants"][-1]] if len(s["variants"]) > 1 else [])
    s["methods"] = [(n, st[:2], ex) for n, st, ex in s["methods"]]
    for v in s["variants"]:
        if v["methods"]:
            v["methods"] = [(n, st[:2], ex) for n, st, ex in v["methods"]]
    s["repeats"] = 1
    labels = [v["label"] for v in s["variants"]]
    for key in ("limit_variant", "stuck_variant"):
        if s[key] not in labels:
            s[key] = None
    if "reduced_t_end" in sw:
        s["t_end"] = float(sw["reduced_t_end"])


def load_sweep(path, reduced):
    """The sweep file at path as a dict (experiments/sweeps/README.md has the
    format); SweepError naming the key if it is malformed."""
    doc = _read_toml(path)
    s, sw = _sweep_table(path, doc)
    for key in ("reference", "check"):
        s[key] = _method_of(path, _need(path, doc, key, dict, "(top level)"), key)
    s["variants"] = _variants(path, doc, s)
    for key in ("limit_variant", "stuck_variant"):
        if s[key] and s[key] not in [v["label"] for v in s["variants"]]:
            raise SweepError(f"{path}: sweep.{key}: expected one of the variants' labels")
    s["methods"] = _methods(path, doc)
    _guarded(s)
    if reduced:
        _reduce(s, sw)
    return s


def slug(text):
    return "".join(c if c.isalnum() or c in "-._" else "_" for c in text)


def run_list(s):
    """Every run of the sweep, sorted by id: (id, variant, tag, integrator, options, repeats)."""
    runs = []
    for v in s["variants"]:
        vdir = slug(v["label"])
        runs.append((f"{vdir}/reference", v, "reference", *v["reference"], 1))
        runs.append((f"{vdir}/check", v, "check", *v["check"], 1))
        for name, settings, extra in v["methods"] or s["methods"]:
            for kind, value, opts in settings:
                tag = f"{name}_{kind}{value:g}" + ("_" + slug(" ".join(o.lstrip("-") for o in extra)) if extra else "")
                runs.append((f"{vdir}/{tag}", v, tag, name, opts + extra, s["repeats"]))
    return sorted(runs, key=lambda r: r[0])


def select_shard(runs, shard):
    """The runs of the share `shard` ("K/N", 1 <= K <= N): those whose index
    in the sorted run list is K-1 modulo N; SweepError if shard is malformed."""
    try:
        k, n = (int(x) for x in shard.split("/"))
    except ValueError:
        k = n = None
    if k is None or not 1 <= k <= n:
        raise SweepError(f"--shard {shard}: expected K/N with 1 <= K <= N")
    return [r for i, r in enumerate(runs) if i % n == k - 1]
