#!/usr/bin/env bash
# Who may include whom, as the module READMEs say: the samples use blvd.h,
# the adapters' headers and their own files; the adapters never reach into
# the CLI; sdk/vehicle reports core::Status, not blvd.h's; libblvd's modules
# never include the CLI or the tools' libraries. Prints every offending line.
set -euo pipefail
root=$1
cd "$root"
bad=0
# `quoted FILES...`: file:line:header for every #include "header".
quoted() { grep -HnoE '^#include "[^"]+"' "$@" | sed -E 's/#include "([^"]+)"/\1/'; }
offend() { echo "$1: $2"; bad=1; }

while IFS=: read -r file line header; do
  dir=$(dirname "$file")
  case "$header" in
    blvd/blvd.h | can/* | gnss/* | replay/* | sim/* | common/*) ;;
    *) [ -e "$dir/$header" ] || offend "$file:$line" "a sample includes $header (only blvd.h, adapters, its own files)" ;;
  esac
done < <(quoted $(find samples -name '*.cpp' -o -name '*.h' -o -name '*.c'))

while IFS=: read -r file line header; do
  case "$header" in cli/*) offend "$file:$line" "an adapter includes the CLI's $header" ;; esac
done < <(quoted $(find adapters -name '*.cpp' -o -name '*.h'))

while IFS=: read -r file line header; do
  case "$header" in blvd/blvd.h) offend "$file:$line" "sdk/vehicle includes blvd.h (it reports core::Status)" ;; esac
done < <(quoted sdk/vehicle/*.cpp sdk/vehicle/*.h)

for m in core geo graph package stream track runtime render capi vehicle; do
  while IFS=: read -r file line header; do
    case "$header" in cli/* | bake/* | imaging/*) offend "$file:$line" "libblvd's $m includes $header" ;; esac
  done < <(quoted $(find "sdk/$m" -name '*.cpp' -o -name '*.h'))
done
[ "$bad" = 0 ] && echo "includes follow the module boundaries"
exit "$bad"
