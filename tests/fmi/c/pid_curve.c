/* ego's curve `pid` (ego.control.curve.CurvePID, pedal loop off) as an FMU: delta from
 * e = e_lat + e_head, a_x = the plan's accel_ref. */
#include "model.h"
#include "ego_pid.h"

int model_init(ModelData *m) { (void)m; return MODEL_OK; }

int model_step(ModelData *m, double t, double h)
{
    (void)t;
    Pid *pid = (Pid *)&m->work[0];
    double *r = m->r;
    if (m->steps == 0)
        pid_init(pid, r[VR_kp], r[VR_ki], r[VR_kd], h, -r[VR_steer_limit], r[VR_steer_limit], 0.05);
    double e_lat = r[VR_d_ref] - r[VR_d], e_head = -r[VR_heading_error];
    double e = e_lat + e_head;
    double de = r[VR_dd_ref] - r[VR_dd] - (r[VR_yaw_rate] - r[VR_ds] * r[VR_curvature]);
    r[VR_delta] = pid_step(pid, e, de);
    r[VR_a_x] = r[VR_accel_ref];
    r[VR_pid_e] = e;
    return MODEL_OK;
}
