/* Forced inlining where it specialises code (the exact scheme's event loop compiled once per kind of
 * inputs, a constant in each; Lemke's small helpers in its pivoting loops), and cold paths kept out
 * of hot loops. The same arithmetic either way, so the same numbers. DFO_NO_FORCE_INLINE leaves
 * the choice to the compiler (the fuzz builds set it: clang's coverage, ASan and UBSan
 * instrumentation of flattened functions is slow to compile). */
#ifndef DFO_INLINE_H
#define DFO_INLINE_H

#if defined(__GNUC__) && !defined(DFO_NO_FORCE_INLINE)
#define DFO_FORCE_INLINE inline __attribute__((always_inline))
#define DFO_NO_INLINE __attribute__((noinline))
#elif defined(__GNUC__)
#define DFO_FORCE_INLINE inline
#define DFO_NO_INLINE __attribute__((noinline))
#else
#define DFO_FORCE_INLINE inline
#define DFO_NO_INLINE
#endif

#endif
