/* Report 000's nonlinear bicycle as an FMU model: the RK4 kernel of ego's native twin
 * (_bicycle.h, shared with ego/_native.c), `substeps` RK4 steps per communication step with
 * the input held. State outputs X, u, Y, v, psi, r start at the parameters X0...r0;
 * lateral_accel is dv/dt + u r at the start of the last step (what ego records). */
#include "model.h"
#include "_bicycle.h"

int model_init(ModelData *m)
{
    double *r = m->r;
    r[VR_X] = r[VR_X0]; r[VR_u] = r[VR_u0]; r[VR_Y] = r[VR_Y0];
    r[VR_v] = r[VR_v0]; r[VR_psi] = r[VR_psi0]; r[VR_r] = r[VR_r0];
    r[VR_lateral_accel] = 0.0;
    if (r[VR_substeps] < 1.0 || r[VR_substeps] != (double)(long)r[VR_substeps]) {
        if (m->log) m->log(m->env, MODEL_ERROR, "logStatusError", "substeps must be a whole number >= 1");
        return MODEL_ERROR;
    }
    return MODEL_OK;
}

int model_step(ModelData *m, double t, double h)
{
    (void)t;
    double *r = m->r;
    const double p[BIKE_NPARAM] = {r[VR_Nw], r[VR_rolling], r[VR_m], r[VR_Iz], r[VR_a], r[VR_b], r[VR_DFzf],
                                   r[VR_DFzr], r[VR_F_max], r[VR_By], r[VR_Cy], r[VR_Ey], r[VR_Shy], r[VR_Svy],
                                   r[VR_slip_speed_floor], r[VR_abs]};
    double x[NX] = {r[VR_X], r[VR_u], r[VR_Y], r[VR_v], r[VR_psi], r[VR_r]}, k1[NX];
    const long n = (long)r[VR_substeps];
    const double hh = h / (double)n, u0 = x[1], r0 = x[5];
    bike_rk4(p, x, r[VR_Fx], r[VR_delta], hh, k1);
    for (long i = 1; i < n; i++) bike_rk4(p, x, r[VR_Fx], r[VR_delta], hh, NULL);
    for (int i = 0; i < NX; i++) if (!isfinite(x[i])) {
        if (m->log) m->log(m->env, MODEL_ERROR, "logStatusError", "the state is no longer finite");
        return MODEL_ERROR;
    }
    r[VR_X] = x[0]; r[VR_u] = x[1]; r[VR_Y] = x[2]; r[VR_v] = x[3]; r[VR_psi] = x[4]; r[VR_r] = x[5];
    r[VR_lateral_accel] = k1[3] + u0 * r0;
    return MODEL_OK;
}
