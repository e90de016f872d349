/* Forced inlining: the step's small functions compiled into the schemes' loops (the state kept in
 * registers; a call and its spills are a good part of a small structure's step), and the cold paths
 * kept out of them. The same arithmetic either way, so the same numbers.
 * DFO_NO_FORCE_INLINE leaves the choice to the compiler: the fuzz builds set it, where clang's
 * coverage, ASan and UBSan instrumentation of the flattened schemes takes minutes per file. */
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
