#!/usr/bin/env bash
# The README's two commands share one build folder. Configure a scratch folder
# as the demo does, then as the test command does, then as the demo again, and
# check each time that the folder holds what that command runs next: the
# test command's CTest must find the Monaco bake and the CLI tests after a demo
# configure, and the demo must get a Release build without tests after a test
# configure. Usage: test_commands_order.sh SCRATCH_DIR
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
dir=${1:?usage: test_commands_order.sh SCRATCH_DIR}
rm -rf "$dir"
scripts="$here/../../packaging/scripts"

# Both commands configure build/ through configure.sh and nowhere else.
grep -q '^bash packaging/scripts/configure.sh demo build$' "$scripts/demo.sh" || { echo "FAIL: demo.sh does not configure build/ with configure.sh" >&2; exit 1; }
grep -q '^bash packaging/scripts/configure.sh test build$' "$scripts/test.sh" || { echo "FAIL: test.sh does not configure build/ with configure.sh" >&2; exit 1; }
if grep -nE '^cmake -S .* -B build( |$)' "$scripts/demo.sh" "$scripts/test.sh"; then
  echo "FAIL: a script configures build/ with its own cmake line" >&2; exit 1
fi

cache() { grep -E "^$1:" "$dir/CMakeCache.txt" | cut -d= -f2; }
fail() { echo "FAIL: $*" >&2; exit 1; }
listing() { (cd "$dir" && ctest -N 2>/dev/null) || true; }
tests_listed() { listing | grep -cE "^ *Test +#" || true; }

bash "$scripts/configure.sh" demo "$dir"
[ "$(cache BLVD_BUILD_TESTS)" = OFF ] || fail "demo configure left BLVD_BUILD_TESTS=$(cache BLVD_BUILD_TESTS)"
[ "$(cache CMAKE_BUILD_TYPE)" = Release ] || fail "demo configure: build type $(cache CMAKE_BUILD_TYPE)"
n=$(tests_listed); [ "$n" -eq 0 ] || fail "demo configure lists $n tests"

bash "$scripts/configure.sh" test "$dir"
[ "$(cache BLVD_BUILD_TESTS)" = ON ] || fail "test configure after demo left BLVD_BUILD_TESTS=$(cache BLVD_BUILD_TESTS)"
[ "$(cache BLVD_WERROR)" = ON ] || fail "test configure after demo: BLVD_WERROR=$(cache BLVD_WERROR)"
[[ "$(listing)" == *"bake.monaco_geofabrik"* ]] || fail "test configure after demo: CTest has no bake.monaco_geofabrik"
n=$(tests_listed); [ "$n" -ge 10 ] || fail "test configure after demo lists only $n tests"
echo "after demo then test: $n tests listed before the build (GoogleTest cases are found at build time)"

bash "$scripts/configure.sh" demo "$dir"
[ "$(cache BLVD_BUILD_TESTS)" = OFF ] || fail "demo configure after test left BLVD_BUILD_TESTS=$(cache BLVD_BUILD_TESTS)"
[ "$(cache BLVD_WERROR)" = OFF ] || fail "demo configure after test kept BLVD_WERROR=$(cache BLVD_WERROR)"
[ "$(cache CMAKE_BUILD_TYPE)" = Release ] || fail "demo configure after test: build type $(cache CMAKE_BUILD_TYPE)"
rm -rf "$dir"
echo "ok: demo -> test -> demo configures each leave the folder as the next command needs it"
