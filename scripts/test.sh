#!/usr/bin/env bash
# All tests, from a fresh clone: set up, C unit tests (ctest), the pytest suite through the FMU, the
# examples (examples/*.py at full size),
# the lowest declared dependency versions (scripts/check_min_versions.sh), then the C tests and
# the pytest suite again with the FMU built with AddressSanitizer and UBSan, and the fuzzer.
# Prints the duration of every stage at the end (also when a stage fails).
set -euo pipefail
cd "$(dirname "$0")/.."
export MPLBACKEND=Agg

DURATIONS=()
stage() {  # stage NAME COMMAND...: run, time, remember
  local name=$1 t0=$SECONDS
  shift
  echo "== $name"
  "$@"
  DURATIONS+=("$(printf '%-22s %5d s' "$name" $((SECONDS - t0)))")
}
report() {
  local rc=$?
  echo "== durations"
  for d in "${DURATIONS[@]}"; do echo "  $d"; done
  [ "$rc" -eq 0 ] || echo "  (stopped by a failure, exit status $rc)"
}
trap report EXIT

asan_build() {
  cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DDFO_SANITIZE=ON \
        -DPython3_EXECUTABLE="$PWD/.venv/bin/python" >/dev/null
  cmake --build build-asan -j"$(nproc)" >/dev/null
}
asan_pytest() {
  local asan ubsan
  asan=$(gcc -print-file-name=libasan.so)
  ubsan=$(gcc -print-file-name=libubsan.so)
  DFO_FMU="$PWD/build-asan/DryFrictionOscillator.fmu" \
  DFO_FMU3="$PWD/build-asan/fmi3/DryFrictionOscillator.fmu" \
  LD_PRELOAD="$asan $ubsan" \
  ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 \
  UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    .venv/bin/python -m pytest -q -m "not no_sanitizer"
}
fuzz() {  # libFuzzer + ASan/UBSan, 60 s; installs clang if missing
  PYTHON="$PWD/.venv/bin/python" FUZZ_BUILD="$PWD/build-fuzz" bash tests/fuzz/run_fuzz.sh 60
}

stage "setup" bash scripts/setup.sh
stage "ctest" ctest --test-dir build --output-on-failure -j2
stage "pytest" .venv/bin/python -m pytest -q
examples() {  # every example at its own size, in a scratch folder
  local d f
  d=$(mktemp -d)
  for f in examples/*.py; do
    echo "-- $f"
    (cd "$d" && "$OLDPWD/.venv/bin/python" "$OLDPWD/$f") || return 1
  done
  rm -rf "$d"
}
stage "examples" examples
stage "min-versions" bash scripts/check_min_versions.sh
stage "ASan/UBSan build" asan_build
stage "ASan ctest" ctest --test-dir build-asan --output-on-failure -j2
stage "ASan pytest" asan_pytest
stage "fuzz" fuzz
