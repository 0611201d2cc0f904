#!/bin/sh
# A GoogleTest binary inside the guest, with vcan0 up (guest_init.sh runs it):
#   GTEST         the binary (/bin/...)
#   GTEST_FILTER  --gtest_filter pattern
# Results: /out/gtest.json (--gtest_output) and /out/gtest.log.
"$GTEST" --gtest_filter="$GTEST_FILTER" --gtest_output=json:/out/gtest.json > /out/gtest.log 2>&1
rc=$?
echo "scenario: $GTEST exited with $rc"
exit $rc
