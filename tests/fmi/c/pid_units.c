/* The tracking pid of pid_tracking.c with the interface of a tool that works in km/h,
 * degrees and kN: speeds come in km/h, Fx goes out in kN and delta in degrees (the
 * modelDescription's unit definitions say so; ego converts). */
#include "model.h"
#include "ego_pid.h"

int model_init(ModelData *m) { (void)m; return MODEL_OK; }

int model_step(ModelData *m, double t, double h)
{
    (void)t;
    Pid *lon = (Pid *)&m->work[0];
    Pid *lat = (Pid *)&m->work[10];
    double *r = m->r;
    if (m->steps == 0) {
        pid_init(lon, r[VR_kp_lon], r[VR_ki_lon], r[VR_kd_lon], h, -r[VR_fx_limit], r[VR_fx_limit], r[VR_tau_d]);
        pid_init(lat, r[VR_kp_lat], r[VR_ki_lat], r[VR_kd_lat], h, -r[VR_steer_limit], r[VR_steer_limit],
                 r[VR_tau_d]);
    }
    const double kmh = 1.0 / 3.6, deg = 57.29577951308232;
    r[VR_Fx] = pid_step(lon, r[VR_s_ref] - r[VR_s], r[VR_ds_ref] * kmh - r[VR_ds] * kmh) / 1000.0;
    r[VR_delta] = pid_step(lat, r[VR_d_ref] - r[VR_d], r[VR_dd_ref] * kmh - r[VR_dd] * kmh) * deg;
    return MODEL_OK;
}
