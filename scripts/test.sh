#!/usr/bin/env bash
# The whole test suite: release build, AddressSanitizer+UBSan build, and a
# bounded libFuzzer run of the TIFF reader. Exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
J=$(nproc)

echo "== release build: tests"
ctest --test-dir build --output-on-failure -j"$J"

echo "== AddressSanitizer + UndefinedBehaviorSanitizer build: tests"
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCOL0RME_SANITIZE=ON >/dev/null
cmake --build build-asan -j"$J" >/dev/null
ASAN_OPTIONS=detect_leaks=1 ctest --test-dir build-asan --output-on-failure -j"$J" -LE slow

echo "== libFuzzer: TIFF reader"
cmake -S . -B build-fuzz -DCMAKE_C_COMPILER=clang -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DCOL0RME_FUZZ=ON -DC0_FUZZ_SECONDS="${C0_FUZZ_SECONDS:-60}" >/dev/null
cmake --build build-fuzz -j"$J" --target fuzz_tiff >/dev/null
ctest --test-dir build-fuzz --output-on-failure -R fuzz_tiff_run
