#!/usr/bin/env bash
# ABI: libblvd exports exactly the functions declared in blvd.h, nothing else,
# and carries the SOVERSION in its soname.
set -euo pipefail
lib=$1 header=$2
exported=$(nm -D --defined-only "$lib" | awk '$2 == "T" {print $3}' | sort)
declared=$(grep -oE 'BLVD_API [^(]*\b(blvd_[a-z_0-9]+)\(' "$header" | grep -oE 'blvd_[a-z_0-9]+\($' | tr -d '(' | sort)
if [ "$exported" != "$declared" ]; then
  echo "exported and declared functions differ:"; diff <(echo "$exported") <(echo "$declared") || true; exit 1
fi
other=$(nm -D --defined-only "$lib" | awk '$2 != "T" && $2 != "A" {print $3}' | grep -v '^blvd_' || true)
[ -z "$other" ] || { echo "unexpected exported symbols: $other"; exit 1; }
# awk reads all of objdump's output: `grep -q` would exit at the match and,
# under pipefail, objdump's SIGPIPE would fail the pipeline at random.
soname=$(objdump -p "$lib" | awk '$1 == "SONAME" {print $2}')
[ "$soname" = "libblvd.so.0" ] || { echo "soname is '$soname', not libblvd.so.0"; exit 1; }
echo "exports: $(echo "$exported" | wc -l) blvd_* functions, soname libblvd.so.0"
