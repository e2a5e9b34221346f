/* What a model gives the FMI frames (fmi2_frame.c, fmi3_frame.c): its real variables in one
 * array indexed by value reference (model_vars.h names the indices VR_<name>), an init and a
 * step. Status values are FMI's: 0 OK, 1 warning, 3 error, 4 fatal. */
#ifndef EGO_FMU_MODEL_H
#define EGO_FMU_MODEL_H

#include <stddef.h>
#include "model_vars.h"

#define MODEL_OK 0
#define MODEL_WARNING 1
#define MODEL_ERROR 3

typedef struct {
    double r[MODEL_N_REALS];
    long steps;  /* doStep calls since the start (or reset) */
    void (*log)(void *env, int status, const char *category, const char *message);
    void *env;
    double work[32];  /* the model's own state (integrators, filters) */
} ModelData;

/* after initialisation mode: parameters are set; returns a status */
int model_init(ModelData *m);
/* one communication step from t to t + h: inputs are in r, write the outputs; returns a status */
int model_step(ModelData *m, double t, double h);

#endif
