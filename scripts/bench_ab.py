#!/usr/bin/python3
"""A/B timing of two Google Benchmark binaries, interleaved: before, after, before, after, ...

    /usr/bin/python3 scripts/bench_ab.py BEFORE AFTER [RUNS] [extra benchmark arguments]

Each run executes each binary once (--benchmark_min_time=0.3, JSON output); the table gives,
per benchmark, the least CPU time over the runs of each binary and their ratio after/before.
The minimum, not the median: on a shared machine noise only adds time. Benchmarks whose code
did not change (a back-end's fd row) show the noise floor of the ratio in the same table.
"""
import json,subprocess,sys,statistics,collections
bins=dict(before=sys.argv[1], after=sys.argv[2]); reps=int(sys.argv[3]) if len(sys.argv) > 3 else 6; extra=sys.argv[4:]
d=collections.defaultdict(lambda: collections.defaultdict(list))
for i in range(reps):
    for v,b in bins.items():
        out=subprocess.run([b,'--benchmark_format=json','--benchmark_min_time=0.3']+extra,capture_output=True,text=True).stdout
        for bm in json.loads(out)['benchmarks']:
            d[bm['name']][v].append(bm['cpu_time'])
for name in d:
    b=min(d[name]["before"]); a=min(d[name]["after"])
    print(f"{name:50s} before {b:9.1f} after {a:9.1f} ratio {a/b:.3f}  (runs {len(d[name]['before'])})")
