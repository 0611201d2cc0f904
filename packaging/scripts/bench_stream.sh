#!/usr/bin/env bash
# `blvd bench stream` on the three link profiles (docs/benchmarks.md): a real
# nginx on loopback serves the package at 56 kbit/s, 1 Mbit/s and 10 Mbit/s
# (limit_rate, times the bench's time scale: the drive runs in simulated
# time; the client paces to the same rate), and the bench drives a 200-cell route at 50 km/h from a cold cache
# on each. Prints one JSON object per profile and a Markdown table.
# Usage: bench_stream.sh [PKG] [WORK] [TIME_SCALE] [CELLS]
#   default: build/test-monaco.blvd, out/bench-stream, 10, 200
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
pkg=$(realpath "${1:-$root/build/test-monaco.blvd}")
work=$(mkdir -p "${2:-$root/out/bench-stream}" && realpath "${2:-$root/out/bench-stream}")
scale=${3:-10}
cells=${4:-200}
blvd=${BLVD:-$root/build/sdk/cli/blvd}
mkdir -p "$work/www" "$work/nginx"
ln -sf "$pkg" "$work/www/city.blvd"
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
rate() { python3 -c "print(int($1 * $scale / 8))"; }
cat > "$work/nginx/nginx.conf" <<CONF
daemon off;
master_process off;
user root;
pid $work/nginx/nginx.pid;
error_log $work/nginx/error.log;
events { worker_connections 64; }
http {
  access_log off;
  client_body_temp_path $work/nginx/body;
  proxy_temp_path $work/nginx/proxy;
  fastcgi_temp_path $work/nginx/fastcgi;
  uwsgi_temp_path $work/nginx/uwsgi;
  scgi_temp_path $work/nginx/scgi;
  server {
    listen 127.0.0.1:$port;
    location /56k/ { alias $work/www/; limit_rate $(rate 56000); }
    location /1m/ { alias $work/www/; limit_rate $(rate 1000000); }
    location /10m/ { alias $work/www/; limit_rate $(rate 10000000); }
  }
}
CONF
nginx=/usr/sbin/nginx
[ -x $nginx ] || nginx=nginx
$nginx -p "$work/nginx" -c "$work/nginx/nginx.conf" &
pid=$!
trap 'kill $pid 2>/dev/null || true' EXIT
for _ in $(seq 50); do curl -s -o /dev/null "http://127.0.0.1:$port/1m/" && break || sleep 0.1; done
for p in 10m 1m 56k; do
  "$blvd" bench stream "$pkg" --url "http://127.0.0.1:$port/$p/city.blvd" --profile "$p" --time-scale "$scale" --cells "$cells" \
    --cache "$work/cache-$p" --json "$work/$p.json" > "$work/$p.txt"
done
python3 - "$work" <<'PY'
import json, sys
w = sys.argv[1]
print("| link | time to first frame | degraded frames (after the first cell) | bytes / km | requests / km | peak cache | cached ahead p5 / p50 |")
print("|---|---|---|---|---|---|---|")
for p, name in (("10m", "10 Mbit/s"), ("1m", "1 Mbit/s"), ("56k", "56 kbit/s")):
    j = json.load(open(f"{w}/{p}.json"))
    print(f"| {name} | {j['time_to_first_frame_s']:.1f} s | {100 * j['degraded_share']:.1f} % "
          f"({100 * j['degraded_share_after_first_cell']:.1f} %) | {j['bytes_per_km'] / 1e6:.2f} MB | "
          f"{j['requests_per_km']:.0f} | {j['peak_cache_bytes'] / 1e6:.1f} MB | "
          f"{j['cached_ahead_s_p5']:.0f} / {j['cached_ahead_s_p50']:.0f} s |")
PY
