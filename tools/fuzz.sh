#!/usr/bin/env bash
# Coverage-guided fuzzing with clang and libFuzzer (ASan + UBSan):
#   tools/fuzz.sh TARGET SECONDS     one campaign, e.g. tools/fuzz.sh fuzz_nmea 3600
#   tools/fuzz.sh all SECONDS        every target in turn, SECONDS each
#   tools/fuzz.sh list               the targets
# Configures and builds build-fuzz (BLVD_FUZZ_BUILD to change it) with the
# whole SDK instrumented, then runs tests/fuzz/campaign.sh: the corpus is kept
# in build-fuzz/fuzz/<target>/corpus from one campaign to the next, a crash is
# minimised into tests/fuzz/regressions/<target>/ (commit it with the fix: CI
# replays it), and each campaign's line is added to build-fuzz/fuzz-campaigns.tsv
# (date, target, seconds, executions, executions/s, cov, ft, corpus, result).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BLVD_FUZZ_BUILD:-$root/build-fuzz}
what=${1:?usage: tools/fuzz.sh TARGET|all|list [SECONDS]}

if [ ! -f "$build/build.ninja" ]; then
  CC=clang CXX=clang++ cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DBLVD_FUZZ=ON -DBLVD_SANITIZE=ON -DBLVD_BUILD_SAMPLES=OFF > /dev/null
fi
targets=$(sed -n 's/^build tests\/fuzz\/\(fuzz_[a-z_]*\): .*/\1/p' "$build/build.ninja" | sort -u)
if [ "$what" = list ]; then
  echo "$targets"
  exit 0
fi
secs=${2:?usage: tools/fuzz.sh TARGET|all SECONDS}
[ "$what" = all ] && run=$targets || run=$what
for t in $run; do
  grep -qx "$t" <<< "$targets" || { echo "tools/fuzz.sh: no fuzz target $t (tools/fuzz.sh list)" >&2; exit 2; }
done
# shellcheck disable=SC2086
ninja -C "$build" $run

rc=0
for t in $run; do
  set +e
  out=$(bash "$root/tests/fuzz/campaign.sh" "$build/tests/fuzz/$t" "$build/tests/fuzz/$t.inputs" "$secs" \
        "$build/fuzz/$t" 2>&1)
  r=$?
  set -e
  echo "$out"
  line=$(tail -n 1 <<< "$out")
  if [ $r = 0 ]; then
    # "<t>: <s> s, <n> executions (<r>/s), cov <c>, ft <f>, corpus <k>"
    read -r execs rate cov ft corpus < <(sed -E 's/.*s, ([0-9]+) executions \(([0-9]+)\/s\), cov ([0-9]+), ft ([0-9]+), corpus ([0-9]+)/\1 \2 \3 \4 \5/' <<< "$line")
    result=ok
  else
    execs=- rate=- cov=- ft=- corpus=- result="crash: $(grep -oE 'kept as .*' <<< "$out" | head -n 1)"
    rc=1
  fi
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$(date -u +%FT%TZ)" "$t" "$secs" "$execs" "$rate" "$cov" "$ft" \
    "$corpus" "$result" >> "$build/fuzz-campaigns.tsv"
done
exit $rc
