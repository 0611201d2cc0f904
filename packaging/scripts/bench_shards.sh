#!/usr/bin/env bash
# Shard scaling of a bake (docs/cluster-bake.md): the single bake, then the
# same bake in 2 and 4 shards run one after another on this machine, each
# merged and compared byte for byte with the single bake. Prints the table of
# docs/cluster-bake.md: CPU seconds of the shards against the single bake
# (duplicated work) and the imbalance (slowest shard / mean), by wall and CPU.
# Usage: bench_shards.sh [OSM] [WORK] [bake options...]
#   default: data/osm/sf-downtown-2023.osm.pbf, out/bench-shards, --impostor both --jobs 2
# About 55 min for San Francisco on the 2-core development VM.
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
osm=$(realpath "${1:-$root/data/osm/sf-downtown-2023.osm.pbf}")
work=${2:-$root/out/bench-shards}
shift $(($# < 2 ? $# : 2))
opts=("$@")
[ ${#opts[@]} -gt 0 ] || opts=(--impostor both --jobs 2)
blvd=$root/build/sdk/cli/blvd
mkdir -p "$work" && cd "$work"
timed() {  # timed NAME blvd-args...: wall and CPU seconds into NAME.time, stdout into NAME.txt
  local name=$1
  shift
  /usr/bin/time -f "%e %U %S" -o "$name.time" "$blvd" "$@" > "$name.txt"
}
timed single bake --quiet "$osm" -o single.blvd "${opts[@]}"
for n in 2 4; do
  rm -f s$n-*.blvdshard
  for ((i = 0; i < n; i++)); do timed s$n-$i bake --quiet "$osm" -o s$n-$i.blvdshard "${opts[@]}" --shard $i/$n; done
  "$blvd" pack merge s$n-*.blvdshard -o m$n.blvd > merge$n.txt
  cmp single.blvd m$n.blvd
done
python3 - <<'PY'
import re
def t(name):
    w, u, s = open(name + ".time").read().split()[-3:]
    return float(w), float(u) + float(s)
def samples(name):
    return int(re.search(r"(\d+) item-buffer samples", open(name + ".txt").read()).group(1))
w1, c1 = t("single")
print("| shards | slowest shard | sum of shards' CPU | ÷ single bake's CPU | imbalance (wall / CPU) | item-buffer samples | merge |")
print("|---|---|---|---|---|---|---|")
print(f"| 1 (single bake) | {w1:.0f} s | {c1:.0f} s | 1.000 | 1.00 / 1.00 | {samples('single')} | – |")
for n in (2, 4):
    ts = [t(f"s{n}-{i}") for i in range(n)]
    ws, cs = [x[0] for x in ts], [x[1] for x in ts]
    sm = sum(samples(f"s{n}-{i}") for i in range(n))
    mg = re.search(r"in ([\d.]+) s", open(f"merge{n}.txt").read()).group(1)
    print(f"| {n} | {max(ws):.0f} s | {sum(cs):.0f} s | {sum(cs) / c1:.3f} | {max(ws) / (sum(ws) / n):.2f} / "
          f"{max(cs) / (sum(cs) / n):.2f} | {sm} (+{sm - samples('single')}) | {mg} s, identical |")
PY
