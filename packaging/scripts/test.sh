#!/usr/bin/env bash
# The whole test suite, as CI runs it: install dependencies, build with
# warnings as errors, run the parser/corruption and runtime-failure tests
# under ASan+UBSan, the fuzz targets under libFuzzer (clang), the threaded
# tests under ThreadSanitizer, the arm64
# cross-build's tests under qemu, then every other test. The last line printed is CTest's summary.
set -euo pipefail
cd "$(dirname "$0")/../.."
bash packaging/scripts/deps.sh
jobs=$(nproc)

# 1. Everything, warnings as errors.
bash packaging/scripts/configure.sh test build
cmake --build build -j"$jobs"

# 2. Sanitizers on the code that reads untrusted bytes (packages, GLB, graph,
#    NMEA, CAN) and on the runtime's create-time failure paths (budget, host
#    allocator failing at each call; every allocation of a package open, a
#    tracker, a CAN profile and a cell's load failing in turn: LeakSanitizer
#    checks that nothing leaks), and the short soak (ten virtual minutes of
#    driving, LeakSanitizer at its end).
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DBLVD_SANITIZE=ON -DBLVD_WERROR=ON > /dev/null
# Every fuzz target is built (its seed replay is labelled fuzz), found in the
# build file so that a new target cannot be left out.
asan_fuzzers=$(sed -n 's/^build tests\/fuzz\/\(fuzz_[a-z_]*\): .*/\1/p' build-asan/build.ninja | sort -u)
# shellcheck disable=SC2086
cmake --build build-asan -j"$jobs" --target test_package test_graph_serialize test_gnss test_can \
  test_runtime_fault test_create_nomem test_soak $asan_fuzzers
# The runtime test needs the Monaco package: the fixture's own bake, run with
# step 1's build (a sanitized CGAL bake would take many minutes).
(cd build && ctest --output-on-failure -R '^bake\.monaco_geofabrik$')
cp build/test-monaco.blvd build-asan/test-monaco.blvd
(cd build-asan && ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j"$jobs" -L "asan|fuzz" -FS monaco_package)

# 2b. Coverage-guided fuzzing (clang, libFuzzer, ASan+UBSan; tools/fuzz.sh for
#     long campaigns): every target replays its seeds, its corpus and the
#     crashes once found (tests/fuzz/regressions), then fuzzes for 10 s.
CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBLVD_FUZZ=ON \
  -DBLVD_SANITIZE=ON -DBLVD_BUILD_SAMPLES=OFF -DBLVD_FUZZ_SECONDS=10 > /dev/null
fuzzers=$(sed -n 's/^build tests\/fuzz\/\(fuzz_[a-z_]*\): .*/\1/p' build-fuzz/build.ninja | sort -u)
# shellcheck disable=SC2086
cmake --build build-fuzz -j"$jobs" --target $fuzzers
(cd build-fuzz && BLVD_FUZZ_SEED=1 ctest --output-on-failure -j"$jobs" -L '^fuzz$|^fuzz_campaign$')

# 3. ThreadSanitizer on the tests that share data across threads: the cell
#    loader's two decoding threads and its frame clock and prefetch share,
#    the tracker's feeds from any thread, the C API's CAN feeds, a package over the air
#    shared by the loaders, the link prefetch and the render thread.
cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBLVD_TSAN=ON -DBLVD_WERROR=ON \
  -DBLVD_BUILD_SAMPLES=OFF > /dev/null
cmake --build build-tsan -j"$jobs" --target test_residency test_cell_loader test_track test_capi_can test_remote_threads
cp build/test-monaco.blvd build-tsan/test-monaco.blvd
(cd build-tsan && TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" \
  ctest --output-on-failure -j"$jobs" -L tsan -FS monaco_package)

# 4. arm64: libblvd and the tests of what a vehicle runs, cross-built with
#    Debian's multiarch toolchain and run under qemu-aarch64 (label arm64),
#    on the package step 1's build baked.
bash packaging/scripts/arm64.sh build build-arm64

# 5. Every test but the Debian packages' (label packaging: a second full build
#    and a clean root; `ctest -L packaging` in build runs them) and the two-hour soak (label soak).
cd build
set +e
ctest --output-on-failure -j"$jobs" --timeout 900 -LE '^(packaging|soak)$' 2>&1 | tee ctest.log
rc=${PIPESTATUS[0]}
# CTest prints skipped tests after its summary; repeat the summary so it is the last line.
grep -E "tests passed|tests failed" ctest.log | tail -n 1
exit "$rc"
