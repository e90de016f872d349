#!/usr/bin/env bash
# The same numbers on every platform: build the FMUs with their Windows x86-64 and Linux aarch64
# binaries (cmake -DDFO_CROSS=ON), then run tests/platforms/fmu_harness on every binary of every
# FMU natively (Linux x86-64), under wine (Windows) and under qemu-aarch64 (Linux aarch64), and
#   1. compare the outputs and serialised states of the 300 parameter sets bit for bit (the FMUs:
#      FMUS below, one line each: the oscillator's with fmu_harness, the chain's with
#      chain_harness, n = 1 ... 6 blocks, the three schemes, the structures' with system_harness),
#   2. resume every set on every platform from the states serialised on every other platform and
#      compare with the original run,
#   3. compare the FMU's elementary functions (test_dmath --dump) bit for bit, and run the
#      physics' C tests (tests/c) on every platform (their printed numbers identical too),
#   4. check the binaries: the DLL exports only fmi2*/fmi3* and imports only system DLLs (no
#      libgcc, no libwinpthread); the Linux binaries need only glibc (the oldest version printed)
#      and import from its libm only functions IEEE 754 fixes to the bit (sqrt, floor, fmod, ...),
#   5. fmpy validate and fmutool -check on the multi-platform FMUs.
#
# Usage: bash scripts/cross_check.sh [--build DIR] [--report-only]
#   --build DIR     the build directory (default build; configured with -DDFO_CROSS=ON if needed)
#   --report-only   print the differences but exit 0 (to measure a build with -DDFO_LIBM=ON)
# Needs: gcc-mingw-w64-x86-64, gcc-aarch64-linux-gnu, qemu-user, wine64 (scripts/test.sh installs
# them), and .venv (scripts/setup.sh). Exit status 1 with one line per failed check.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
BUILD=build
REPORT_ONLY=0
while [ $# -gt 0 ]; do
  case $1 in
    --build) BUILD=$2; shift 2 ;;
    --report-only) REPORT_ONLY=1; shift ;;
    *) echo "cross_check: unknown argument $1 (usage: cross_check.sh [--build DIR] [--report-only])" >&2; exit 2 ;;
  esac
done
case $BUILD in /*) ;; *) BUILD=$ROOT/$BUILD ;; esac
PY=$ROOT/.venv/bin/python
[ -x "$PY" ] || { echo "cross_check: .venv missing: run bash scripts/setup.sh first" >&2; exit 2; }

WINE=$(command -v wine || command -v wine64 || { [ -x /usr/lib/wine/wine64 ] && echo /usr/lib/wine/wine64; } || true)
QEMU=$(command -v qemu-aarch64 || command -v qemu-aarch64-static || true)
[ -n "$WINE" ] || { echo "cross_check: wine not found (apt-get install wine64)" >&2; exit 2; }
[ -n "$QEMU" ] || { echo "cross_check: qemu-aarch64 not found (apt-get install qemu-user)" >&2; exit 2; }
export WINEPREFIX=$BUILD/wineprefix WINEDEBUG=-all
# One wine server for the whole check (persistent, stopped on exit): by default it exits a few
# seconds after its last client, and a client starting in that moment loses its connection
# ("wine client error: recvmsg: Connection reset by peer"), which fails a run for the emulator's sake.
WINESERVER=$(command -v wineserver || { [ -x /usr/lib/wine/wineserver ] && echo /usr/lib/wine/wineserver; } || true)
AARCH64_SYSROOT=/usr/aarch64-linux-gnu

FAILED=()
fail() { FAILED+=("$1"); echo "FAIL: $1"; }

if [ -n "$WINESERVER" ]; then
  mkdir -p "$WINEPREFIX"
  "$WINESERVER" -p && trap '"$WINESERVER" -k 2>/dev/null || true' EXIT
fi

# ---- build --------------------------------------------------------------------------------------
t0=$SECONDS
cmake -S . -B "$BUILD" -DDFO_CROSS=ON -DPython3_EXECUTABLE="$PY" >/dev/null
cmake --build "$BUILD" -j"$(nproc)" >/dev/null
echo "build (native + cross): $((SECONDS - t0)) s"

W=$BUILD/cross_check
rm -rf "$W"
mkdir -p "$W"
# The FMUs checked, one line each: "<name> <fmi2|fmi3> <.fmu below the build directory> <harness>"
# (the harness: a program of tests/platforms that drives that model through its FMI version).
FMUS=(
  "fmi2 fmi2 DryFrictionOscillator.fmu fmu_harness"
  "fmi3 fmi3 fmi3/DryFrictionOscillator.fmu fmu_harness"
  "chain2 fmi2 DryFrictionChain.fmu chain_harness"
  "chain3 fmi3 fmi3/DryFrictionChain.fmu chain_harness"
  "system2 fmi2 DryFrictionSystem.fmu system_harness"
  "system3 fmi3 fmi3/DryFrictionSystem.fmu system_harness"
)
declare -A FMI_OF FILE_OF HARNESS_NAME_OF ID_OF
KEYS=()
for line in "${FMUS[@]}"; do
  read -r key fmi file harness <<<"$line"
  KEYS+=("$key")
  FMI_OF[$key]=$fmi
  FILE_OF[$key]=$BUILD/$file
  HARNESS_NAME_OF[$key]=$harness
  # the binaries as shipped: unzip the FMU
  unzip -q -o "$BUILD/$file" -d "$W/$key"
  ID_OF[$key]=$(grep -o 'modelIdentifier="[^"]*"' "$W/$key/modelDescription.xml" | head -1 | cut -d'"' -f2)
done

# run PLATFORM PROGRAM ARGS...: the program natively, under wine or under qemu
run_on() {
  local plat=$1
  shift
  case $plat in
    x86_64-linux) "$@" ;;
    x86_64-windows) "$WINE" "$@" ;;
    aarch64-linux) "$QEMU" -L "$AARCH64_SYSROOT" "$@" ;;
  esac
}
# program PLATFORM NAME: a program of tests/platforms built for PLATFORM
program() {
  case $1 in
    x86_64-linux) echo "$BUILD/tests/platforms/$2" ;;
    x86_64-windows) echo "$BUILD/cross/x86_64-windows/tests/platforms/$2.exe" ;;
    *) echo "$BUILD/cross/$1/tests/platforms/$2" ;;
  esac
}
harness_of() { program "$2" "${HARNESS_NAME_OF[$1]}"; } # harness_of KEY PLATFORM
# lib_of KEY PLATFORM: the FMU's binary for PLATFORM as shipped (empty: the FMU has no folder for
# it, as FMI 2.0 for aarch64)
lib_of() {
  local key=$1 plat=$2 folder=$2 sfx=.so
  [ "$plat" = x86_64-windows ] && sfx=.dll
  if [ "${FMI_OF[$key]}" = fmi2 ]; then
    case $plat in x86_64-linux) folder=linux64 ;; x86_64-windows) folder=win64 ;; *) return 0 ;; esac
  fi
  echo "$W/$key/binaries/$folder/${ID_OF[$key]}$sfx"
}
PLATS=(x86_64-linux x86_64-windows aarch64-linux)

# ---- 1. outputs and states ------------------------------------------------------------------------
# The three platforms at once (one background job each, its FMUs in turn: wine's and qemu's start-ups
# overlap), their lines printed in order afterwards.
t0=$SECONDS
run_platform() {  # run_platform PLATFORM: every FMU's harness run on PLATFORM; failures into $W/fail_run_PLATFORM
  local p=$1 fmi lib ts
  for fmi in "${KEYS[@]}"; do
    lib=$(lib_of $fmi "$p")
    [ -n "$lib" ] || continue
    [ -f "$lib" ] || { echo "$fmi $p: no binary $lib" >>"$W/fail_run_$p"; continue; }
    ts=$SECONDS
    for try in 1 2; do  # (a second run only where the emulator itself failed, not the harness)
      if run_on "$p" "$(harness_of $fmi "$p")" "${FMI_OF[$fmi]}" "$lib" run "$W/states_${fmi}_$p.txt" >"$W/run_${fmi}_$p.txt" 2>"$W/run_${fmi}_$p.err" </dev/null; then
        break
      elif [ "$try" = 1 ] && grep -q '^wine client error' "$W/run_${fmi}_$p.err"; then
        echo "  $fmi $p: wine lost its server ($(tail -1 "$W/run_${fmi}_$p.err")), run again" >&2
      else
        echo "$fmi $p: fmu_harness failed ($(tail -1 "$W/run_${fmi}_$p.err"))" >>"$W/fail_run_$p"
        break
      fi
    done
    tr -d '\r' <"$W/run_${fmi}_$p.txt" >"$W/run_${fmi}_$p.tmp" && mv "$W/run_${fmi}_$p.tmp" "$W/run_${fmi}_$p.txt"
    echo "  $fmi $p: $(grep -c '^out' "$W/run_${fmi}_$p.txt") outputs, $(grep -c '^state' "$W/run_${fmi}_$p.txt") states, $(grep -c '^err' "$W/run_${fmi}_$p.txt" || true) failed calls ($((SECONDS - ts)) s)" >"$W/log_run_${fmi}_$p"
  done
}
for p in "${PLATS[@]}"; do run_platform "$p" & done
wait
for fmi in "${KEYS[@]}"; do
  for p in "${PLATS[@]}"; do [ ! -f "$W/log_run_${fmi}_$p" ] || cat "$W/log_run_${fmi}_$p"; done
done
for p in "${PLATS[@]}"; do
  [ ! -f "$W/fail_run_$p" ] || while IFS= read -r line; do fail "$line"; done <"$W/fail_run_$p"
done
echo "harness runs: $((SECONDS - t0)) s"

# compare A B: the sets whose lines differ, the largest difference of x relative to max |x|
compare() {
  "$PY" - "$1" "$2" <<'EOF'
import sys
def load(p):
    d = {}
    for line in open(p):
        f = line.split()
        if f and f[0] in ("out", "state", "err"):
            d.setdefault(int(f[1]), []).append(line.rstrip("\n"))
    return d
a, b = load(sys.argv[1]), load(sys.argv[2])
sets = sorted(set(a) | set(b))
diff = [s for s in sets if a.get(s) != b.get(s)]
worst = 0.0
for s in diff:
    for la, lb in zip(a.get(s, []), b.get(s, [])):
        fa, fb = la.split(), lb.split()
        if fa[0] == fb[0] == "out":
            xa, xb = float(fa[4].split(":")[0]), float(fb[4].split(":")[0])
            worst = max(worst, abs(xa - xb))
st = sum(1 for s in diff if [l for l in a.get(s, []) if l.startswith("state")] != [l for l in b.get(s, []) if l.startswith("state")])
print(f"{len(diff)} {len(sets)} {worst:.3g} {st}")
EOF
}

for fmi in "${KEYS[@]}"; do
  ref=$W/run_${fmi}_x86_64-linux.txt
  for p in x86_64-windows aarch64-linux; do
    other=$W/run_${fmi}_$p.txt
    [ -s "$other" ] || continue
    read -r nd ns worst nst < <(compare "$ref" "$other")
    echo "  $fmi x86_64-linux vs $p: $nd of $ns sets differ (max |dx| $worst; serialised states differ in $nst)"
    [ "$nd" = 0 ] || fail "$fmi: $p differs from x86_64-linux in $nd of $ns sets"
  done
done

# ---- 2. states across platforms ---------------------------------------------------------------
# Run on the three platforms at once (one background job per platform resuming every FMU's states
# from every platform), then compared in order.
t0=$SECONDS
for fmi in "${KEYS[@]}"; do
  for from in "${PLATS[@]}"; do
    [ -s "$W/states_${fmi}_$from.txt" ] || continue
    grep -E '^out [0-9]+ (9|1[0-6]) ' "$W/run_${fmi}_$from.txt" >"$W/second_${fmi}_$from.txt" || true
  done
done
resume_on() {  # resume_on PLATFORM: every FMU's states of every platform continued on PLATFORM
  local to=$1 fmi from out
  for fmi in "${KEYS[@]}"; do
    [ -n "$(lib_of $fmi "$to")" ] || continue
    for from in "${PLATS[@]}"; do
      [ -s "$W/states_${fmi}_$from.txt" ] || continue
      out=$W/resume_${fmi}_${from}_on_$to.txt
      # (into a file: wine writes to a pipe ten times slower)
      for try in 1 2; do  # (a second run where the emulator's first ended short)
        run_on "$to" "$(harness_of $fmi "$to")" "${FMI_OF[$fmi]}" "$(lib_of $fmi "$to")" resume "$W/states_${fmi}_$from.txt" >"$out.raw" 2>/dev/null </dev/null || true
        tr -d '\r' <"$out.raw" >"$out"
        [ "$(grep -c '^out' "$out" || true)" = "$(grep -c '^out' "$W/second_${fmi}_$from.txt" || true)" ] && break
        [ "$try" = 1 ] && echo "  $fmi state from $from on $to: the run ended short, run again" >&2
      done
    done
  done
}
for to in "${PLATS[@]}"; do resume_on "$to" & done
wait
for fmi in "${KEYS[@]}"; do
  for from in "${PLATS[@]}"; do
    [ -s "$W/states_${fmi}_$from.txt" ] || continue
    for to in "${PLATS[@]}"; do
      [ -n "$(lib_of $fmi "$to")" ] || continue
      out=$W/resume_${fmi}_${from}_on_$to.txt
      nerr=$(grep -c '^err' "$out" || true)
      if cmp -s "$out" "$W/second_${fmi}_$from.txt"; then
        echo "  $fmi state from $from continued on $to: identical to the original run"
      else
        read -r nd ns worst _ < <(compare "$W/second_${fmi}_$from.txt" "$out")
        echo "  $fmi state from $from continued on $to: $nd of $ns sets differ (max |dx| $worst, $nerr refused)"
        fail "$fmi: states from $from continued on $to differ in $nd sets"
      fi
    done
  done
done
echo "resumes: $((SECONDS - t0)) s"

# ---- 3. the elementary functions ----------------------------------------------------------------
for p in "${PLATS[@]}"; do
  run_on "$p" "$(program "$p" test_dmath)" --dump >"$W/dmath_$p.raw" </dev/null || fail "test_dmath --dump failed on $p"
  tr -d '\r' <"$W/dmath_$p.raw" >"$W/dmath_$p.txt"
done
for p in x86_64-windows aarch64-linux; do
  n=$(cmp -l "$W/dmath_x86_64-linux.txt" "$W/dmath_$p.txt" 2>/dev/null | wc -l || true)
  if cmp -s "$W/dmath_x86_64-linux.txt" "$W/dmath_$p.txt"; then
    echo "  dmath: $p identical to x86_64-linux ($(wc -l <"$W/dmath_$p.txt") results)"
  else
    echo "  dmath: $p differs from x86_64-linux ($n bytes)"
    fail "dmath: $p differs from x86_64-linux"
  fi
done

# ---- 3b. the physics' C tests (tests/c) on every platform -------------------------------------------
t0=$SECONDS
CTESTS=(test_lcp test_stepper test_host_clock test_exact test_engine test_engine_step)
for t in "${CTESTS[@]}"; do # all at once (qemu takes 3-18 s per test)
  for p in "${PLATS[@]}"; do
    { run_on "$p" "$(program "$p" "$t" | sed 's|/tests/platforms/|/tests/c/|')" >"$W/$t.$p.raw" 2>&1 </dev/null
      echo $? >"$W/$t.$p.rc"; } &
  done
done
wait
for t in "${CTESTS[@]}"; do
  for p in "${PLATS[@]}"; do
    tr -d '\r' <"$W/$t.$p.raw" >"$W/$t.$p.txt"
    [ "$(cat "$W/$t.$p.rc")" = 0 ] || fail "$t fails on $p: $(tail -1 "$W/$t.$p.txt")"
  done
  same=yes
  for p in x86_64-windows aarch64-linux; do cmp -s "$W/$t.x86_64-linux.txt" "$W/$t.$p.txt" || same=no; done
  echo "  $t: passes on ${PLATS[*]}; printed numbers identical on all: $same"
  # test_exact draws its cases and references with the platform's libm: only passing is compared
  [ "$same" = yes ] || [ "$t" = test_exact ] || fail "$t prints different numbers on the platforms"
done
echo "C tests: $((SECONDS - t0)) s"

# ---- 4. the binaries ------------------------------------------------------------------------------
LIBM_FUNCS=$(nm -D --defined-only "$(gcc -print-file-name=libm.so.6)" | awk '{sub(/@.*/, "", $3); print $3}' | sort -u)
for fmi in "${KEYS[@]}"; do
  dll=$(lib_of $fmi x86_64-windows)
  imports=$(x86_64-w64-mingw32-objdump -p "$dll" | awk '/DLL Name:/ {print $3}' | sort -u | tr '\n' ' ')
  exports=$(x86_64-w64-mingw32-objdump -p "$dll" | awk '/\[Ordinal\/Name Pointer\] Table/ {f=1; next} f && /^[ \t]*\[/ {print $NF} f && /^$/ {f=0}')
  nexp=$(echo "$exports" | grep -c . || true)
  bad=$(echo "$exports" | grep -v "^${FMI_OF[$fmi]}" || true)
  echo "  $fmi DLL: imports $imports; exports $nexp functions$([ -n "$bad" ] && echo ", also: $bad")"
  [ -z "$bad" ] || fail "$fmi DLL exports more than the FMI functions: $bad"
  for d in $imports; do
    case ${d,,} in kernel32.dll | msvcrt.dll | api-ms-win-crt-*.dll | ucrtbase.dll) ;; *) fail "$fmi DLL needs $d" ;; esac
  done
  for p in x86_64-linux aarch64-linux; do
    so=$(lib_of $fmi "$p")
    [ -n "$so" ] || continue
    needed=$(objdump -p "$so" | awk '/NEEDED/ {print $2}' | tr '\n' ' ')
    glibc=$(objdump -T "$so" | grep -o 'GLIBC_[0-9.]*' | sort -uV | tail -1)
    echo "  $fmi $p: needs $needed(newest symbol version $glibc)"
    for d in $needed; do
      case $d in libc.so.6 | libm.so.6 | ld-linux-*) ;; *) fail "$fmi $p needs $d" ;; esac
    done
  done
  # from the C library's mathematics only functions whose results IEEE 754 fixes to the bit (the
  # others, e.g. hypot, atan2, exp, sin, differ in their last bits between libms: numerics/dmath.h)
  so=$(lib_of $fmi x86_64-linux)
  used=""
  for f in $(nm -D --undefined-only "$so" | awk '{sub(/@.*/, "", $2); print $2}'); do
    grep -qx "$f" <<<"$LIBM_FUNCS" || continue
    used="$used $f"
    case $f in sqrt | fabs | floor | ceil | trunc | round | fmod | fmax | fmin | nextafter | copysign | ldexp | frexp | scalbn) ;;
      *) fail "$fmi imports libm's $f, whose last bits differ between platforms (use numerics/dmath.h)" ;;
    esac
  done
  echo "  $fmi x86_64-linux: from libm only$used"
done

# ---- 5. the FMUs ----------------------------------------------------------------------------------
for key in "${KEYS[@]}"; do
  f=${FILE_OF[$key]}
  name=${f#"$BUILD"/}
  failed_before=${#FAILED[@]}
  "$ROOT/.venv/bin/fmpy" validate "$f" >"$W/validate.txt" 2>&1 || fail "fmpy validate $name: $(grep -v '^$' "$W/validate.txt" | tail -1)"
  # the checker once reported the chain FMU not compliant in CI and passed it on every run since
  # (its XSD validation of the same file): a failure is run once more, the first one's sentence
  # printed; a second failure fails the check with the tool's own error lines
  check_ok() { grep -q "seems to be compliant" <<<"$1" && grep -q "No semantic error" <<<"$1"; }
  check=$("$ROOT/.venv/bin/fmutool" -input "$f" -check 2>&1) || true
  if ! check_ok "$check"; then
    first=$(grep -i -m2 "error" <<<"$check" | tr '\n' ' ' || true)
    check=$("$ROOT/.venv/bin/fmutool" -input "$f" -check 2>&1) || true
    if check_ok "$check"; then
      echo "  note: fmutool -check $name failed once (${first:-no error line}), passed when run again"
    else
      fail "fmutool -check $name: $(grep -i "error\|compliant" <<<"$check" | head -3 | tr '\n' ' ')"
    fi
  fi
  platforms=$(unzip -Z1 "$f" | awk -F/ '$1 == "binaries" && $3 != "" {print $2}' | sort -u | tr '\n' ' ')
  if [ ${#FAILED[@]} -eq "$failed_before" ]; then
    echo "  $name: binaries/ $platforms; fmpy validate, fmutool -check: passed"
  fi
done

if [ ${#FAILED[@]} -gt 0 ]; then
  echo "cross_check: ${#FAILED[@]} check(s) failed"
  [ "$REPORT_ONLY" = 1 ] && exit 0
  exit 1
fi
echo "cross_check: all platforms give the same numbers"
