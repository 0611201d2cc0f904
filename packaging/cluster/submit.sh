#!/usr/bin/env bash
# Submits a cluster bake to Slurm: an array job of SHARDS shard bakes
# (blvd-bake-shard.sbatch) and the merge (blvd-merge.sbatch) that runs once
# every shard has succeeded. Shard files and job logs go to OUTPUT.shards/.
#
#   submit.sh [--wait] INPUT OUTPUT SHARDS [-- bake options...]
#
#   --wait   return when the merge has ended: 0 once the package is written,
#            1 otherwise (a shard that fails makes Slurm cancel the merge)
# Environment:
#   BLVD                        the blvd CLI the jobs run (default: blvd on PATH)
#   BLVD_SBATCH_OPTIONS         sbatch options for both jobs, e.g. "--partition=bake --account=maps"
#   BLVD_SBATCH_ARRAY_OPTIONS   sbatch options for the shard bakes only, e.g. "--cpus-per-task=4 --mem=8G"
# Prints the two job ids, and writes OUTPUT.shards/submit.env: the environment
# the jobs ran with, for resubmitting one shard (README.md).
set -euo pipefail

usage() {
  echo "usage: $0 [--wait] INPUT OUTPUT SHARDS [-- bake options...]" >&2
  exit 2
}

wait_merge=0
args=()
while (($#)); do
  case $1 in
    --wait) wait_merge=1 ;;
    -h | --help) usage ;;
    --) shift; break ;;
    -*) echo "submit.sh: unknown option $1" >&2; usage ;;
    *) args+=("$1") ;;
  esac
  shift
done
((${#args[@]} == 3)) || usage
bake_options=("$@")
input=${args[0]} output=${args[1]} shards=${args[2]}

if ! [[ $shards =~ ^[1-9][0-9]*$ ]]; then
  echo "submit.sh: SHARDS must be a positive number, not '$shards'" >&2
  exit 2
fi
if [[ ! -f $input ]]; then
  echo "submit.sh: $input: no such file" >&2
  exit 2
fi
for o in "${bake_options[@]}"; do
  case $o in
    -o | --output | --output=* | --shard | --shard=* | --shards | --shards=*)
      echo "submit.sh: $o is set by the jobs; pass the other bake options only" >&2
      exit 2
      ;;
    --report | --report=*)
      echo "submit.sh: a shard cannot write a bake report ($o)" >&2
      exit 2
      ;;
  esac
done

here=$(cd "$(dirname "$0")" && pwd)
# The jobs run in this directory on another node, maybe much later: absolute paths.
input=$(realpath "$input")
output=$(realpath -m "$output")
shard_dir=$output.shards
blvd=${BLVD:-blvd}
[[ $blvd != */* ]] || blvd=$(realpath "$blvd")

mkdir -p "$shard_dir" "$(dirname "$output")"
# Shards of an earlier bake into the same output would mix with these (the merge
# would refuse them): this submission replaces them.
shopt -s nullglob
old=("$shard_dir"/shard-*.blvdshard "$shard_dir"/shard-*.blvdshard.tmp)
if ((${#old[@]})); then
  echo "removing ${#old[@]} shard files of an earlier bake from $shard_dir"
  rm -f "${old[@]}"
fi

export INPUT=$input OUTPUT=$output SHARD_DIR=$shard_dir SHARDS=$shards BLVD=$blvd
BAKE_OPTIONS=${bake_options[*]+$(printf '%q ' "${bake_options[@]}")}
export BAKE_OPTIONS
{
  echo "# The environment of the bake jobs submitted by submit.sh on $(date -u +%FT%TZ)."
  for v in INPUT OUTPUT SHARD_DIR SHARDS BLVD BAKE_OPTIONS; do
    printf 'export %s=%q\n' "$v" "${!v}"
  done
} > "$shard_dir/submit.env"

# shellcheck disable=SC2086  # the option variables are lists of words
array_job=$(sbatch --parsable --export=ALL --array=0-$((shards - 1)) \
  --output="$shard_dir/blvd-bake-%A_%a.out" ${BLVD_SBATCH_OPTIONS:-} ${BLVD_SBATCH_ARRAY_OPTIONS:-} \
  "$here/blvd-bake-shard.sbatch")
array_job=${array_job%%;*}  # "id;cluster" on a multi-cluster setup
echo "array job $array_job: $shards shard bakes -> $shard_dir/"

# The merge runs when every array task has succeeded; if one fails (or is
# cancelled) the dependency can never be met, and Slurm cancels the merge
# instead of leaving it pending for ever.
merge=(sbatch --parsable --export=ALL --dependency=afterok:"$array_job" --kill-on-invalid-dep=yes
  --output="$shard_dir/blvd-merge-%j.out")
# shellcheck disable=SC2206
merge+=(${BLVD_SBATCH_OPTIONS:-})
if ((wait_merge)); then
  # sbatch --wait prints the id at submission, then returns with the job's exit
  # status: print the id as it comes (lastpipe: the loop sets merge_job here).
  shopt -s lastpipe
  merge_job='' status=0
  "${merge[@]}" --wait "$here/blvd-merge.sbatch" | while read -r id; do
    merge_job=${id%%;*}
    echo "merge job $merge_job: -> $output (after array job $array_job)"
  done || status=$?
  # A merge cancelled because a shard failed never ran, and sbatch --wait then
  # returns 0: ask Slurm how it ended, and whether the package was written.
  state=
  [[ -z $merge_job ]] ||
    state=$(scontrol show job "$merge_job" 2> /dev/null | sed -n 's/.*JobState=\([A-Z_]*\) Reason=\([^ ]*\).*/\1 (\2)/p' || true)
  if ((status)) || [[ -n $state && $state != COMPLETED* ]] || [[ ! $output -nt $shard_dir/submit.env ]]; then
    echo "submit.sh: the merge did not write $output (${state:-exit status $status}); logs in $shard_dir/" >&2
    exit 1
  fi
  echo "wrote $output"
else
  merge_job=$("${merge[@]}" "$here/blvd-merge.sbatch")
  echo "merge job ${merge_job%%;*}: -> $output (after array job $array_job)"
fi
