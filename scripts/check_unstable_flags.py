#!/usr/bin/python3
"""No run that a committed table had ok is now flagged unstable (issue 31).

    /usr/bin/python3 scripts/check_unstable_flags.py REV

After results/ is regenerated with the physical bounds
(models/plant/physical_bounds.hpp), compares every sweep table under results/
with the same table at git revision REV (made before the bounds existed):
each run the regenerated table flags "unstable" is listed with what REV's
table said of it, and the exit status is 1 if REV had it ok (finished, and
within its targets where the table says so): a bound that flags a good run
is wrong. Exit 0 when every run flagged was already a failure at REV, or
diverged unseen there (ok but past a target).
"""
import csv
import glob
import io
import re
import subprocess
import sys


def rows(text):
    lines = [line for line in text.splitlines() if not line.startswith("#")]
    return list(csv.DictReader(io.StringIO("\n".join(lines))))


def target_of(text):
    """The ranking measure's target from a sweep table's header comment ("target 0.005 mm"), or None."""
    m = re.search(r"^# ranked by .*?, target ([0-9.e+-]+) mm", text, re.M)
    return float(m.group(1)) if m else None


def within(r, target):
    """Within the table's position target (a table without one: ok is enough)."""
    try:
        return target is None or float(r.get("max_tool_position_error_mm")) <= target
    except (TypeError, ValueError):
        return False


def key(r):
    return (r.get("variant"), r.get("integrator"), r.get("setting"))


def main():
    rev, bad, flagged = sys.argv[1], 0, 0
    for path in sorted(glob.glob("results/**/*.csv", recursive=True)):
        p = subprocess.run(["git", "show", f"{rev}:{path}"], capture_output=True, text=True)
        if p.returncode != 0:
            continue
        new = rows(open(path).read())
        if not new or "failure" not in new[0]:
            continue
        before = {key(r): r for r in rows(p.stdout)}
        target = target_of(p.stdout)
        for r in new:
            if "unstable at t = " not in (r.get("failure") or ""):
                continue
            flagged += 1
            b = before.get(key(r))
            was_good = b is not None and b.get("ok") == "True" and within(b, target)
            bad += was_good
            print(f"{path}: {key(r)}: now {r['failure'][:100]}...; at {rev}: "
                  + ("absent" if b is None else f"ok={b.get('ok')}, tool error {b.get('max_tool_position_error_mm')} "
                     f"mm, current error {b.get('max_current_error_A')} A") + (" <- WAS GOOD" if was_good else ""))
    print(f"check_unstable_flags: {flagged} runs flagged unstable, {bad} of them ok and within target at {rev}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
