#!/usr/bin/env bash
# ABI: libblvd exports exactly the functions declared in blvd.h, nothing else,
# carries the SOVERSION in its soname, and the Debian symbols file
# (packaging/debian/libblvd0.symbols, which dpkg-gensymbols checks when the
# package is built) lists exactly these functions: a new or removed function
# is a change to that file too, with the version that brings it.
set -euo pipefail
lib=$1 header=$2 symbols=$3
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
listed=$(sed -n 's/^ \(blvd_[a-z_0-9]*\)@Base .*/\1/p' "$symbols" | sort)
if [ "$exported" != "$listed" ]; then
  echo "exported functions and $symbols differ:"; diff <(echo "$exported") <(echo "$listed") || true; exit 1
fi
head -n 1 "$symbols" | grep -qx "libblvd.so.0 libblvd0 #MINVER#" || { echo "$symbols: first line is not the soname's"; exit 1; }
echo "exports: $(echo "$exported" | wc -l) blvd_* functions, soname libblvd.so.0, all in $symbols"
