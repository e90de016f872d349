#!/usr/bin/env bash
# All tests, from a fresh clone: set up, C unit tests (ctest), the pytest suite through fmpy, then
# the C tests and the pytest suite again with the FMU built with AddressSanitizer and UBSan.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export MPLBACKEND=Agg

echo "== ctest (Release)"
ctest --test-dir build --output-on-failure -j2

echo "== pytest (Release FMU)"
.venv/bin/python -m pytest -q

echo "== ASan/UBSan build"
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DDFO_SANITIZE=ON \
      -DPython3_EXECUTABLE="$PWD/.venv/bin/python" >/dev/null
cmake --build build-asan -j"$(nproc)" >/dev/null
echo "== ctest (ASan/UBSan)"
ctest --test-dir build-asan --output-on-failure -j2

echo "== pytest (ASan/UBSan FMU)"
ASAN_LIB=$(gcc -print-file-name=libasan.so)
UBSAN_LIB=$(gcc -print-file-name=libubsan.so)
DFO_FMU="$PWD/build-asan/DryFrictionOscillator.fmu" \
LD_PRELOAD="$ASAN_LIB $UBSAN_LIB" \
ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 \
UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
  .venv/bin/python -m pytest -q -m "not no_sanitizer"

echo "== fuzzing the FMI entry points (libFuzzer + ASan/UBSan, 60 s; installs clang if missing)"
PYTHON="$PWD/.venv/bin/python" FUZZ_BUILD="$PWD/build-fuzz" bash tests/fuzz/run_fuzz.sh 60
