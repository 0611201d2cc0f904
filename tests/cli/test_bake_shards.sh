#!/usr/bin/env bash
# A bake in shards: shards named explicitly (I/N) and by a scheduler's
# environment (Slurm, Kubernetes) merge into the package a single bake
# writes, byte for byte, in any order; with no impostors and on terrain too. The merge
# refuses a missing or repeated shard, a shard of other options or other
# input, a package, and a corrupt shard, naming the file and the reason; the
# runtime refuses to open a shard.
# Usage: test_bake_shards.sh BLVD_EXE OSM OTHER_OSM WORKDIR
set -euo pipefail
blvd=$1 osm=$2 other=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
cd "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }
opts=(--quiet --impostor both --impostor-route auto:8 --seed 3 --jobs 1)

"$blvd" bake "$osm" -o single.blvd "${opts[@]}" > /dev/null
"$blvd" bake "$osm" -o s0.blvdshard "${opts[@]}" --shard 0/3 > /dev/null
JOB_COMPLETION_INDEX=1 "$blvd" bake "$osm" -o s1.blvdshard "${opts[@]}" --shard env --shards 3 > /dev/null
SLURM_ARRAY_TASK_ID=2 SLURM_ARRAY_TASK_COUNT=3 "$blvd" bake "$osm" -o s2.blvdshard "${opts[@]}" --shard env > s2.txt
grep -q "shard 2 of 3" s2.txt || fail "shard 2's summary: $(cat s2.txt)"
"$blvd" pack merge s2.blvdshard s0.blvdshard s1.blvdshard -o merged.blvd > merge.txt
cmp single.blvd merged.blvd || fail "merged package differs from the single bake"
grep -q "imbalance" merge.txt || fail "merge summary: $(cat merge.txt)"
"$blvd" pack verify merged.blvd > /dev/null

"$blvd" bake "$osm" -o none.blvd --quiet --impostor none > /dev/null
for i in 0 1; do "$blvd" bake "$osm" -o none$i.blvdshard --quiet --impostor none --shard $i/2 > /dev/null; done
"$blvd" pack merge none0.blvdshard none1.blvdshard -o none-merged.blvd > /dev/null
cmp none.blvd none-merged.blvd || fail "merge without impostors differs from the single bake"

# On terrain (--dem): the ground under the streets and the terrain's tiles are every shard's alike.
dem=$(dirname "$osm")/../dem/N43E007.hgt.zip
"$blvd" bake "$osm" -o dem.blvd "${opts[@]}" --dem "$dem" > /dev/null
for i in 0 1; do "$blvd" bake "$osm" -o dem$i.blvdshard "${opts[@]}" --dem "$dem" --shard $i/2 > /dev/null; done
"$blvd" pack merge dem1.blvdshard dem0.blvdshard -o dem-merged.blvd > /dev/null
cmp dem.blvd dem-merged.blvd || fail "merge on terrain differs from the single bake"
"$blvd" pack info dem-merged.blvd | grep -q "TERR" || fail "merged package on terrain lacks its TERR section"

refused() {  # refused EXPECTED_TEXT COMMAND...
  local want=$1 msg rc
  shift
  set +e
  msg=$("$@" 2>&1); rc=$?
  set -e
  [ "$rc" != 0 ] || fail "accepted: $*"
  echo "$msg" | grep -qF -- "$want" || fail "$* : message does not say '$want': $msg"
  [ ! -e bad.blvd ] || fail "$* wrote a package"
}
refused "shard 1 of 3 is missing" "$blvd" pack merge s0.blvdshard s2.blvdshard -o bad.blvd
refused "are both shard 0" "$blvd" pack merge s0.blvdshard s0.blvdshard s1.blvdshard s2.blvdshard -o bad.blvd
"$blvd" bake "$osm" -o seed4.blvdshard --quiet --impostor both --impostor-route auto:8 --seed 4 --jobs 1 --shard 1/3 > /dev/null
refused "seed4.blvdshard: baked with other options" "$blvd" pack merge s0.blvdshard seed4.blvdshard s2.blvdshard -o bad.blvd
"$blvd" bake "$other" -o other.blvdshard "${opts[@]}" --shard 1/3 > /dev/null
refused "other.blvdshard: baked from other input bytes" "$blvd" pack merge s0.blvdshard other.blvdshard s2.blvdshard -o bad.blvd
refused "single.blvd: not a bake shard" "$blvd" pack merge s0.blvdshard single.blvd s2.blvdshard -o bad.blvd
refused "shard of 2 shards" "$blvd" pack merge s0.blvdshard none1.blvdshard s2.blvdshard -o bad.blvd
cp s1.blvdshard corrupt.blvdshard
size=$(stat -c %s corrupt.blvdshard)
printf '\xff' | dd of=corrupt.blvdshard bs=1 seek=$((size / 2)) conv=notrunc status=none
refused "corrupt.blvdshard" "$blvd" pack merge s0.blvdshard corrupt.blvdshard s2.blvdshard -o bad.blvd
refused "a shard of a bake, not a package" "$blvd" pack info s0.blvdshard
refused "index 3 is out of range for 3 shards" "$blvd" bake "$osm" -o bad.blvd "${opts[@]}" --shard 3/3
refused "cannot be tiled" "$blvd" bake "$osm" -o bad.blvd --quiet --impostor none --tile 2x2 --shard 0/2
refused "none1.blvdshard: baked with other options" "$blvd" pack merge dem0.blvdshard none1.blvdshard -o bad.blvd
refused "cannot be combined with --tile" "$blvd" bake "$osm" -o bad.blvd --quiet --impostor none --tile 2x2 --dem "$dem"
refused "--report: not with --shard" "$blvd" bake "$osm" -o bad.blvd "${opts[@]}" --shard 0/2 --report rep
echo "bake shards: 3 shards (explicit, JOB_COMPLETION_INDEX, SLURM_ARRAY_TASK_ID) merge to $(stat -c %s merged.blvd) bytes identical to the single bake, on terrain too; 13 refusals named"
