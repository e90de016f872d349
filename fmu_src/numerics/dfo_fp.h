/* The same numbers whatever flags a host compiles the FMU's sources with: no contraction of
 * a * b + c into a fused multiply-add (a host's `fmpy compile`, a plain `cc -O2 -march=native` or
 * aarch64's default would contract otherwise, and change the last bits), the C99 pragma where the
 * compiler honours it, GCC's equivalent where it does not. Included first by every source file of
 * the FMUs, before any other header, so that it covers the inline functions of the headers too.
 * (CMake also passes -ffp-contract=off; this makes the sources alone enough: tests/test_rebuild.py
 * rebuilds every FMU with -mfma -ffp-contract=fast and compares the outputs bit for bit.) */
#ifndef DFO_FP_H
#define DFO_FP_H

#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#if defined(__FMA__) || defined(__ARM_FEATURE_COMPLEX)
/* where the target has fused (complex) multiply-add instructions: GCC 12's SLP vectoriser fuses
 * a * b - c * d, a * d + c * b pairs into vfmaddsub even with fp-contract off (measured with
 * -mfma on x86-64); the baseline targets the shipped binaries are built for have none */
#pragma GCC optimize("no-tree-slp-vectorize")
#endif
#elif defined(_MSC_VER)
#pragma fp_contract(off)
#else
#pragma STDC FP_CONTRACT OFF
#endif

#endif
