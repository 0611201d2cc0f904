#!/usr/bin/env bash
# One libFuzzer campaign of a fuzz target built with BLVD_FUZZ:
#   campaign.sh FUZZER INPUTS SECONDS WORKDIR [libFuzzer flags...]
# INPUTS is the target's <name>.inputs (CMake writes it): the folder its seeds
# go to (BLVD_FUZZ_SEED_DIR), then folders and files to start from. libFuzzer
# takes folders only, so files are copied into WORKDIR/files. What the campaign
# finds goes to WORKDIR/corpus, kept from one run to the next.
# SECONDS 0 runs every input once (a replay).
# A crash, leak, timeout (one that times out again alone) or out-of-memory
# is minimised into
# tests/fuzz/regressions/<target>/ (which CTest replays from then on), and the
# script exits 1 naming it and the command that reproduces it.
# The last line: "<target>: <s> s, <n> executions (<n>/s), cov <n>, ft <n>, corpus <n>".
set -euo pipefail
bin=$1 list=$2 secs=$3 work=$4
shift 4
name=$(basename "$bin")
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$work/corpus" "$work/files" "$work/artifacts"

dirs=()
first=1
while IFS= read -r p; do
  [ -n "$p" ] || continue
  if [ "$first" = 1 ]; then  # the seeds' folder: written by the target at start-up
    export BLVD_FUZZ_SEED_DIR=$p
    mkdir -p "$p"
    first=0
  fi
  if [ -d "$p" ]; then dirs+=("$p")
  elif [ -f "$p" ]; then cp -f "$p" "$work/files/"
  else echo "$name: input $p not found" >&2; exit 2
  fi
done < "$list"
# BLVD_FUZZ_SEED fixes libFuzzer's random seed (CI's short campaigns: the same
# mutations in the same order on every run); unset, each campaign draws its own.
# Leaks of the system's libraries that blvd cannot free, each explained there.
export LSAN_OPTIONS="suppressions=$here/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
flags=(-timeout=25 -rss_limit_mb=2048 -print_final_stats=1 "-artifact_prefix=$work/artifacts/" "-seed=${BLVD_FUZZ_SEED:-0}")
[ -f "$here/dict/$name.dict" ] && flags+=("-dict=$here/dict/$name.dict")

if [ "$secs" = 0 ]; then
  exec "$bin" -runs=0 "${flags[@]}" "$@" "$work/files" "${dirs[@]}"
fi

log=$work/last.log
rm -f "$work"/artifacts/*
set +e
"$bin" -max_total_time="$secs" "${flags[@]}" "$@" "$work/corpus" "$work/files" "${dirs[@]}" > "$log" 2>&1
rc=$?
set -e
execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -n 1)
cov=$(grep -oE 'cov: [0-9]+' "$log" | tail -n 1 | cut -d' ' -f2)
ft=$(grep -oE 'ft: [0-9]+' "$log" | tail -n 1 | cut -d' ' -f2)
corpus=$(find "$work/corpus" -type f | wc -l)

art=$(ls -t "$work"/artifacts/* 2> /dev/null | head -n 1 || true)
# A timeout is tried again alone: one that then runs within the limit was the
# machine stalling (a stopped or starved process), not the input. It is said
# and not kept, and the campaign counts as run.
if [ "$rc" != 0 ] && [ -n "$art" ] && [[ $(basename "$art") == timeout-* ]] &&
   timeout 120 "$bin" -timeout=25 -rss_limit_mb=2048 "$art" > "$work/retry.log" 2>&1; then
  echo "$name: $(basename "$art") ran within the limit when tried again alone: the machine stalled; not kept"
  rc=0
fi
if [ "$rc" != 0 ]; then
  tail -n 60 "$log"
  if [ -z "$art" ]; then
    echo "$name: libFuzzer exited $rc without an artifact (log: $log)"
    exit 1
  fi
  out="$here/regressions/$name"
  mkdir -p "$out"
  kept="$out/$(basename "$art")"
  # A crash minimises in seconds; a timeout would take 25 s a try: kept whole.
  case $(basename "$art") in
    crash-*) timeout 300 "$bin" -minimize_crash=1 -runs=20000 -timeout=25 "-exact_artifact_path=$kept.min" "$art" \
               > "$work/minimize.log" 2>&1 || true ;;
  esac
  if [ -s "$kept.min" ]; then mv -f "$kept.min" "$kept"; else rm -f "$kept.min"; cp -f "$art" "$kept"; fi
  echo "$name: found $(basename "$art"), kept as $kept"
  echo "reproduce: $bin $kept"
  exit 1
fi
echo "$name: $secs s, ${execs:-0} executions (${rate:-0}/s), cov ${cov:-0}, ft ${ft:-0}, corpus $corpus"
