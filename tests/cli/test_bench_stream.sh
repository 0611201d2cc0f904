#!/usr/bin/env bash
# `blvd bench stream` through packaging/scripts/bench_stream.sh on a short
# route: a real nginx at the three link profiles, a cold cache each; every
# report is whole, the drive had no load error, the cache stayed in its bytes
# and the cold start fetched the tables in two requests before any blob.
# Usage: test_bench_stream.sh BLVD PKG WORK
set -euo pipefail
blvd=$1 pkg=$2 work=$3
rm -rf "$work"
BLVD=$blvd bash "$(dirname "$0")/../../packaging/scripts/bench_stream.sh" "$pkg" "$work" 20 8 | tee "$work.table"
python3 - "$work" <<'PY'
import json, sys
for p in ("10m", "1m", "56k"):
    j = json.load(open(f"{sys.argv[1]}/{p}.json"))
    assert j["load_errors"] == 0, (p, j)
    assert j["frames"] > 0 and j["route_cells"] >= 2, (p, j)
    assert 0 < j["peak_cache_bytes"] <= j["cache_bytes"], (p, j)
    assert j["cold_start_requests"] >= 3 and j["time_to_first_frame_s"] > 0, (p, j)
    assert 0 <= j["degraded_share"] <= 1, (p, j)
print("bench stream: 3 profiles, reports whole")
PY
