#!/usr/bin/env bash
# A cluster bake on a one-node Slurm cluster (local_slurm.sh) gives the package
# a single bake gives:
#   1. packaging/cluster/submit.sh --wait, 4 shards: the merged package is REFERENCE, byte for byte;
#   2. one array task cancelled before it starts, resubmitted alone as the README
#      says (sbatch --array=2 with OUTPUT.shards/submit.env), then the merge: REFERENCE again.
# REFERENCE is a single-machine bake of INPUT with the options below.
#   test_slurm_bake.sh BLVD INPUT REFERENCE WORK
# Exits 77 (skipped) where the cluster cannot run (not root, no Slurm).
set -euo pipefail
[[ $# -eq 4 ]] || { echo "usage: $0 BLVD INPUT REFERENCE WORK" >&2; exit 2; }
blvd=$(realpath "$1") osm=$(realpath "$2") ref=$(realpath "$3") work=$4
here=$(cd "$(dirname "$0")" && pwd)
cluster_dir=$(cd "$here/../../packaging/cluster" && pwd)
options=(--quiet --impostor both --impostor-route auto:40 --seed 7 --jobs 1)
shards=4 cancelled=2

mkdir -p "$work"
work=$(cd "$work" && pwd)
slurm=$work/cluster
# What an earlier run left: its cluster (if it was killed) and its files.
bash "$here/local_slurm.sh" stop "$slurm"
rm -rf "$slurm" "$work/run1" "$work/run2" "$work"/submit2.log "$work"/incomplete.* "$work"/merge2.id

dump_logs() {
  echo "==== Slurm logs"
  local f
  for f in "$slurm"/slurmctld.log "$slurm"/slurmd.log; do
    [[ -f $f ]] && { echo "---- $f (last 60 lines)"; tail -n 60 "$f"; }
  done
  for f in "$work"/run*/*.shards/*.out; do
    [[ -f $f ]] && { echo "---- $f"; cat "$f"; }
  done
  if [[ -n ${SLURM_CONF:-} ]]; then
    echo "---- squeue"
    squeue 2>&1 || true
  fi
}
finish() {
  local rc=$?
  if ((rc != 0 && rc != 77)); then dump_logs; fi
  bash "$here/local_slurm.sh" stop "$slurm" || true
  exit "$rc"
}
trap finish EXIT

fail() { echo "FAIL: $*" >&2; exit 1; }

t0=$SECONDS
rc=0
bash "$here/local_slurm.sh" start "$slurm" || rc=$?
((rc == 0)) || exit "$rc"
# shellcheck disable=SC1091
source "$slurm/env"
export BLVD=$blvd
unset BLVD_SBATCH_OPTIONS BLVD_SBATCH_ARRAY_OPTIONS

# 1. The whole bake through submit.sh.
t1=$SECONDS
out1=$work/run1/monaco.blvd
bash "$cluster_dir/submit.sh" --wait "$osm" "$out1" "$shards" -- "${options[@]}"
cmp "$out1" "$ref" || fail "the merged package of run 1 differs from $ref"
files=("$out1.shards"/shard-*.blvdshard)
((${#files[@]} == shards)) || fail "run 1 left ${#files[@]} shard files, not $shards"
echo "checked: submit.sh --wait, $shards shards: $out1 = REFERENCE ($(stat -c %s "$ref") bytes), $((SECONDS - t1)) s"

# 2. Task $cancelled cancelled while the array is held, so it never runs.
t2=$SECONDS
out2=$work/run2/monaco.blvd
BLVD_SBATCH_ARRAY_OPTIONS=--hold bash "$cluster_dir/submit.sh" "$osm" "$out2" "$shards" -- "${options[@]}" |
  tee "$work/submit2.log"
array=$(sed -n 's/^array job \([0-9]*\):.*/\1/p' "$work/submit2.log")
merge=$(sed -n 's/^merge job \([0-9]*\):.*/\1/p' "$work/submit2.log")
[[ -n $array && -n $merge ]] || fail "no job ids in submit.sh's output"
scancel "${array}_$cancelled"
# A pending array task that is cancelled leaves the array (no record of its own).
left=$(squeue -h -r -j "$array" -o %K | sort -n | xargs)
expected=$(seq 0 $((shards - 1)) | grep -vx "$cancelled" | xargs)
[[ $left == "$expected" ]] ||
  fail "array job $array holds tasks '$left' after scancel of task $cancelled, not '$expected'"
scontrol release "$array"

# Until the other tasks have ended, and Slurm has cancelled the merge: its
# afterok can never be met now (submit.sh passes --kill-on-invalid-dep).
merge_state=
for ((i = 0; i < 600; i++)); do
  state=$(scontrol show job "$merge" 2> /dev/null | sed -n 's/.*JobState=\([A-Z_]*\) Reason=\([A-Za-z]*\).*/\1 \2/p' || true)
  [[ -z $state ]] || merge_state=$state
  [[ -z $(squeue -h -j "$array" -o %i 2> /dev/null) && $merge_state == CANCELLED* ]] && break
  sleep 0.5
done
[[ -z $(squeue -h -j "$array" -o %i 2> /dev/null) ]] || fail "array job $array still queued after 300 s"
[[ $merge_state == "CANCELLED DependencyNeverSatisfied" ]] ||
  fail "the merge job $merge is '$merge_state', not 'CANCELLED DependencyNeverSatisfied'"
for ((k = 0; k < shards; k++)); do
  f=$out2.shards/shard-$k.blvdshard
  if ((k == cancelled)); then
    [[ ! -e $f ]] || fail "cancelled task $k wrote $f"
  else
    [[ -f $f ]] || fail "task $k did not write $f"
  fi
done
[[ ! -e $out2 && ! -e $out2.shards/blvd-merge-$merge.out ]] ||
  fail "the merge of run 2 ran although task $cancelled was cancelled"
# The merge refuses the incomplete set and names the missing shard.
if "$blvd" pack merge "$out2.shards"/shard-*.blvdshard -o "$work/incomplete.blvd" 2> "$work/incomplete.txt"; then
  fail "pack merge accepted $((shards - 1)) of $shards shards"
fi
grep -q "shard $cancelled of $shards is missing" "$work/incomplete.txt" ||
  fail "pack merge did not name shard $cancelled: $(cat "$work/incomplete.txt")"
echo "checked: task $cancelled of array job $array cancelled before it ran: no shard-$cancelled; merge job $merge cancelled by Slurm ($merge_state); pack merge says: $(tail -n 1 "$work/incomplete.txt")"

# The resubmission, as README.md tells: the same environment, that one index.
(
  # shellcheck source=/dev/null
  source "$out2.shards/submit.env"
  resub=$(sbatch --parsable --array="$cancelled" --output="$SHARD_DIR/blvd-bake-%A_%a.out" \
    "$cluster_dir/blvd-bake-shard.sbatch")
  resub=${resub%%;*}
  sbatch --parsable --wait --dependency=afterok:"$resub" --kill-on-invalid-dep=yes \
    --output="$SHARD_DIR/blvd-merge-%j.out" "$cluster_dir/blvd-merge.sbatch" > "$work/merge2.id"
  echo "resubmitted task $cancelled as job $resub, merge job $(cat "$work/merge2.id")"
)
cmp "$out2" "$ref" || fail "the merged package of run 2 differs from $ref"
echo "checked: task $cancelled resubmitted alone, merged: $out2 = REFERENCE, $((SECONDS - t2)) s"
echo "slurm bake: 2 cluster bakes of $shards shards byte-identical to the single bake ($((SECONDS - t0)) s with the cluster's start)"
