#!/usr/bin/env bash
# Fuzz the FMI entry points with libFuzzer + ASan/UBSan for a bounded time.
#
#   tests/fuzz/run_fuzz.sh [seconds]        (default 60; env FUZZ_TIME_ORACLE=0 to explore past
#                                            the time-exactness oracle, FUZZ_BUILD=<dir> for the build,
#                                            FUZZ_TARGET=fuzz_fmi3 or fuzz_chain3 for the FMI 3.0
#                                            oscillator or chain: corpus3 / corpus_chain3, and
#                                            regressions3 / regressions_chain3 for the kept inputs,
#                                            FUZZ_STEP=build to only build the target, FUZZ_STEP=run
#                                            to fuzz a target built before: scripts/test.sh builds
#                                            both of its targets, then fuzzes them at once)
#
# Installs clang when missing (apt-get, quiet), builds tests/fuzz with -DDFO_FUZZ=ON, fuzzes from
# tests/fuzz/corpus (new coverage goes to a scratch corpus, not into the repository) and copies
# every crash / timeout / leak input into tests/fuzz/regressions/, where ctest replays it
# (fuzz_regression_<name>). Exit status: 0 when nothing was found, 1 when inputs were kept, 2 when
# clang with its fuzzer runtime could not be installed or the target did not build.
set -euo pipefail
secs=${1:-60}
# the target: fuzz_fmi (FMI 2.0, default), fuzz_fmi3 (FMI 3.0), fuzz_chain3 or fuzz_chain2 (the
# chain's FMI 3.0 and 2.0), each with its corpus and regressions folder
target=${FUZZ_TARGET:-fuzz_fmi}
case $target in
  fuzz_fmi) corpus=corpus; regressions=regressions ;;
  fuzz_fmi3) corpus=corpus3; regressions=regressions3 ;;
  fuzz_chain3) corpus=corpus_chain3; regressions=regressions_chain3 ;;
  fuzz_chain2) corpus=corpus_chain2; regressions=regressions_chain2 ;; # no seeds: starts empty
  *) echo "run_fuzz: unknown FUZZ_TARGET $target (fuzz_fmi, fuzz_fmi3, fuzz_chain3, fuzz_chain2)" >&2; exit 2 ;;
esac
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
build=${FUZZ_BUILD:-/tmp/dfo-fuzz-build}
oracle=${FUZZ_TIME_ORACLE:-1}
step=${FUZZ_STEP:-all}
case $step in all | build | run) ;; *) echo "run_fuzz: unknown FUZZ_STEP $step (all, build, run)" >&2; exit 2 ;; esac
python=${PYTHON:-}
if [ -z "$python" ]; then   # the interpreter with fmpy (the FMI headers come from it)
  if [ -x "$root/.venv/bin/python" ]; then python=$root/.venv/bin/python; else python=$(command -v python3); fi
fi

# clang (installed when missing), then the target's configure and build (FUZZ_STEP all or build)
build_target() {
  # clang with its libFuzzer and sanitizer runtimes: a one-line test build tells whether they work
  fuzzer_works() {
    local d
    d=$(mktemp -d /tmp/dfo-fuzz-probe.XXXXXX)
    printf 'int LLVMFuzzerTestOneInput(const unsigned char *d, unsigned long n) { (void)d; (void)n; return 0; }\n' >"$d/p.c"
    clang -fsanitize=fuzzer,address,undefined "$d/p.c" -o "$d/p" >/dev/null 2>&1
    local rc=$?
    rm -rf "$d"
    return $rc
  }
  if ! command -v clang >/dev/null 2>&1 || ! fuzzer_works; then
    echo "run_fuzz: installing clang and its fuzzer runtime" >&2
    export DEBIAN_FRONTEND=noninteractive
    # wait for the dpkg lock (another install may hold it, e.g. on a CI runner starting up) rather
    # than fail at once; without recommends, the runtime package (libclang-rt-dev: libFuzzer, ASan,
    # UBSan) is named explicitly where the distribution has it
    apt_log=$(mktemp /tmp/dfo-fuzz-apt.XXXXXX)
    apt_get() { apt-get -o DPkg::Lock::Timeout=600 "$@" >>"$apt_log" 2>&1; }
    if apt_get update -qq; then
      apt_get install -y -qq --no-install-recommends clang libclang-rt-dev \
        || apt_get install -y -qq --no-install-recommends clang || true
    fi
    if ! command -v clang >/dev/null 2>&1 || ! fuzzer_works; then
      echo "run_fuzz: could not install clang with a working libFuzzer (apt-get needs root and network; log: $apt_log)" >&2
      exit 2
    fi
    rm -f "$apt_log"
  fi

  cmake -S "$root" -B "$build" -DCMAKE_C_COMPILER=clang -DDFO_FUZZ=ON -DFUZZ_TIME_ORACLE="$oracle" \
        -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPython3_EXECUTABLE="$python" >/dev/null
  if ! cmake --build "$build" --target "$target" -j2 >"$build/fuzz_build.log" 2>&1; then
    echo "run_fuzz: building the fuzz target failed (log: $build/fuzz_build.log)" >&2
    exit 2
  fi
}
[ "$step" = run ] || build_target
[ "$step" != build ] || exit 0
if [ ! -x "$build/tests/fuzz/$target" ]; then
  echo "run_fuzz: $build/tests/fuzz/$target is not built (FUZZ_STEP=build first)" >&2
  exit 2
fi

work=$(mktemp -d /tmp/dfo-fuzz.XXXXXX)
mkdir -p "$work/corpus" "$work/artifacts"
cp "$here/$corpus"/* "$work/corpus/" 2>/dev/null || true
echo "run_fuzz: fuzzing $target for ${secs}s (time oracle ${oracle}), scratch dir $work" >&2
set +e
# fork mode: keep fuzzing after a crash, so that one known bug does not hide the next
UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
"$build/tests/fuzz/$target" "$work/corpus" -fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 \
  -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -max_len=512 -print_final_stats=1 \
  -artifact_prefix="$work/artifacts/" >"$work/fuzz.log" 2>&1
rc=$?
set -e
grep -E "^#[0-9]+: cov|INFO: exiting|DONE" "$work/fuzz.log" | tail -n 3 >&2 || true

# One regression input per distinct failure: the signature is the first oracle / sanitizer /
# timeout line of a replay of the input.
signature() {
  local out
  out=$( (timeout 60 "$build/tests/fuzz/$target" "$1" -timeout=10 -runs=1 2>&1 || true) \
    | grep -m1 -oE "oracle failed: .*|ERROR: [A-Za-z]+Sanitizer: [a-z-]+|runtime error: [^0-9]*|ALARM: working on the last Unit" || true)
  echo "${out:-timeout or no failure}"
}
declare -A seen=()
mkdir -p "$here/$regressions"
for f in "$here/$regressions"/*; do
  [ -f "$f" ] && seen["$(signature "$f")"]=1
done
found=0
for f in "$work"/artifacts/*; do
  [ -f "$f" ] || continue
  sig=$(signature "$f")
  if [ -n "${seen[$sig]:-}" ]; then continue; fi
  seen["$sig"]=1
  name=$(basename "$f")
  cp "$f" "$here/$regressions/$name.tmp" && mv "$here/$regressions/$name.tmp" "$here/$regressions/$name"
  echo "run_fuzz: kept $name in tests/fuzz/$regressions/ ($sig)" >&2
  found=1
done
echo "run_fuzz: libFuzzer exit $rc, $(ls "$work/artifacts" | wc -l) failing inputs found, corpus $(ls "$work/corpus" | wc -l) inputs, log $work/fuzz.log" >&2
exit $found
