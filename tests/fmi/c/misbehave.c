/* A controller that misbehaves at step `fail_step` as its macro says: HANG (doStep never
 * returns: a busy loop), SEGV (a write through a null pointer in doStep), KILL (it
 * sends itself SIGKILL in doStep); ABORT_INSTANTIATE
 * aborts in fmi2Instantiate (the frame's MODEL_ON_INSTANTIATE hook). Until then it holds
 * Fx = hold_fx and steers straight. */
#include <signal.h>
#include <stdlib.h>
#include "model.h"

int model_init(ModelData *m)
{
    (void)m;
    return MODEL_OK;
}

int model_step(ModelData *m, double t, double h)
{
    (void)t;
    (void)h;
    double *r = m->r;
    r[VR_Fx] = r[VR_hold_fx];
    r[VR_delta] = 0.0;
    if ((double)m->steps >= r[VR_fail_step]) {
#if defined(HANG)
        volatile unsigned long spin = 0;
        for (;;) spin++;
#elif defined(SEGV)
        volatile int *nowhere = (volatile int *)0;
        *nowhere = 1;
#elif defined(KILL)
        raise(SIGKILL);
#endif
    }
    return MODEL_OK;
}
