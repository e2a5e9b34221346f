/* Report 002's linear dynamic bicycle (ego.models.dynamic_bicycle.DynamicBicycle) as an FMU
 * model: the same right-hand side and unrolled RK4, term for term, so the FMU and ego agree
 * to rounding. Inputs a_x (m/s^2) and delta (rad); state outputs X, u, Y, v, psi, r. */
#include <math.h>
#include "model.h"

static void lin_rhs(const double *r_, const double *x, double a_x, double delta, double *dx)
{
    const double two_m = 2.0 / r_[VR_m], two_iz = 2.0 / r_[VR_Iz];
    const double lf = r_[VR_lf], lr = r_[VR_lr], cf = r_[VR_Cf], cr = r_[VR_Cr], floor_ = r_[VR_slip_speed_floor];
    const double u = x[1], v = x[3], psi = x[4], r = x[5];
    const double us = u >= floor_ ? u : floor_;
    const double f_cf = cf * ((v + lf * r) / us - delta);
    const double f_cr = cr * ((v - lr * r) / us);
    const double c = cos(psi), s = sin(psi);
    dx[0] = u * c - v * s;
    dx[1] = r * v + a_x;
    dx[2] = u * s + v * c;
    dx[3] = -r * u + two_m * (f_cf * cos(delta) + f_cr);
    dx[4] = r;
    dx[5] = two_iz * (lf * f_cf - lr * f_cr);
}

static void lin_rk4(const double *p, double *x, double a_x, double delta, double h, const double *k1_in)
{
    double a[6], b[6], c[6], d[6], y[6];
    const double half = 0.5 * h, sixth = h / 6.0;
    int i;
    if (k1_in) for (i = 0; i < 6; i++) a[i] = k1_in[i];
    else lin_rhs(p, x, a_x, delta, a);
    for (i = 0; i < 6; i++) y[i] = x[i] + half * a[i];
    lin_rhs(p, y, a_x, delta, b);
    for (i = 0; i < 6; i++) y[i] = x[i] + half * b[i];
    lin_rhs(p, y, a_x, delta, c);
    for (i = 0; i < 6; i++) y[i] = x[i] + h * c[i];
    lin_rhs(p, y, a_x, delta, d);
    for (i = 0; i < 6; i++) x[i] = x[i] + sixth * (a[i] + 2.0 * b[i] + 2.0 * c[i] + d[i]);
}

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
    double x[6] = {r[VR_X], r[VR_u], r[VR_Y], r[VR_v], r[VR_psi], r[VR_r]}, k1[6];
    const long n = (long)r[VR_substeps];
    /* as ego's FixedStepIntegrator(rhs, (h / n) * n, n): its step is ((h / n) * n) / n */
    const double hh = ((h / (double)n) * (double)n) / (double)n, u0 = x[1], r0 = x[5];
    lin_rhs(r, x, r[VR_a_x], r[VR_delta], k1);
    lin_rk4(r, x, r[VR_a_x], r[VR_delta], hh, k1);
    for (long i = 1; i < n; i++) lin_rk4(r, x, r[VR_a_x], r[VR_delta], hh, NULL);
    for (int i = 0; i < 6; i++) if (!isfinite(x[i])) {
        if (m->log) m->log(m->env, MODEL_ERROR, "logStatusError", "the state is no longer finite");
        return MODEL_ERROR;
    }
    r[VR_X] = x[0]; r[VR_u] = x[1]; r[VR_Y] = x[2]; r[VR_v] = x[3]; r[VR_psi] = x[4]; r[VR_r] = x[5];
    r[VR_lateral_accel] = k1[3] + u0 * r0;
    return MODEL_OK;
}
