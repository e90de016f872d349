/* The instance of the DryFrictionOscillator FMUs (its core: osc_instance.c, the model API of
 * core/instance.h): the life cycle first, then the values that define where a simulation is, plain
 * values without pointers (an FMU state copies them, its serialisation writes their bytes). The
 * variable table generated from modelDescription.xml (model_vars.h) reaches the parameters and
 * inputs by offsetof into osc_values' p and u. No FMI types. */
#ifndef DFO_OSC_INSTANCE_H
#define DFO_OSC_INSTANCE_H

#include "instance.h"
#include "scheme.h"
#include "oscillator.h"

typedef struct {
    dfo_params p;
    dfo_inputs u;
    dfo_inputs u_used;        /* the inputs of the last step (or of initialisation) */
    dfo_model M;
    dfo_state s;
    double t_switch;          /* the time of the last stick/slip switch a step met (-inf: none) */
    int effects;
} osc_values;

typedef struct {
    dfo_lifecycle lc;         /* first: the glues see the instance as its life cycle */
    osc_values v;
} osc_instance;

#endif
