#!/usr/bin/env bash
# All tests, from a fresh clone: set up, C unit tests (ctest), the pytest suite through the FMU, the
# documentation site (scripts/docs.sh), the examples (examples/*.py at full size), the cross-platform
# check (Windows x86-64 under wine, Linux aarch64 under qemu: scripts/cross_check.sh), then the C
# tests and the pytest suite again with the FMU built with AddressSanitizer and UBSan (every test that
# runs C: not the no_sanitizer and python_only markers), and the fuzzer, with the lowest declared
# dependency versions (scripts/check_min_versions.sh) on the core the shorter fuzzer leaves.
# Prints the duration of every stage at the end (also when a stage fails).
#
# bash scripts/test.sh --quick: the quick loop (about 100 s of CPU time once set up). Setup only
# when needed (no .venv, no build/, or pyproject.toml newer than the installed package), else an
# incremental build; then ctest and the fast pytest subset (-m "not slow": without the wheel, the
# rebuilds, the external hosts, the examples, the long studies). tests/README.md lists what it leaves
# out.
set -euo pipefail
cd "$(dirname "$0")/.."
export MPLBACKEND=Agg

QUICK=0
case "${1-}" in
  "") ;;
  --quick) QUICK=1 ;;
  *) echo "usage: bash scripts/test.sh [--quick]" >&2; exit 2 ;;
esac

# pytest runs on the cores that are idle when it starts (pytest-xdist, one worker per idle core, one
# test module per worker at a time: --dist loadfile builds a module's fixtures once; the modules
# handed out in collection order, --no-loadscope-reorder, where conftest.py puts the longest first);
# on busy cores one process, as more workers would only add their start-up (the scheduler shares
# the CPU between sessions, not processes).
idle_cores() {  # the idle share of the CPU over 1 s, in cores (rounded)
  local a b
  read -r -a a < <(head -1 /proc/stat); sleep 1; read -r -a b < <(head -1 /proc/stat)
  local idle=$(( b[4] + b[5] - a[4] - a[5] )) total=0 i
  for i in 1 2 3 4 5 6 7 8; do total=$(( total + b[i] - a[i] )); done
  echo $(( total > 0 ? (2 * idle * $(nproc) + total) / (2 * total) : 1 ))
}
pytest_() {  # pytest_ ARGS...: the pytest suite on the idle cores
  local n
  n=$(idle_cores)
  if [ "$n" -gt 1 ]; then
    echo "pytest: $n workers ($n of $(nproc) cores idle)"
    .venv/bin/python -m pytest -q -n "$n" --dist loadfile --no-loadscope-reorder "$@"
  else
    echo "pytest: one process (no two of the $(nproc) cores idle)"
    .venv/bin/python -m pytest -q "$@"
  fi
}

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
  DFO_CHAIN_FMU="$PWD/build-asan/DryFrictionChain.fmu" \
  DFO_CHAIN_FMU3="$PWD/build-asan/fmi3/DryFrictionChain.fmu" \
  DFO_CHAIN_DRIVER="$PWD/build-asan/tests/c/chain_driver" \
  DFO_CHAIN_DERIV="$PWD/build-asan/tests/c/test_chain_deriv" \
  DFO_CHAIN_DERIV_N1="$PWD/build-asan/tests/c/chain_deriv_n1" \
  DFO_POLY_DRIVER="$PWD/build-asan/tests/c/test_exact_poly" \
  DFO_TWO_MASS_DRIVER="$PWD/build-asan/tests/c/two_mass_driver" \
  DFO_TWO_MASS_FMU="$PWD/build-asan/TwoMass.fmu" \
  DFO_TWO_MASS_FMU3="$PWD/build-asan/fmi3/TwoMass.fmu" \
  DFO_SYSTEM_FMU="$PWD/build-asan/DryFrictionSystem.fmu" \
  DFO_SYSTEM_FMU3="$PWD/build-asan/fmi3/DryFrictionSystem.fmu" \
  LD_PRELOAD="$asan $ubsan" \
  ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 \
  UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    pytest_ -m "not no_sanitizer and not python_only"
}
fuzz() {  # libFuzzer + ASan/UBSan: the oscillator's FMI 2.0 entry points 60 s, the chain's FMI 3.0 30 s; installs clang if missing
  # both targets built first, then fuzzed at once (a fuzzer keeps one core busy: the two on the two
  # cores, each for its whole time); the lowest dependency versions (scripts/check_min_versions.sh:
  # an install, then one pytest process) on the core the chain's fuzzer leaves after its 30 s, beside
  # the oscillator's; the messages printed in that order, each after the other
  local env=(env PYTHON="$PWD/.venv/bin/python" FUZZ_BUILD="$PWD/build-fuzz") log1 log2 log3 rc1=0 rc2=0 rc3=0 t0 took
  "${env[@]}" FUZZ_STEP=build bash tests/fuzz/run_fuzz.sh
  "${env[@]}" FUZZ_STEP=build FUZZ_TARGET=fuzz_chain3 bash tests/fuzz/run_fuzz.sh
  log1=$(mktemp); log2=$(mktemp); log3=$(mktemp)
  "${env[@]}" FUZZ_STEP=run FUZZ_TARGET=fuzz_chain3 bash tests/fuzz/run_fuzz.sh 30 >"$log2" 2>&1 &
  local chain=$!
  "${env[@]}" FUZZ_STEP=run bash tests/fuzz/run_fuzz.sh 60 >"$log1" 2>&1 &
  local osc=$!
  wait "$chain" || rc2=$?
  t0=$SECONDS
  bash scripts/check_min_versions.sh >"$log3" 2>&1 || rc3=$?
  took=$((SECONDS - t0))
  wait "$osc" || rc1=$?
  cat "$log1" "$log2"
  echo "== min-versions (beside the fuzzer: $took s)"
  cat "$log3"
  rm -f "$log1" "$log2" "$log3"
  [ "$rc1" = 0 ] && [ "$rc2" = 0 ] && [ "$rc3" = 0 ]
}

# The cross toolchains and emulators (Debian packages), installed when missing: the win32 thread
# model of mingw-w64 (no libwinpthread), the aarch64 cross gcc with its C library, qemu-user,
# 64-bit wine only (no i386 multiarch).
CROSS_PACKAGES=(gcc-mingw-w64-x86-64-win32 gcc-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user wine64)
cross_install() {
  command -v x86_64-w64-mingw32-gcc-win32 >/dev/null && command -v aarch64-linux-gnu-gcc >/dev/null &&
    [ -e /usr/aarch64-linux-gnu/lib/libc.so.6 ] && command -v qemu-aarch64 >/dev/null &&
    { command -v wine64 >/dev/null || command -v wine >/dev/null || [ -x /usr/lib/wine/wine64 ]; } && return 0
  local sudo="" log=${TMPDIR:-/tmp}/dfo-apt-$$.log
  [ "$(id -u)" = 0 ] || sudo="sudo -n"
  local apt=(env DEBIAN_FRONTEND=noninteractive $sudo apt-get -o DPkg::Lock::Timeout=600)
  if ! { "${apt[@]}" install -y -q --no-install-recommends "${CROSS_PACKAGES[@]}" ||
         { "${apt[@]}" update -q && "${apt[@]}" install -y -q --no-install-recommends "${CROSS_PACKAGES[@]}"; }; } >"$log" 2>&1; then
    echo "cross-platform: apt-get install ${CROSS_PACKAGES[*]} failed: $(tail -1 "$log") (full log: $log)"
    return 1
  fi
}
cross_platform() {
  cross_install
  bash scripts/cross_check.sh
}
# fmusim (../shared/tools or $FMUSIM, run by tests/test_hosts.py) needs libxml2 and zlib at runtime:
# installed when it is there and they are missing (the test says so plainly if they stay missing).
host_libs() {
  local sim=${FMUSIM:-../shared/tools/fmusim/fmusim} sudo=""
  [ -x "$sim" ] && ldd "$sim" 2>/dev/null | grep -q "not found" || return 0
  [ "$(id -u)" = 0 ] || sudo="sudo -n"
  local apt=(env DEBIAN_FRONTEND=noninteractive $sudo apt-get -o DPkg::Lock::Timeout=600)
  { "${apt[@]}" install -y -q --no-install-recommends libxml2 zlib1g ||
    { "${apt[@]}" update -q && "${apt[@]}" install -y -q --no-install-recommends libxml2 zlib1g; }; } >/dev/null 2>&1 ||
    echo "host-libs: apt-get install libxml2 zlib1g failed: tests/test_hosts.py will skip fmusim"
}

# The quick loop: is the setup current? (.venv with the package installed after the last change of
# pyproject.toml, and a configured build/); then the build brings itself up to date.
setup_current() {
  local info
  [ -x .venv/bin/python ] && [ -f build/CMakeCache.txt ] || return 1
  info=$(ls -d .venv/lib/python3*/site-packages/dryfriction-*.dist-info 2>/dev/null | head -1)
  [ -n "$info" ] && [ ! pyproject.toml -nt "$info" ]
}
quick_setup() {
  if setup_current; then
    echo "setup current (.venv, build/): incremental build only"
    cmake --build build -j2 >/dev/null
  else
    bash scripts/setup.sh
  fi
}
if [ "$QUICK" = 1 ]; then
  stage "setup (quick)" quick_setup
  stage "ctest" ctest --test-dir build --output-on-failure -j2
  stage "pytest not slow" pytest_ -m "not slow"
  exit 0
fi

stage "setup" bash scripts/setup.sh
stage "ctest" ctest --test-dir build --output-on-failure -j2
stage "host-libs" host_libs
stage "pytest" pytest_
stage "docs" bash scripts/docs.sh  # the site, warnings as errors, every internal link and anchor checked
examples() {  # every example at its own size, each in a scratch folder of its own, two at a time (one core each); the outputs printed in order
  local d i root=$PWD failed=()
  local -a files pids
  d=$(mktemp -d)
  files=(examples/*.py)
  for i in "${!files[@]}"; do
    mkdir "$d/$i"
    (cd "$d/$i" && "$root/.venv/bin/python" "$root/${files[i]}") >"$d/$i.log" 2>&1 &
    pids[i]=$!
    if [ "$i" -ge 1 ]; then  # at most two running: wait for the one before this
      wait "${pids[i - 1]}" || failed+=("${files[i - 1]}")
    fi
  done
  i=$((${#files[@]} - 1))
  wait "${pids[i]}" || failed+=("${files[i]}")
  for i in "${!files[@]}"; do
    echo "-- ${files[i]}"
    cat "$d/$i.log"
  done
  rm -rf "$d"
  [ ${#failed[@]} -eq 0 ] || { echo "examples failed: ${failed[*]}"; return 1; }
}
stage "examples" examples
stage "siconos-peer" .venv/bin/python bench/siconos_peer.py --quick  # installs python3-siconos when missing
stage "cross-platform" cross_platform
stage "ASan/UBSan build" asan_build
stage "ASan ctest" ctest --test-dir build-asan --output-on-failure -j2
stage "ASan pytest" asan_pytest
stage "fuzz, min-versions" fuzz
