#!/usr/bin/env bash
# A/B comparison of two bench_assembly binaries on the same machine: runs them alternately
# ROUNDS times (old, new, old, new, ...) and prints, per benchmark, the median over rounds of each
# binary's median time, and new/old. Alternation spreads the host's load over both.
#   bench/ab_assembly.sh OLD_BIN NEW_BIN [ROUNDS=3] [FILTER]
set -euo pipefail
old=${1:?usage: ab_assembly.sh OLD_BIN NEW_BIN [ROUNDS] [FILTER]}
new=${2:?usage: ab_assembly.sh OLD_BIN NEW_BIN [ROUNDS] [FILTER]}
rounds=${3:-3}
filter=${4:-'(fem|interpolated|polydec|vrm|cotan)/'}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for r in $(seq 1 "$rounds"); do
  for side in old new; do
    bin=$old; [ "$side" = new ] && bin=$new
    "$bin" --benchmark_filter="$filter" --benchmark_repetitions=3 --benchmark_report_aggregates_only=true \
      --benchmark_format=json >"$work/$side.$r.json" 2>/dev/null
  done
done
python3 - "$work" "$rounds" <<'PY'
import json, statistics, sys
work, rounds = sys.argv[1], int(sys.argv[2])
times = {"old": {}, "new": {}}
for side in times:
    for r in range(1, rounds + 1):
        for b in json.load(open(f"{work}/{side}.{r}.json"))["benchmarks"]:
            if b.get("aggregate_name") == "median":
                name = b["run_name"].replace("/min_time:0.500/real_time", "")
                times[side].setdefault(name, []).append(b["real_time"])
print(f"| benchmark | old ms | new ms | new/old |")
print(f"|---|---|---|---|")
for name in times["old"]:
    if name not in times["new"]:
        continue
    o, n = statistics.median(times["old"][name]), statistics.median(times["new"][name])
    print(f"| {name} | {o:.1f} | {n:.1f} | {n / o:.2f} |")
PY
