/* The engine of the oscillator's Bossak schemes (osc_bossak.c), kept by a caller that steps often
 * (the FMU instance: scheme.h's dfo_advance_cached): its engine model made on first use, and made
 * anew when the model changes or the cache has moved, so that a call costs no set-up. A plain
 * struct the caller embeds and zero-fills; it holds no part of a trajectory (an FMU state never
 * copies it). dfo_advance without one makes the engine on the stack in every call (a few hundred
 * ns). Plain C, no FMI types. */
#ifndef DFO_OSC_BOSSAK_H
#define DFO_OSC_BOSSAK_H

#include "osc_engine_ops.h"
#include "oscillator.h"

#define OSC_BOSSAK_ARENA 448 /* doubles (3.5 KiB): the engine of one DOF and one contact needs 3.0 KiB (386) */

/* An arena of doubles the engine's memory comes from (eng_alloc over it; nothing is released). */
typedef struct {
    double *buf;
    size_t used, cap; /* in doubles */
} osc_arena;

typedef struct osc_bossak_engine_s {
    const void *self;              /* where it was made (NULL: never; elsewhere: moved, made anew) */
    dfo_model M;                   /* the model it was made for */
    double buf[OSC_BOSSAK_ARENA];
    osc_arena ar;
    osc_eng_model O;
    eng *E;
} osc_bossak_engine;

#endif
