/* A controller that goes wrong at step `fail_step`: with FAULT_NAN its delta output turns
 * NaN; otherwise doStep returns fmi2Error with a message of its own. Until then it holds
 * Fx = hold_fx and steers straight. */
#include <math.h>
#include <stdio.h>
#include "model.h"

int model_init(ModelData *m)
{
    if (m->log) m->log(m->env, MODEL_OK, "logEvents", "faulty controller initialised");
    return MODEL_OK;
}

int model_step(ModelData *m, double t, double h)
{
    (void)h;
    double *r = m->r;
    r[VR_Fx] = r[VR_hold_fx];
    r[VR_delta] = 0.0;
    if ((double)m->steps >= r[VR_fail_step]) {
#ifdef FAULT_NAN
        r[VR_delta] = NAN;
#else
        char msg[160];
        snprintf(msg, sizeof msg, "actuator model diverged at t = %.2f s (step %ld)", t, m->steps);
        if (m->log) m->log(m->env, MODEL_ERROR, "logStatusError", msg);
        return MODEL_ERROR;
#endif
    }
    return MODEL_OK;
}
