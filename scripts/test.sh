#!/usr/bin/env bash
# The whole test suite: release build, AddressSanitizer+UBSan build, and
# bounded libFuzzer runs (TIFF reader, command-line arguments). Every stage
# runs even when an earlier one fails; the failures are listed at the end
# and the exit status is non-zero if there was any.
set -uo pipefail
cd "$(dirname "$0")/.."
J=$(nproc)
export OMP_WAIT_POLICY=PASSIVE
failed=()
stage() {   # stage NAME COMMAND...: run, remember a failure, go on; say how long it took
  local name=$1 t0=$SECONDS; shift
  echo "== $name"
  if ! "$@"; then
    failed+=("$name")
    echo "== $name: FAILED"
  fi
  echo "== $name: $((SECONDS - t0)) s"
}

stage "setup and release build" bash scripts/setup.sh
stage "release build: tests" ctest --test-dir build --output-on-failure -j"$J"

# (no ImageJ plugin there: its test runs only in the release build, and its javac took
# 12 of the build's 61 s)
asan() {
  cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCOL0RME_SANITIZE=ON -DCOL0RME_IMAGEJ=OFF >/dev/null &&
  cmake --build build-asan -j"$J" >/dev/null &&
  ASAN_OPTIONS=detect_leaks=1 ctest --test-dir build-asan --output-on-failure -j"$J" -LE slow
}
stage "AddressSanitizer + UndefinedBehaviorSanitizer build: tests" asan

fuzz() {
  cmake -S . -B build-fuzz -DCMAKE_C_COMPILER=clang -DCMAKE_BUILD_TYPE=RelWithDebInfo \
        -DCOL0RME_FUZZ=ON -DC0_FUZZ_SECONDS="${C0_FUZZ_SECONDS:-20}" >/dev/null &&
  cmake --build build-fuzz -j"$J" --target fuzz_tiff fuzz_cli >/dev/null &&
  ctest --test-dir build-fuzz --output-on-failure -j"$J" -R "fuzz_(tiff|cli)_run"
}
stage "libFuzzer: TIFF reader and command-line arguments" fuzz

if ((${#failed[@]})); then
  echo
  echo "FAILED stages (${#failed[@]}):"
  printf '  - %s\n' "${failed[@]}"
  exit 1
fi
echo
echo "all stages passed"
