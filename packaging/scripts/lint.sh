#!/usr/bin/env bash
# lintian on built packages, as deb.sh and deb_cross.sh want it: any error
# fails, and so does any warning whose tag packaging/debian/README does not
# explain as a "- TAG: reason" line. Output in LOG.
#   lint.sh CHANGES LOG
set -euo pipefail
changes=${1:?usage: lint.sh CHANGES LOG} log=${2:?usage: lint.sh CHANGES LOG}
readme=$(dirname "$0")/../debian/README
if ! lintian --fail-on error --tag-display-limit 0 "$changes" > "$log" 2>&1; then
  echo "FAIL: lintian $changes:" >&2
  cat "$log" >&2
  exit 1
fi
for tag in $(sed -n 's/^W: [^:]*: \([a-z0-9-]*\).*/\1/p' "$log" | sort -u); do
  grep -q -- "^- $tag:" "$readme" || { echo "FAIL: lintian warning $tag is not explained in $readme" >&2;
    grep -- ": $tag" "$log" >&2; exit 1; }
done
