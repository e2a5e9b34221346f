/*
 * Report 000's nonlinear bicycle right-hand side and its RK4 step: the kernel shared by the
 * native twin (ego/_native.c) and the FMU ego export-fmu writes (ego/fmi/c/nonlinear_bicycle.c),
 * so both integrate with the same arithmetic. Plain C99 and <math.h>; compile with
 * -ffp-contract=off to keep CPython's (unfused) arithmetic.
 */
#ifndef EGO_BICYCLE_H
#define EGO_BICYCLE_H
#include <math.h>
#include <stddef.h>

/* ---------------------------------------------------------------------------------------
 * Nonlinear bicycle (report 000). Parameters are 16 doubles packed in a bytes object:
 * Nw, rolling, m, Iz, a, b, DFzf, DFzr, F_max, By, Cy, Ey, Shy, Svy, slip_speed_floor,
 * abs (1: the drive/brake force is limited to what the rear friction circle leaves beside
 * the rear lateral force, so the circle never scales the lateral force down).
 * ------------------------------------------------------------------------------------- */
#define BIKE_NPARAM 16
#define NX 6

static void bike_rhs(const double *p, const double *x, double Fx, double delta, double *dx)
{
    const double Nw = p[0], rolling = p[1], m = p[2], Iz = p[3], a = p[4], b = p[5];
    const double DFzf = p[6], DFzr = p[7], F_max = p[8], By = p[9], Cy = p[10], Ey = p[11];
    const double Shy = p[12], Svy = p[13], floor_ = p[14], abs_ = p[15];
    const double R2D = 180.0 / 3.141592653589793;
    const double oneE = 1.0 - Ey, EB = Ey / By, F_max2 = F_max * F_max;
    const double uu = x[1], v = x[3], psi = x[4], r = x[5];
    const double us = uu >= floor_ ? uu : floor_;
    const double af = (delta - atan2(v + a * r, us)) * R2D + Shy;
    const double ar = -atan2(v - b * r, us) * R2D + Shy;
    const double F_yf = DFzf * sin(Cy * atan(By * (oneE * af + EB * atan(By * af)))) + Svy;
    double F_yr = DFzr * sin(Cy * atan(By * (oneE * ar + EB * atan(By * ar)))) + Svy;
    double NF = Nw * Fx;
    double total2 = NF * NF + F_yr * F_yr;
    if (abs_ != 0.0 && total2 > F_max2) { /* ABS / traction control */
        const double room = F_max2 - F_yr * F_yr;
        const double lim = room > 0.0 ? sqrt(room) : 0.0;
        NF = NF > 0.0 ? lim : -lim;
        total2 = NF * NF + F_yr * F_yr;
    }
    if (total2 > F_max2) { /* rear friction circle */
        const double scale = F_max / sqrt(total2);
        NF *= scale;
        F_yr *= scale;
    }
    const double c = cos(psi), s = sin(psi), cd = cos(delta);
    dx[0] = uu * c - v * s;
    dx[1] = (-rolling + NF - F_yf * sin(delta)) / m + v * r;
    dx[2] = uu * s + v * c;
    dx[3] = (F_yf * cd + F_yr) / m - uu * r;
    dx[4] = r;
    dx[5] = (F_yf * a * cd - F_yr * b) / Iz;
}

/* One RK4 step of length h with the input held (same expression order as unrolled_rk4). */
static void bike_rk4(const double *p, double *x, double Fx, double delta, double h, double *k1_out)
{
    double k1[NX], k2[NX], k3[NX], k4[NX], y[NX];
    const double half = 0.5 * h, sixth = h / 6.0;
    int i;
    bike_rhs(p, x, Fx, delta, k1);
    if (k1_out) for (i = 0; i < NX; i++) k1_out[i] = k1[i];
    for (i = 0; i < NX; i++) y[i] = x[i] + half * k1[i];
    bike_rhs(p, y, Fx, delta, k2);
    for (i = 0; i < NX; i++) y[i] = x[i] + half * k2[i];
    bike_rhs(p, y, Fx, delta, k3);
    for (i = 0; i < NX; i++) y[i] = x[i] + h * k3[i];
    bike_rhs(p, y, Fx, delta, k4);
    for (i = 0; i < NX; i++) x[i] = x[i] + sixth * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
}

#endif
