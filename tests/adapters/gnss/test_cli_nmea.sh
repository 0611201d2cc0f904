#!/usr/bin/env bash
# `blvd nmea decode`: JSON lines, the table, errors with line numbers, exit codes.
# Usage: test_cli_nmea.sh BLVD NMEA_DATA_DIR
set -euo pipefail
blvd=$1
data=$2
fail() { echo "FAIL: $*" >&2; exit 1; }

# --json: one TPV object per line, gpsd's field names and formats.
out=$("$blvd" nmea decode "$data/nmea-rtk.log" --json)
[ "$(wc -l <<<"$out")" -eq 122 ] || fail "nmea-rtk.log: expected 122 TPV lines"
first=${out%%$'\n'*}
expect='{"class":"TPV","mode":3,"time":"2020-03-18T13:28:19.600Z","lat":41.574965910,"lon":-93.750571901,"alt":278.1610,"speed":0.076,"track":124.8880}'
[ "$first" = "$expect" ] || fail "first TPV: got $first"
printf '%s\n' "$out" | python3 -c '
import json, sys
for line in sys.stdin:
    j = json.loads(line)
    assert j["class"] == "TPV" and j["mode"] in (0, 1, 2, 3), line
    assert j["time"].endswith("Z") and len(j["time"]) == 24, line
' || fail "JSON lines do not parse as TPV objects"

# The table, and a summary on stderr.
table=$("$blvd" nmea decode "$data/bt451.log" 2>/tmp/blvd_nmea_err.$$)
# (here-strings, not pipes: under pipefail a `grep -q` that exits at its match can
# fail the pipeline with the writer's SIGPIPE)
grep -q "time (UTC)" <<<"${table%%$'\n'*}" || fail "no table header"
grep -q "2009-12-09T15:25:05.000Z   3D     55.7970188" <<<"$table" || fail "table row"
grep -q "fixes from 144 sentences" /tmp/blvd_nmea_err.$$ || fail "no summary on stderr"

# Problems go to stderr with line numbers and byte offsets; decoding goes on.
"$blvd" nmea decode "$data/gp-320fw-2019-04-07-coldboot.log" --json >/tmp/blvd_nmea_out.$$ 2>/tmp/blvd_nmea_err.$$ \
  || fail "a damaged log must still exit 0"
grep -q "gp-320fw-2019-04-07-coldboot.log: line 27, byte 1353: GPRMC: bad checksum" /tmp/blvd_nmea_err.$$ \
  || fail "bad checksum not reported with line and byte"
grep -q '"time":"2019-04-07T00:03:45.030Z","lat":48.149988333' /tmp/blvd_nmea_out.$$ || fail "fix after bad data lost"
rm -f /tmp/blvd_nmea_err.$$ /tmp/blvd_nmea_out.$$

# A file that cannot be read: exit 1 and say why.
set +e
msg=$("$blvd" nmea decode /nonexistent/file.log 2>&1)
rc=$?
set -e
[ $rc -eq 1 ] || fail "unreadable file: exit $rc, want 1"
grep -q "cannot read /nonexistent/file.log" <<<"$msg" || fail "unreadable file message: $msg"
echo "cli nmea: ok"
