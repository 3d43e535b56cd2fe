"""Hand-written findings about a results table, each checked against the table.

A finding is a sentence (or a few) that report.py prints under a table, written
by hand after reading it, with assertions beside it that say what in the table
makes it true. report.py checks every assertion against the rows before it
writes anything: a table that no longer supports a sentence fails the report,
naming the sentence, the assertion and the row, instead of leaving the sentence
wrong. The findings live in a sweep file (`[[sweep.findings]]`) or, for the
planning comparison, in experiments/planning_findings.toml (`[[findings]]`):

    [[sweep.findings]]
    text = "Every fixed-step method reaches the target at a small enough step."
    [[sweep.findings.assert]]
    rows = { integrator = ["euler", "ab2", "rk4"] }   # the rows it is about
    per = "integrator"                                # in each integrator's rows
    some = "within"                                   # some row satisfies this

A finding has `text` and either `assert` (one or more assertions) or
`unchecked` (why it states nothing the table could contradict: a definition,
a mechanism, a remark on the method). An assertion's keys:

  table   the rows it reads: "runs" (the sweep's CSV, default), "references"
          (each variant's reference against its cross-check), "creep", "limit"
          (distance of each variant's reference to the limit variant's), or a
          CSV path relative to the results folder ("stiffness/scenes.csv").
  rows    {column = value or [values]}: the rows kept; every value listed must
          match some kept row (a renamed integrator or a dropped setting fails
          instead of leaving the assertion vacuous).
  pick    "cheapest": per variant and integrator, its cheapest run that is
          `within` (the one the report's table shows); pairs without one drop
          out.
  group, values
          group the kept rows by these columns; each group becomes one row with
          them, `n` (its size) and each of `values` ({name = "expression"}, in
          which a column's name is the list of the group's values).
  where   {column = value or [values]}: the grouped rows kept.
  than, match
          pair every row with the rows that `than` selects (a filter like
          `rows`, then the same pick and group; without it, the kept rows
          themselves) and that agree with it in the `match` columns; the
          expression sees the partner as `other`. A row without a partner fails.
  all | none | most | some
          the expression every item (row or pair) satisfies, none satisfies,
          more than half satisfy, or at least one satisfies (in each group of
          `per` columns, if given).

Expressions are Python expressions over a row's columns (numbers as floats,
True/False as booleans, empty as None) and: `target` (the ranking measure's
accuracy target), `error` (the run's error in that measure), `within_ranking`
(the run finished and error <= target), `within` (the report's criterion: a
table with the column within_targets, which sweep.py writes since issue 31,
judges a run on every target the sweep sets, so `within` is within_ranking and
within_targets, and a run within the ranking target that misses another one,
named in its disqualified_by, is not within; a table without that column is
judged on the ranking measure alone, `within` = within_ranking), `dt`, `rtol` and
`setting_value` (from the setting "dt=0.001"), `options` (what follows it, e.g.
"late-events"), `failed_at` (the time in the failure's "at t = ..."), `value`
(the variant's value); functions abs, min, max, sum, len, all, any, sorted,
log10, isnan and fmt (a number as the report prints it, 3 significant digits).
"""
import ast
import math
import re

import tomllib

FUNCS = {"abs": abs, "min": min, "max": max, "sum": sum, "len": len, "all": all, "any": any, "sorted": sorted,
         "log10": math.log10, "isnan": math.isnan, "fmt": lambda x: "–" if x is None or math.isnan(x) else f"{x:.3g}"}
NODES = (ast.Expression, ast.BoolOp, ast.And, ast.Or, ast.UnaryOp, ast.Not, ast.USub, ast.UAdd, ast.BinOp, ast.Add,
         ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.Mod, ast.FloorDiv, ast.Compare, ast.Eq, ast.NotEq, ast.Lt, ast.LtE,
         ast.Gt, ast.GtE, ast.In, ast.NotIn, ast.Is, ast.IsNot, ast.IfExp, ast.Call, ast.Name, ast.Load, ast.Constant,
         ast.Attribute, ast.Tuple, ast.List, ast.GeneratorExp, ast.ListComp, ast.comprehension, ast.Store)
QUANTIFIERS = ("all", "none", "most", "some")
KEYS = {"table", "rows", "pick", "group", "values", "where", "than", "match", "per", *QUANTIFIERS}
IDENTITY = ("variant", "integrator", "setting", "method", "traversal_time_s", "scene", "case", "group")


class FindingsError(Exception):
    """A malformed findings list (not a contradicted one: check() reports those)."""


class Row(dict):
    """A row: its columns by name, also as attributes (`other.steps`)."""

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError:
            raise AttributeError(name) from None


def typed(text):
    """A CSV cell as the expressions see it: bool, None, float or the string."""
    if not isinstance(text, str):
        return text
    if text in ("True", "False"):
        return text == "True"
    if text == "":
        return None
    try:
        return float(text)
    except ValueError:
        return text


SETTING_RE = re.compile(r"^(dt|rtol)=([^_]+)(?:_(.*))?$")
FAILED_AT_RE = re.compile(r"at t = ([0-9.eE+-]+)")


def run_row(raw, rank_column, target):
    """A sweep CSV row with the derived names (the module docstring lists them)."""
    r = Row({k: typed(v) for k, v in raw.items()})
    m = SETTING_RE.match(raw.get("setting", ""))
    r["dt"] = r["rtol"] = r["setting_value"] = None
    r["options"] = ""
    if m:
        r[m.group(1)] = r["setting_value"] = float(m.group(2))
        r["options"] = m.group(3) or ""
    f = FAILED_AT_RE.search(raw.get("failure", ""))
    r["failed_at"] = float(f.group(1)) if f else None
    r["target"] = target
    r["error"] = typed(raw[rank_column])
    r["within_ranking"] = r["ok"] is True and isinstance(r["error"], float) and r["error"] <= target
    # Every target the sweep sets where the table says (within_targets); else the ranking one's alone.
    r["within"] = r["within_ranking"] and r.get("within_targets", True) is True
    return r


def plain_rows(raw_rows):
    """The rows of any other CSV, typed."""
    return [Row({k: typed(v) for k, v in raw.items()}) for raw in raw_rows]


def compile_expression(text, where):
    """The expression compiled, after checking that it uses only the allowed
    constructs (no attribute but a partner's column, no call but FUNCS)."""
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError as e:
        raise FindingsError(f"{where}: not an expression: {text!r} ({e.msg})") from None
    for node in ast.walk(tree):
        if not isinstance(node, NODES):
            raise FindingsError(f"{where}: {type(node).__name__} not allowed in {text!r}")
        if isinstance(node, ast.Attribute) and not (isinstance(node.value, ast.Name) and node.value.id == "other"):
            raise FindingsError(f"{where}: only other.<column> may be an attribute in {text!r}")
        if isinstance(node, ast.Call) and not (isinstance(node.func, ast.Name) and node.func.id in FUNCS):
            raise FindingsError(f"{where}: only {', '.join(sorted(FUNCS))} may be called in {text!r}")
    names = sorted({n.id for n in ast.walk(tree) if isinstance(n, ast.Name)} - set(FUNCS) - {"other"})
    attrs = sorted({n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)})
    return compile(tree, where, "eval"), names, attrs


def evaluate(code, row, other=None):
    """The compiled expression's value for row (and its partner)."""
    scope = {**FUNCS, **row}
    if other is not None:
        scope["other"] = other
    return eval(code, {"__builtins__": {}}, scope)  # noqa: S307 (compiled from a checked tree)


def describe(row, names=()):
    """A row for a message: its identifying columns, then the named ones
    (with the error and target behind `within`, and the measures that
    disqualify it if any)."""
    if "within" in names:
        names = [*names, "ok", "error", "target", *(["disqualified_by"] if row.get("disqualified_by") else [])]
    ident = [str(row[k]) for k in IDENTITY if row.get(k) is not None]
    shown = [f"{k}={fmt_value(row[k])}" for k in dict.fromkeys(names) if k in row and k not in IDENTITY]
    return " ".join(ident) + (" (" + ", ".join(shown) + ")" if shown else "")


def fmt_value(v):
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, list) and len(v) > 6:
        return "[" + ", ".join(fmt_value(x) for x in v[:6]) + ", …]"
    return repr(v) if isinstance(v, str) else str(v)


def select(rows, spec, where):
    """The rows matching the filter spec; FindingsError if a column is unknown,
    AssertionFailed if a listed value matches no kept row."""
    if not spec:
        return list(rows)
    if not isinstance(spec, dict):
        raise FindingsError(f"{where}: expected a table {{column = value}}, got {spec!r}")
    wanted = {k: v if isinstance(v, list) else [v] for k, v in spec.items()}
    for k in wanted:
        if rows and all(k not in r for r in rows):
            raise FindingsError(f"{where}: no column '{k}' (columns: {', '.join(sorted(rows[0]))})")
    kept = [r for r in rows if all(r.get(k) in vs for k, vs in wanted.items())]
    for k, vs in wanted.items():
        missing = [v for v in vs if all(r.get(k) != v for r in kept)]
        if missing:
            raise AssertionFailed(f"{k} = {', '.join(map(repr, missing))} matches no row")
    return kept


class AssertionFailed(Exception):
    """An assertion the rows contradict (its message names the rows)."""


def cheapest(rows):
    """Per (variant, integrator) the cheapest row that is `within` (every
    target the sweep sets where the table has within_targets, else the
    ranking one's), in the order of the rows (report.cheapest_runs picks the
    same)."""
    best = {}
    for r in rows:
        key = (r.get("variant"), r.get("integrator"))
        if r["within"] and (key not in best or r["rhs_evaluations"] < best[key]["rhs_evaluations"]):
            best[key] = r
    return list(best.values())


def grouped(rows, by, values, where):
    """One row per group of rows equal in the columns by: those columns, n,
    and each of values evaluated with the group's columns as lists."""
    by = [by] if isinstance(by, str) else list(by)
    groups = {}
    for r in rows:
        groups.setdefault(tuple(r.get(k) for k in by), []).append(r)
    out = []
    for key, members in groups.items():
        g = Row(zip(by, key))
        g["group"] = ", ".join(f"{k}={v}" for k, v in zip(by, key)) or "all rows"
        g["n"] = len(members)
        columns = {k: [m.get(k) for m in members] for k in members[0]}
        for name, text in (values or {}).items():
            code, _, _ = compile_expression(text, f"{where}.values.{name}")
            try:
                g[name] = evaluate(code, columns)
            except Exception as e:  # noqa: BLE001 (any error of the expression is the assertion's)
                raise AssertionFailed(f"values.{name} = {text!r}: {type(e).__name__}: {e} in group {g['group']}")
        out.append(g)
    return out


def prepared(a, rows, spec, where):
    """The table's rows matching the filter spec, then picked and grouped as a says."""
    rows = select(rows, spec, where)
    if a.get("pick") == "cheapest":
        rows = cheapest(rows)
    elif a.get("pick") is not None:
        raise FindingsError(f"{where}: pick: expected \"cheapest\"")
    if "group" in a:
        rows = select(grouped(rows, a["group"], a.get("values"), where), a.get("where"), f"{where}.where")
    if not rows:
        raise AssertionFailed("selects no row")
    return rows


def items_of(a, table, where):
    """The items the quantifier runs over: the selected rows, or (row, partner) pairs."""
    rows = prepared(a, table, a.get("rows"), f"{where}.rows")
    if "than" not in a and "match" not in a:
        return [(r, None) for r in rows]
    pool = prepared(a, table, a["than"], f"{where}.than") if "than" in a else rows
    match = [a["match"]] if isinstance(a.get("match"), str) else list(a.get("match", []))
    pairs = []
    for r in rows:
        partners = [o for o in pool if o is not r and all(o.get(k) == r.get(k) for k in match)]
        if not partners:
            raise AssertionFailed(f"no row to compare {describe(r)} with")
        pairs += [(r, o) for o in partners]
    return pairs


def check_assertion(a, rows, where):
    """None if the rows satisfy assertion a, else the reason, naming the rows."""
    unknown = set(a) - KEYS
    if unknown:
        raise FindingsError(f"{where}: unknown key(s) {', '.join(sorted(unknown))}; expected {', '.join(sorted(KEYS))}")
    quant = [q for q in QUANTIFIERS if q in a]
    if len(quant) != 1:
        raise FindingsError(f"{where}: expected exactly one of {', '.join(QUANTIFIERS)}")
    q, text = quant[0], a[quant[0]]
    code, names, attrs = compile_expression(text, f"{where}.{q}")
    try:
        items = items_of(a, rows, where)
        results = []
        for r, o in items:
            try:
                results.append(bool(evaluate(code, r, o)))
            except Exception as e:  # noqa: BLE001
                raise AssertionFailed(f"{type(e).__name__}: {e} at {item_text(r, o, names, attrs)}")
    except AssertionFailed as e:
        return f"{q} = {text!r}: {e}"
    return verdict(q, text, a.get("per"), items, results, names, attrs)


def item_text(r, o, names, attrs):
    return describe(r, names) + ("" if o is None else f" against {describe(o, attrs)}")


def verdict(q, text, per, items, results, names, attrs):
    """None if the quantifier q holds over the items' results, else the reason."""
    label = f"{q} = {text!r}"
    if q in ("all", "none"):
        bad = [k for k, ok in enumerate(results) if ok != (q == "all")]
        if bad:
            r, o = items[bad[0]]
            more = f" (and {len(bad) - 1} more)" if len(bad) > 1 else ""
            return f"{label} fails at {item_text(r, o, names, attrs)}{more}"
        return None
    if q == "most":
        n = sum(results)
        return None if 2 * n > len(results) else f"{label} holds for {n} of {len(results)}, not most"
    per = [per] if isinstance(per, str) else list(per or [])
    groups = {}
    for (r, o), ok in zip(items, results):
        groups.setdefault(tuple(r.get(k) for k in per), []).append((r, o, ok))
    for key, members in groups.items():
        if not any(ok for _, _, ok in members):
            who = ", ".join(f"{k}={v}" for k, v in zip(per, key)) or "the selected rows"
            shown = "; ".join(item_text(r, o, names, attrs) for r, o, _ in members[:8])
            return f"{label}: no row of {who} satisfies it ({shown}{'; …' if len(members) > 8 else ''})"
    return None


def check(findings, tables, where):
    """The problems (strings) of a findings list against tables ({name: rows}):
    each contradicted assertion, naming its finding's sentence and the rows."""
    problems = []
    for k, f in enumerate(validated(findings, where), 1):
        for j, a in enumerate(f.get("assert", []), 1):
            at = f"{where}: finding {k}, assertion {j}"
            name = a.get("table", "runs")
            if name not in tables:
                raise FindingsError(f"{at}: no table '{name}' (tables: {', '.join(sorted(tables))})")
            reason = check_assertion(a, tables[name], at)
            if reason:
                problems.append(f"{at} ({name}): {reason}\n    the sentence: {f['text']}")
    return problems


def validated(findings, where):
    """The findings list, after checking its shape."""
    if not isinstance(findings, list):
        raise FindingsError(f"{where}: findings must be a list of tables with text and assert (or unchecked)"
                            f" (experiments/findings.py), not {type(findings).__name__}")
    for k, f in enumerate(findings, 1):
        if not isinstance(f, dict) or not isinstance(f.get("text"), str):
            raise FindingsError(f"{where}: finding {k}: needs text = \"...\"")
        extra = set(f) - {"text", "assert", "unchecked"}
        if extra:
            raise FindingsError(f"{where}: finding {k}: unknown key(s) {', '.join(sorted(extra))}")
        if bool(f.get("assert")) == bool(f.get("unchecked")):
            raise FindingsError(f"{where}: finding {k} ({f['text'][:60]}…): needs assertions (assert) or, "
                                "for a sentence the table cannot contradict, unchecked = \"why\" (not both)")
    return findings


def text(findings):
    """The findings' sentences as the report's paragraph."""
    return " ".join(f["text"].strip() for f in findings)


def sweep_findings(path):
    """The [[sweep.findings]] of the sweep file at path ([] if it has none)."""
    with open(path, "rb") as f:
        return tomllib.load(f)["sweep"].get("findings", [])
