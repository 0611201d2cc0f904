#!/usr/bin/env bash
# Configures a build folder the way one of the README's two commands needs it:
#   configure.sh demo BUILD_DIR   Release, the CLI only (no tests)
#   configure.sh test BUILD_DIR   RelWithDebInfo, warnings as errors, tests on
# Every option either command depends on is named here, so running one command
# after the other in the same checkout reconfigures the folder instead of
# inheriting the other's cache (a demo build followed by the test command would
# otherwise find no tests).
set -euo pipefail
kind=${1:?usage: configure.sh demo|test BUILD_DIR}
dir=${2:?usage: configure.sh demo|test BUILD_DIR}
src="$(cd "$(dirname "$0")/../.." && pwd)"
case "$kind" in
  demo) opts=(-DCMAKE_BUILD_TYPE=Release -DBLVD_BUILD_TESTS=OFF -DBLVD_WERROR=OFF -DBLVD_SANITIZE=OFF) ;;
  test) opts=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DBLVD_BUILD_TESTS=ON -DBLVD_WERROR=ON -DBLVD_SANITIZE=OFF) ;;
  *) echo "configure.sh: unknown kind '$kind' (demo or test)" >&2; exit 2 ;;
esac
cmake -S "$src" -B "$dir" -G Ninja "${opts[@]}" > /dev/null
