/* ego.control.pid.PID, operation for operation (same order, so the same doubles with
 * -ffp-contract=off): filtered derivative, saturation, back-calculation anti-windup. */
#ifndef EGO_PID_H
#define EGO_PID_H
#include <math.h>

typedef struct { double kp, ki, kd, dt, u_min, u_max, alpha, kaw, integral, de_f; } Pid;

static void pid_init(Pid *p, double kp, double ki, double kd, double dt, double u_min, double u_max,
                     double tau_d)
{
    p->kp = kp; p->ki = ki; p->kd = kd; p->dt = dt; p->u_min = u_min; p->u_max = u_max;
    p->alpha = tau_d > 0 ? dt / (tau_d + dt) : 1.0;
    double tau_aw = 0.0;
    if (ki > 0) {
        double ti = kp > 0 ? kp / ki : 1.0;
        tau_aw = (kp > 0 && kd > 0) ? sqrt(ti * (kd / kp)) : ti;
    }
    p->kaw = tau_aw != 0.0 ? dt / tau_aw : 0.0;
    p->integral = 0.0;
    p->de_f = 0.0;
}

static double pid_step(Pid *p, double e, double de)
{
    p->de_f += p->alpha * (de - p->de_f);
    double u = p->kp * e + p->ki * p->integral + p->kd * p->de_f;
    double u_sat = u > p->u_max ? p->u_max : (u < p->u_min ? p->u_min : u);
    p->integral += p->dt * e;
    if (p->ki > 0.0 && u_sat != u)
        p->integral += p->kaw * (u_sat - u) / p->ki;
    return u_sat;
}
#endif
