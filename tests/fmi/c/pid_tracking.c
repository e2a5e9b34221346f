/* ego's tracking `pid` (ego.control.pid.PIDController) as an FMU: Fx from the longitudinal
 * error, delta from the lateral one. The PIDs are set up at the first step, when the
 * communication step (the control period) is known. */
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
    r[VR_Fx] = pid_step(lon, r[VR_s_ref] - r[VR_s], r[VR_ds_ref] - r[VR_ds]);
    r[VR_delta] = pid_step(lat, r[VR_d_ref] - r[VR_d], r[VR_dd_ref] - r[VR_dd]);
    r[VR_integral_lon] = lon->integral;
    r[VR_integral_lat] = lat->integral;
    return MODEL_OK;
}
