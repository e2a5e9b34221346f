/*
 * Native twins of ego's hottest numerical kernels.
 *
 *  - bicycle_step: report 000's nonlinear bicycle integrated by classical RK4, the same
 *    arithmetic, term for term, as NonlinearBicycle.rhs + ego.models.integrate.unrolled_rk4;
 *  - mamdani2: the closed-form Mamdani centroid of ego.control.fuzzy_engine for two inputs
 *    and one output (FastMamdani.single2);
 *  - fill_obs, observe, command, reward, reward_of and env_step: ego.gym's EgoState
 *    observation vector, continuous action and default reward (EgoStateObservation.observe,
 *    ContinuousAction.native, Reward.__call__), and EgoEnv._step for an env step that ends
 *    nothing, handing the rest to the Python step;
 *  - boxes and place: the surround sensor's reading of a SUMO step, as
 *    SumoBridge.surroundings (the context subscription's vehicles as boxes) and
 *    SurroundSensor.sync (each box placed in the lane frame) compute it;
 *  - bp_pid, bp_pid_acc and rbf_smc: the learning controllers' steps
 *    (BPPIDController._step_py, BPPIDAcc._update_py, RBFSMCController._network_py): their
 *    element-wise arithmetic here, numpy called for what numpy computes its own way (BLAS
 *    products, tanh, exp, einsum); sum_squares: numpy's pairwise sum of squares;
 *  - plant_step, trace_write and road_frame: the scenario loop's glue every control period
 *    (BicyclePlant.step, Trace.bind's writer, RoadSensor.frame) on the records they are
 *    bound to (FIELDS below), each handing what it does not cover to the Python code it
 *    stands for (look_between and plan_steady went back to Python: docs/performance.md);
 *  - near and nearest: the surround sensor's search at a look (SurroundSensor.scan's and
 *    _scan_lane's filter, _nearest).
 *
 * The Python implementations stay the references: the tests require these kernels to agree
 * with them (and with scikit-fuzzy) on random inputs, to the bit. Compiled with
 * -ffp-contract=off so the arithmetic is not fused differently from CPython's. When the
 * extension is missing, ego falls back to the Python code (slower, same results).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <string.h>

/* numpy's C API (its headers at build time, setup.py): new arrays and their data without the
 * buffer protocol, whose export costs as much as the rest of an env step's observation */
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>

#include "_bicycle.h"

/* ---- the records the glue kernels read and write -----------------------------------------
 * Each kernel takes its records as arguments (bound once a run) and reads or writes their
 * public fields, listed here by record: the Python class declares each (in ``__slots__``
 * where it has them, else in its ``__init__``) beside the Python reference the kernel stands
 * for. ``fields()`` gives this table; tests/test_native.py checks every field is declared by
 * its record, so a rename in Python fails that test instead of silently cutting a kernel off. */
static PyObject *s_state, *s_applied, *s_lateral_accel;                         /* plant */
static PyObject *s_road, *s_X, *s_Y, *s_s, *s_d_road, *s_heading_error, *s_curvature, *s_ds, *s_dd;
static PyObject *s_turn, *s_station;                                            /* view */
static PyObject *s_t;                                                           /* observation */
static PyObject *s_id, *s_gap, *s_speed, *s_accel, *s_gap0, *s_o, *s_lo_, *s_hi_, *s_since_, *s_d_; /* detection */
static PyObject *s_c_, *s_hint_, *s_at_, *s_mean_curvature;                    /* lane */
static PyObject *s_elapsed_, *s_bridge, *s_status, *s_step, *s_step_joint;    /* env, scenario */
static PyObject *s_rewards, *s_running, *str_empty, *float_zero, *float_inf;  /* values */

static const struct {
    const char *record;
    PyObject **slot;
    const char *name;
} FIELDS[] = {
    {"ego.models.plant.BicyclePlant", &s_state, "state"},
    {"ego.models.plant.BicyclePlant", &s_applied, "applied"},
    {"ego.models.plant.BicyclePlant", &s_lateral_accel, "lateral_accel"},
    {"ego.scenarios.road.RoadSensor", &s_road, "road"},
    {"ego.scenarios.road.RoadSensor", &s_X, "X"},
    {"ego.scenarios.road.RoadSensor", &s_Y, "Y"},
    {"ego.scenarios.road.RoadSensor", &s_s, "s"},
    {"ego.scenarios.road.RoadSensor", &s_d_road, "d_road"},
    {"ego.scenarios.road.RoadSensor", &s_heading_error, "heading_error"},
    {"ego.scenarios.road.RoadSensor", &s_curvature, "curvature"},
    {"ego.scenarios.road.RoadSensor", &s_ds, "ds"},
    {"ego.scenarios.road.RoadSensor", &s_dd, "dd"},
    {"ego.scenarios.road.RoadSensor", &s_turn, "turn"},
    {"ego.scenarios.road.RoadSensor", &s_station, "station"},
    {"ego.scenarios.sensor.Detection", &s_id, "id"},
    {"ego.scenarios.sensor.Detection", &s_gap, "gap"},
    {"ego.scenarios.sensor.Detection", &s_speed, "speed"},
    {"ego.scenarios.sensor.Detection", &s_accel, "accel"},
    {"ego.scenarios.sensor.Detection", &s_gap0, "gap0"},
    {"ego.scenarios.sensor.Detection", &s_o, "obj"},
    {"ego.scenarios.sensor.Detection", &s_lo_, "lo"},
    {"ego.scenarios.sensor.Detection", &s_hi_, "hi"},
    {"ego.scenarios.sensor.Detection", &s_since_, "since"},
    {"ego.scenarios.sensor.Detection", &s_d_, "line"},
    {"ego.lane_frame.LanePolyline", &s_c_, "packed"},
    {"ego.lane_frame.LanePolyline", &s_hint_, "hint"},
    {"ego.lane_frame.LanePolyline", &s_at_, "at"},
    {"ego.lane_frame.LanePolyline", &s_mean_curvature, "mean_curvature"},
    {"ego.lane_frame.LanePolyline", NULL, "place"},
    {"ego.gym.env.EgoEnv", &s_elapsed_, "elapsed"},
    {"ego.control.base.Observation", &s_t, "t"},
    {"ego.scenarios.base.Scenario", &s_bridge, "bridge"},
    {"ego.scenarios.base.Scenario", &s_status, "status"},
    {"ego.scenarios.base.Scenario", &s_step, "step"},
    {"ego.scenarios.base.Scenario", &s_step_joint, "step_joint"},
};

/* fields() -> ((record, field), ...): the table above */
static PyObject *fields(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    const Py_ssize_t n = (Py_ssize_t)(sizeof FIELDS / sizeof FIELDS[0]);
    PyObject *out = PyTuple_New(n);
    if (!out) return NULL;
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *pair = Py_BuildValue("(ss)", FIELDS[i].record, FIELDS[i].name);
        if (!pair) { Py_DECREF(out); return NULL; }
        PyTuple_SET_ITEM(out, i, pair);
    }
    return out;
}

static int intern_fields(void)
{
    for (size_t i = 0; i < sizeof FIELDS / sizeof FIELDS[0]; i++) {
        if (!FIELDS[i].slot || *FIELDS[i].slot) continue; /* a method called by name, or a field of two records */
        *FIELDS[i].slot = PyUnicode_InternFromString(FIELDS[i].name);
        if (!*FIELDS[i].slot) return -1;
    }
    s_rewards = PyUnicode_InternFromString("rewards");
    s_running = PyUnicode_InternFromString("running");
    str_empty = PyUnicode_InternFromString("");
    float_zero = PyFloat_FromDouble(0.0);
    float_inf = PyFloat_FromDouble(Py_HUGE_VAL);
    return s_rewards && s_running && str_empty && float_zero && float_inf ? 0 : -1;
}

static int read_doubles(PyObject *seq, double *out, Py_ssize_t n, const char *what)
{
    PyObject *fast = PySequence_Fast(seq, what);
    if (!fast) return -1;
    if (PySequence_Fast_GET_SIZE(fast) != n) {
        PyErr_Format(PyExc_ValueError, "%s must have %zd items", what, n);
        Py_DECREF(fast);
        return -1;
    }
    PyObject **items = PySequence_Fast_ITEMS(fast);
    for (Py_ssize_t i = 0; i < n; i++) {
        out[i] = PyFloat_AsDouble(items[i]);
        if (out[i] == -1.0 && PyErr_Occurred()) { Py_DECREF(fast); return -1; }
    }
    Py_DECREF(fast);
    return 0;
}

static const double *params_of(PyObject *obj, Py_ssize_t n, const char *what)
{
    if (!PyBytes_Check(obj) || PyBytes_GET_SIZE(obj) != (Py_ssize_t)(n * sizeof(double))) {
        PyErr_Format(PyExc_TypeError, "%s must be %zd packed doubles (bytes)", what, n);
        return NULL;
    }
    return (const double *)PyBytes_AS_STRING(obj);
}

/* bicycle_step(state, Fx, delta, h, substeps, params) -> (new_state, lateral_accel)
 * lateral_accel = dv/dt + u*r at the start of the step (what an accelerometer reads). */
static PyObject *bicycle_step(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    double x[NX], k1[NX];
    if (nargs != 6) {
        PyErr_SetString(PyExc_TypeError, "bicycle_step(state, Fx, delta, h, substeps, params)");
        return NULL;
    }
    if (read_doubles(args[0], x, NX, "state") < 0) return NULL;
    const double Fx = PyFloat_AsDouble(args[1]);
    const double delta = PyFloat_AsDouble(args[2]);
    const double h = PyFloat_AsDouble(args[3]);
    const long substeps = PyLong_AsLong(args[4]);
    if (PyErr_Occurred()) return NULL;
    const double *p = params_of(args[5], BIKE_NPARAM, "params");
    if (!p) return NULL;
    const double u0 = x[1], r0 = x[5];
    bike_rk4(p, x, Fx, delta, h, k1);
    for (long i = 1; i < substeps; i++) bike_rk4(p, x, Fx, delta, h, NULL);
    PyObject *state = PyTuple_New(NX);
    if (!state) return NULL;
    for (int i = 0; i < NX; i++) PyTuple_SET_ITEM(state, i, PyFloat_FromDouble(x[i]));
    PyObject *out = PyTuple_New(2);
    if (!out) { Py_DECREF(state); return NULL; }
    PyTuple_SET_ITEM(out, 0, state);
    PyTuple_SET_ITEM(out, 1, PyFloat_FromDouble(k1[3] + u0 * r0));
    return out;
}

/* ---------------------------------------------------------------------------------------
 * Two-input, one-output Mamdani (min-AND, min implication, max aggregation, centroid as
 * scikit-fuzzy computes it). The inputs x0, x1 come last so functools.partial can bind the
 * tables once. Tables are bytes objects of packed doubles / int32:
 * peaks0[n0], peaks1[n1], table[n0*n1] (int32 output term per rule), coef[nout*4]
 * (area/moment coefficients per output term), out_peaks[nout], grid[ngrid].
 * ------------------------------------------------------------------------------------- */
#define MAX_TERMS 64

static Py_ssize_t bisect_right(const double *a, Py_ssize_t n, double x)
{
    Py_ssize_t lo = 0, hi = n;
    while (lo < hi) {
        Py_ssize_t mid = (lo + hi) / 2;
        if (x < a[mid]) hi = mid; else lo = mid + 1;
    }
    return lo;
}

static void fuzzify(const double *peaks, Py_ssize_t n, double x, Py_ssize_t *k, double *upper)
{
    if (x <= peaks[0]) { *k = 0; *upper = 0.0; return; }
    if (x >= peaks[n - 1]) { *k = n - 1; *upper = 0.0; return; }
    Py_ssize_t i = bisect_right(peaks, n, x) - 1;
    *k = i;
    *upper = (x - peaks[i]) * (1.0 / (peaks[i + 1] - peaks[i]));
}

static double envelope(double a, double b, double s)
{
    const double left = a < 1.0 - s ? a : 1.0 - s;
    const double right = b < s ? b : s;
    return left > right ? left : right;
}

/* Overlap correction of neighbours j (cut a) and j+1 (cut b): FastMamdani._Output._pair */
static void pair(const double *peaks, const double *grid, Py_ssize_t ngrid, Py_ssize_t j,
                 double a, double b, double *area, double *moment)
{
    const double p = peaks[j], q = peaks[j + 1], w = q - p;
    const double m = a < b ? a : b;
    double ar = -w * (m >= 0.5 ? 0.25 : m - m * m);
    double mo = ar * 0.5 * (p + q);
    double s_star;
    if (a >= 0.5 && b >= 0.5) s_star = 0.5;
    else if (a > b) s_star = 1.0 - b;
    else if (a < b) s_star = a;
    else { *area += ar; *moment += mo; return; }
    const double x_star = p + s_star * w;
    Py_ssize_t i = bisect_right(grid, ngrid, x_star) - 1;
    double left = grid[i];
    if (left == x_star) { *area += ar; *moment += mo; return; }
    double right = grid[i + 1];
    const double cuts[2] = {q - a * w, p + b * w};
    for (int c = 0; c < 2; c++) {
        if (left < cuts[c] && cuts[c] < x_star) left = cuts[c];
        else if (x_star < cuts[c] && cuts[c] < right) right = cuts[c];
    }
    const double fl = envelope(a, b, (left - p) / w);
    const double fr = envelope(a, b, (right - p) / w);
    const double f_star = s_star <= 0.5 ? s_star : 1.0 - s_star;
    const double tri = 0.5 * ((x_star - left) * (fr - fl) - (right - left) * (f_star - fl));
    *area += ar + tri;
    *moment += mo + tri * (left + x_star + right) / 3.0;
}

static PyObject *mamdani2(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 8) {
        PyErr_SetString(PyExc_TypeError,
                        "mamdani2(peaks0, peaks1, table, coef, out_peaks, grid, x0, x1)");
        return NULL;
    }
    const double x0 = PyFloat_AsDouble(args[6]);
    const double x1 = PyFloat_AsDouble(args[7]);
    if (PyErr_Occurred()) return NULL;
    for (int i = 0; i < 6; i++) {
        if (!PyBytes_Check(args[i])) {
            PyErr_SetString(PyExc_TypeError, "mamdani2 tables must be bytes");
            return NULL;
        }
    }
    const double *p0 = (const double *)PyBytes_AS_STRING(args[0]);
    const Py_ssize_t n0 = PyBytes_GET_SIZE(args[0]) / (Py_ssize_t)sizeof(double);
    const double *p1 = (const double *)PyBytes_AS_STRING(args[1]);
    const Py_ssize_t n1 = PyBytes_GET_SIZE(args[1]) / (Py_ssize_t)sizeof(double);
    const int *table = (const int *)PyBytes_AS_STRING(args[2]);
    const double *coef = (const double *)PyBytes_AS_STRING(args[3]);
    const double *out_peaks = (const double *)PyBytes_AS_STRING(args[4]);
    const Py_ssize_t nout = PyBytes_GET_SIZE(args[4]) / (Py_ssize_t)sizeof(double);
    const double *grid = (const double *)PyBytes_AS_STRING(args[5]);
    const Py_ssize_t ngrid = PyBytes_GET_SIZE(args[5]) / (Py_ssize_t)sizeof(double);
    if (nout > MAX_TERMS || n0 < 2 || n1 < 2 || ngrid < 2 ||
        PyBytes_GET_SIZE(args[2]) != (Py_ssize_t)(n0 * n1 * sizeof(int))) {
        PyErr_SetString(PyExc_ValueError, "mamdani2: inconsistent tables");
        return NULL;
    }

    Py_ssize_t k0, k1;
    double b0, b1;
    fuzzify(p0, n0, x0, &k0, &b0);
    fuzzify(p1, n1, x1, &k1, &b1);
    const double a0 = 1.0 - b0, a1 = 1.0 - b1;

    double cuts[MAX_TERMS];
    for (Py_ssize_t j = 0; j < nout; j++) cuts[j] = 0.0;
#define FIRE(i, jj, w) do { int t_ = table[(i) * n1 + (jj)]; double w_ = (w); \
        if (w_ > cuts[t_]) cuts[t_] = w_; } while (0)
    FIRE(k0, k1, a0 < a1 ? a0 : a1);
    if (b1 > 0.0) FIRE(k0, k1 + 1, a0 < b1 ? a0 : b1);
    if (b0 > 0.0) {
        FIRE(k0 + 1, k1, b0 < a1 ? b0 : a1);
        if (b1 > 0.0) FIRE(k0 + 1, k1 + 1, b0 < b1 ? b0 : b1);
    }
#undef FIRE
    double area = 0.0, moment = 0.0;
    for (Py_ssize_t j = 0; j < nout; j++) {
        const double c = cuts[j];
        if (c <= 0.0) continue;
        const double *k = coef + 4 * j;
        area += k[0] * c * (1.0 - 0.5 * c);
        moment += c * (k[1] + c * (k[2] + c * k[3]));
        if (j + 1 < nout && cuts[j + 1] > 0.0)
            pair(out_peaks, grid, ngrid, j, c, cuts[j + 1], &area, &moment);
    }
    if (area <= 0.0) {
        PyErr_SetString(PyExc_ArithmeticError, "no rule fired: the aggregated membership is empty");
        return NULL;
    }
    return PyFloat_FromDouble(moment / area);
}


/* ---- the surround sensor's reading of a SUMO step ------------------------------------- */

static const double DEG_TO_RAD = 3.14159265358979323846 / 180.0; /* CPython's math.radians */
static PyObject *math_hypot = NULL;

static int as_double(PyObject *o, double *out)
{
    *out = PyFloat_AsDouble(o);
    return (*out == -1.0 && PyErr_Occurred()) ? -1 : 0;
}

/* boxes(results, controlled, known, dims, p_key, a_key, v_key) -> (ids, rows)
 * SumoBridge.surroundings: each vehicle of a context subscription's results not in
 * ``controlled``, as (centre x, y, yaw rad, speed, length, width); (length, width) from
 * ``known`` or dims(id). */
static PyObject *boxes(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 7 || !PyDict_Check(args[0]) || !PyDict_Check(args[2])) {
        PyErr_SetString(PyExc_TypeError, "boxes(results: dict, controlled, known: dict, dims, p_key, a_key, v_key)");
        return NULL;
    }
    PyObject *results = args[0], *controlled = args[1], *known = args[2], *dims = args[3];
    PyObject *p_key = args[4], *a_key = args[5], *v_key = args[6];
    PyObject *ids = PyList_New(0), *rows = PyList_New(0);
    if (!ids || !rows) goto fail;
    Py_ssize_t pos = 0;
    PyObject *other, *var;
    while (PyDict_Next(results, &pos, &other, &var)) {
        int skip = PySequence_Contains(controlled, other);
        if (skip < 0) goto fail;
        if (skip) continue;
        PyObject *xy = PyObject_GetItem(var, p_key);
        if (!xy) goto fail;
        double xf = 0.0, yf = 0.0, angle = 0.0;
        PyObject *fx = PySequence_GetItem(xy, 0), *fy = fx ? PySequence_GetItem(xy, 1) : NULL;
        Py_DECREF(xy);
        int bad = !fx || !fy || as_double(fx, &xf) || as_double(fy, &yf);
        Py_XDECREF(fx);
        Py_XDECREF(fy);
        if (bad) goto fail;
        PyObject *a = PyObject_GetItem(var, a_key);
        if (!a) goto fail;
        bad = as_double(a, &angle);
        Py_DECREF(a);
        if (bad) goto fail;
        PyObject *v = PyObject_GetItem(var, v_key);
        if (!v) goto fail;
        PyObject *lw = PyDict_GetItemWithError(known, other); /* borrowed */
        if (lw && !PyObject_IsTrue(lw)) lw = NULL;
        if (lw) Py_INCREF(lw);
        else if (PyErr_Occurred()) { Py_DECREF(v); goto fail; }
        else lw = PyObject_CallOneArg(dims, other);
        if (!lw) { Py_DECREF(v); goto fail; }
        PyObject *len_o = PySequence_GetItem(lw, 0), *wid_o = len_o ? PySequence_GetItem(lw, 1) : NULL;
        Py_DECREF(lw);
        double length;
        if (!len_o || !wid_o || as_double(len_o, &length)) {
            Py_XDECREF(len_o); Py_XDECREF(wid_o); Py_DECREF(v); goto fail;
        }
        const double psi = (90.0 - angle) * DEG_TO_RAD;
        const double half = 0.5 * length;
        PyObject *row = PyTuple_New(6);
        if (!row) { Py_DECREF(len_o); Py_DECREF(wid_o); Py_DECREF(v); goto fail; }
        PyTuple_SET_ITEM(row, 0, PyFloat_FromDouble(xf - half * cos(psi)));
        PyTuple_SET_ITEM(row, 1, PyFloat_FromDouble(yf - half * sin(psi)));
        PyTuple_SET_ITEM(row, 2, PyFloat_FromDouble(psi));
        PyTuple_SET_ITEM(row, 3, v);
        PyTuple_SET_ITEM(row, 4, len_o);
        PyTuple_SET_ITEM(row, 5, wid_o);
        if (!PyTuple_GET_ITEM(row, 0) || !PyTuple_GET_ITEM(row, 1) || !PyTuple_GET_ITEM(row, 2) ||
            PyList_Append(ids, other) || PyList_Append(rows, row)) {
            Py_DECREF(row);
            goto fail;
        }
        Py_DECREF(row);
    }
    return Py_BuildValue("(NN)", ids, rows);
fail:
    Py_XDECREF(ids);
    Py_XDECREF(rows);
    return NULL;
}

/* math.hypot(dx, dy) <= reach, decided without Python where the squares settle it */
static int within(double dx, double dy, double reach)
{
    const double d2 = dx * dx + dy * dy, r2 = reach * reach;
    if (d2 < r2 * (1.0 - 1e-9)) return 1;
    if (d2 > r2 * (1.0 + 1e-9)) return 0;
    PyObject *h = PyObject_CallFunction(math_hypot, "dd", dx, dy);
    if (!h) return -1;
    const double value = PyFloat_AsDouble(h);
    Py_DECREF(h);
    if (value == -1.0 && PyErr_Occurred()) return -1;
    return value <= reach;
}

/* ---- LanePolyline's projection on plain data (ego.lane_frame: _closest, locate, place) -----
 * A lane's ``packed`` = (segments, grid_x, grid_y, grid_seg): its segments as 11 doubles each
 * (x0, y0, ux, uy, length, s0, direction, heading at start, heading change, curvature, turn)
 * and its grid (cells of GRID m, sorted by (x, y), each with its one segment), built once per
 * lane; ``hint`` the segment the last projection found. The same arithmetic as the Python
 * methods, in the same order: Python's min/max (the first argument unless the second is
 * strictly beyond it, so NaN goes through as there). A point the Python method would raise
 * on (an infinite coordinate into math.floor, an infinite angle into math.fmod) is left to it. */
#define LANE_GRID 10.0
#define SEG_W 11

typedef struct {
    Py_buffer views[4];
    const double *seg;
    const long long *gx, *gy, *gs;
    Py_ssize_t n, ng;
} LaneData;

static double py_max(double a, double b) { return b > a ? b : a; }
static double py_min(double a, double b) { return b < a ? b : a; }

static void lane_release(LaneData *L)
{
    for (int k = 0; k < 4; k++) PyBuffer_Release(&L->views[k]);
}

/* 0 with L filled, -1 with an exception, 1 when ``lane`` has no packed data */
static int lane_acquire(PyObject *packed, LaneData *L)
{
    if (!PyTuple_Check(packed) || PyTuple_GET_SIZE(packed) != 4) return 1;
    int k;
    for (k = 0; k < 4; k++) {
        if (PyObject_GetBuffer(PyTuple_GET_ITEM(packed, k), &L->views[k], PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) break;
        const char *fmt = L->views[k].format;
        const int want_double = k == 0;
        if ((want_double && strcmp(fmt, "d") != 0) || (!want_double && strcmp(fmt, "q") != 0)) {
            PyBuffer_Release(&L->views[k]);
            PyErr_SetString(PyExc_TypeError, "a lane's packed must be (array('d'), array('q') x 3)");
            break;
        }
    }
    if (k < 4) {
        while (k-- > 0) PyBuffer_Release(&L->views[k]);
        return -1;
    }
    L->seg = (const double *)L->views[0].buf;
    L->n = L->views[0].len / (Py_ssize_t)(SEG_W * sizeof(double));
    L->gx = (const long long *)L->views[1].buf;
    L->gy = (const long long *)L->views[2].buf;
    L->gs = (const long long *)L->views[3].buf;
    L->ng = L->views[1].len / (Py_ssize_t)sizeof(long long);
    if (L->n < 1 || L->views[2].len != L->views[1].len || L->views[3].len != L->views[1].len) {
        lane_release(L);
        PyErr_SetString(PyExc_ValueError, "a lane's packed is inconsistent");
        return -1;
    }
    return 0;
}

/* lane_acquire on lane.packed (a LanePolyline's): 0 with L filled, -1 with an exception, 1 when
 * its packed data is not the four arrays */
static int lane_packed(PyObject *lane, LaneData *L)
{
    PyObject *packed = PyObject_GetAttr(lane, s_c_);
    if (!packed) return -1;
    const int got = lane_acquire(packed, L);
    Py_DECREF(packed);
    return got;
}

/* LanePolyline._local */
static void lane_local(const LaneData *L, Py_ssize_t i, double x, double y, double *out)
{
    const double *sg = L->seg + i * SEG_W;
    const double x0 = sg[0], y0 = sg[1], ux = sg[2], uy = sg[3], length = sg[4];
    const double dx = x - x0, dy = y - y0;
    const double along = dx * ux + dy * uy;
    const double across = uy * -dx + ux * dy;
    out[0] = along;
    out[1] = across;
    if (along < 0.0) {
        out[2] = dx * dx + dy * dy;
    } else if (along > length) {
        const double ex = dx - length * ux, ey = dy - length * uy;
        out[2] = ex * ex + ey * ey;
    } else {
        out[2] = across * across;
    }
}

/* the grid's segment of cell (cx, cy), or -1 */
static long long lane_cell(const LaneData *L, long long cx, long long cy)
{
    Py_ssize_t lo = 0, hi = L->ng;
    while (lo < hi) {
        const Py_ssize_t mid = (lo + hi) / 2;
        if (L->gx[mid] < cx || (L->gx[mid] == cx && L->gy[mid] < cy)) lo = mid + 1;
        else hi = mid;
    }
    return (lo < L->ng && L->gx[lo] == cx && L->gy[lo] == cy) ? L->gs[lo] : -1;
}

/* LanePolyline._closest from segment *hint (updated): 0, or 1 where the Python method
 * must decide (it raises there) */
static int lane_closest(const LaneData *L, Py_ssize_t *hint, double x, double y, Py_ssize_t *seg_i, double *along,
                        double *across)
{
    const Py_ssize_t n = L->n;
    Py_ssize_t i = *hint;
    if (i < 0 || i >= n) return 1;
    double best[3], cand[3];
    lane_local(L, i, x, y, best);
    if (best[2] > LANE_GRID * LANE_GRID) {
        const double fx = floor(x / LANE_GRID), fy = floor(y / LANE_GRID);
        if (!isfinite(fx) || !isfinite(fy) || fabs(fx) > 1e15 || fabs(fy) > 1e15) return 1;
        const long long cx = (long long)fx, cy = (long long)fy;
        const long long own = lane_cell(L, cx, cy);
        for (int a = -1; a <= 1; a++) {
            for (int b = -1; b <= 1; b++) {
                long long j;
                if (own >= 0) {
                    if (a != 0 || b != 0) continue;
                    j = own;
                } else {
                    j = lane_cell(L, cx + a, cy + b);
                    if (j < 0) continue;
                }
                lane_local(L, (Py_ssize_t)j, x, y, cand);
                if (cand[2] < best[2]) {
                    i = (Py_ssize_t)j;
                    best[0] = cand[0], best[1] = cand[1], best[2] = cand[2];
                }
            }
        }
    }
    for (int step = 1; step >= -1; step -= 2) {
        Py_ssize_t j = i + step;
        while (0 <= j && j < n) {
            lane_local(L, j, x, y, cand);
            if (cand[2] < best[2]) {
                i = j;
                best[0] = cand[0], best[1] = cand[1], best[2] = cand[2];
                j += step;
            } else {
                break;
            }
        }
    }
    *hint = i;
    double a = best[0];
    const double length = L->seg[i * SEG_W + 4];
    if (0 < i && a < 0.0) a = 0.0;
    if (i < n - 1 && a > length) a = length;
    *seg_i = i;
    *along = a;
    *across = best[1];
    return 0;
}

/* lane_frame.wrap_angle of a finite angle */
static double wrap_finite(double a)
{
    a = fmod(a + Py_MATH_PI, 2.0 * Py_MATH_PI);
    if (a <= 0.0) a += 2.0 * Py_MATH_PI;
    return a - Py_MATH_PI;
}

/* LanePolyline.locate: out = (s, d, heading error, curvature, turn, station); 0, or 1 where
 * the Python method must decide; *hint updated only on 0 */
static int lane_locate(const LaneData *L, Py_ssize_t *hint, double x, double y, double psi, double *out)
{
    Py_ssize_t i, h = *hint;
    double along, across;
    if (lane_closest(L, &h, x, y, &i, &along, &across)) return 1;
    const double *sg = L->seg + i * SEG_W;
    const double length = sg[4];
    const double u = py_min(py_max(along, 0.0), length);
    const double kappa = sg[9];
    const double d = across + kappa * u * (length - u) * 0.5;
    const double frac = u / length;
    const double s = sg[5] + along;
    double station = s;
    if (kappa != 0.0) {
        const double q = 1.0 - kappa * d;
        if (q > 0.5) {
            const double half = 0.5 * length;
            const double raw = (x - sg[0]) * sg[2] + (y - sg[1]) * sg[3];
            station = sg[5] + half + (raw - half) / q;
        }
    }
    const double err = psi - sg[7] - frac * sg[8];
    if (isinf(err)) return 1; /* math.fmod raises there */
    out[0] = s;
    out[1] = d;
    out[2] = wrap_finite(err);
    out[3] = kappa;
    out[4] = sg[10] + frac * sg[8];
    out[5] = station;
    *hint = h;
    return 0;
}

/* lane_mean_curvature(lane, s, ahead) -> float: LanePolyline.mean_curvature on the lane's
 * packed data (packed) and its remembered segments (at, a list of two ints), the same
 * arithmetic; an infinite angle (math.fmod raises) or a lane without packed data: the
 * Python method */
static Py_ssize_t lane_segment_at(const LaneData *L, Py_ssize_t i, double s)
{
    const Py_ssize_t last = L->n - 1;
    const double *sg = L->seg;
#define S0(k) sg[(k) * SEG_W + 5]
    if (i < 0 || i > last) i = 0; /* (Python would raise on a bad index: never made) */
    if (S0(i) <= s && (i == last || s < S0(i + 1))) return i;
    if (i < last && S0(i + 1) <= s && (i + 1 == last || s < S0(i + 2))) return i + 1;
    Py_ssize_t lo = 0, hi = last;
    while (lo < hi) {
        const Py_ssize_t mid = (lo + hi + 1) / 2;
        if (S0(mid) <= s) lo = mid;
        else hi = mid - 1;
    }
#undef S0
    return lo;
}

static double lane_heading_raw(const LaneData *L, Py_ssize_t i, double s)
{
    const double *sg = L->seg + i * SEG_W;
    const double t = py_min(py_max((s - sg[5]) / sg[4], 0.0), 1.0);
    return sg[7] + t * sg[8];
}


static PyObject *lane_mean_curvature(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 3) {
        PyErr_SetString(PyExc_TypeError, "lane_mean_curvature(lane, s, ahead)");
        return NULL;
    }
    PyObject *lane = args[0];
    const double s = PyFloat_AsDouble(args[1]), ahead = PyFloat_AsDouble(args[2]);
    if (PyErr_Occurred()) return NULL;
    LaneData L;
    const int got = lane_packed(lane, &L);
    if (got < 0) return NULL;
    PyObject *at = got == 0 ? PyObject_GetAttr(lane, s_at_) : NULL;
    if (got > 0 || (at && !(PyList_CheckExact(at) && PyList_GET_SIZE(at) == 2))) {
        Py_XDECREF(at);
        if (got == 0) lane_release(&L);
        return PyObject_CallMethodObjArgs(lane, s_mean_curvature, args[1], args[2], NULL);
    }
    if (!at) { lane_release(&L); return NULL; }
    Py_ssize_t slot[2];
    for (int k = 0; k < 2; k++) {
        slot[k] = PyLong_AsSsize_t(PyList_GET_ITEM(at, k));
        if (slot[k] == -1 && PyErr_Occurred()) { Py_DECREF(at); lane_release(&L); return NULL; }
    }
    double result;
    Py_ssize_t i0 = slot[0], i1 = slot[1];
    if (ahead <= 0.0) { /* curvature_at(s), slot 0 */
        i0 = lane_segment_at(&L, slot[0], s);
        result = L.seg[i0 * SEG_W + 9];
    } else { /* NaN included, as in the Python method */
        i1 = lane_segment_at(&L, slot[1], s + ahead);
        i0 = lane_segment_at(&L, slot[0], s);
        const double a = lane_heading_raw(&L, i1, s + ahead), b = lane_heading_raw(&L, i0, s);
        if (isinf(a) || isinf(b)) goto python;
        result = wrap_finite(wrap_finite(a) - wrap_finite(b)) / ahead;
    }
    lane_release(&L);
    for (int k = 0; k < 2; k++) {
        const Py_ssize_t v = k ? i1 : i0;
        if (v == slot[k]) continue;
        PyObject *o = PyLong_FromSsize_t(v);
        if (!o || PyList_SetItem(at, k, o) < 0) { Py_DECREF(at); return NULL; } /* steals o */
    }
    Py_DECREF(at);
    return PyFloat_FromDouble(result);
python:
    lane_release(&L);
    Py_DECREF(at);
    return PyObject_CallMethodObjArgs(lane, s_mean_curvature, args[1], args[2], NULL);
}

/* place(ids, rows, front, reach, straight, frame, previous, dt, rated, low_edge)
 *   -> (ids, rows, objects, speeds)
 * SurroundSensor.sync after SurroundView.sense's range filter: the vehicles within ``reach``
 * of ``front`` (x, y) (all when ``front`` is None), each placed in the lane frame (the
 * rotation ``straight`` = (x0, y0, ux, uy, s0, heading), or frame(x, y, yaw) -> (s, d, rel,
 * _) or, LanePolyline.place, (s, d, rel, turn, kappa)), as (id, s_lo, s_hi, d_lo, d_hi, v_s,
 * v_d, accel, rel[, turn, kappa]), sorted by s_lo (stable); speeds: id -> v_s. */
static PyObject *place(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 10 || !PyList_Check(args[0]) || !PyList_Check(args[1]) || !PyDict_Check(args[6])) {
        PyErr_SetString(PyExc_TypeError,
                        "place(ids: list, rows: list, front, reach, straight, frame, previous: dict, dt, rated, low_edge)");
        return NULL;
    }
    PyObject *ids = args[0], *rows = args[1], *front = args[2], *straight = args[4], *frame = args[5];
    PyObject *previous = args[6], *low_edge = args[9];
    const Py_ssize_t n = PyList_GET_SIZE(ids);
    if (PyList_GET_SIZE(rows) != n) {
        PyErr_SetString(PyExc_ValueError, "place: ids and rows differ in length");
        return NULL;
    }
    double reach, dt, bumper[2] = {0.0, 0.0}, st[6] = {0, 0, 0, 0, 0, 0};
    if (as_double(args[3], &reach) || as_double(args[7], &dt)) return NULL;
    const int rated = PyObject_IsTrue(args[8]);
    if (rated < 0) return NULL;
    const int filter = front != Py_None;
    if (filter && read_doubles(front, bumper, 2, "front")) return NULL;
    const int rotation = straight != Py_None;
    if (rotation && read_doubles(straight, st, 6, "straight")) return NULL;
    /* a lane with packed data (LanePolyline): its place, on that data, from its _hint */
    LaneData L;
    int packed_lane = 0;
    Py_ssize_t hint = 0;
    if (!rotation && !PyCallable_Check(frame)) {
        const int got = lane_packed(frame, &L);
        if (got != 0) {
            if (got > 0) PyErr_SetString(PyExc_TypeError, "place: a lane without packed data");
            return NULL;
        }
        PyObject *h = PyObject_GetAttr(frame, s_hint_);
        hint = h ? PyLong_AsSsize_t(h) : -1;
        Py_XDECREF(h);
        if (hint == -1 && (!h || PyErr_Occurred())) { lane_release(&L); return NULL; }
        packed_lane = 1;
    }

    PyObject *near_ids = filter ? PyList_New(0) : (Py_INCREF(ids), ids);
    PyObject *near_rows = filter ? PyList_New(0) : (Py_INCREF(rows), rows);
    PyObject *objects = PyList_New(0), *speeds = PyDict_New();
    double *keys = NULL;
    if (!near_ids || !near_rows || !objects || !speeds) goto fail;
    int sortable = 1;
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *vid = PyList_GET_ITEM(ids, i), *row = PyList_GET_ITEM(rows, i);
        double r[6];
        if (read_doubles(row, r, 6, "row")) goto fail;
        if (filter) {
            int in = within(r[0] - bumper[0], r[1] - bumper[1], reach);
            if (in < 0) goto fail;
            if (!in) continue;
            if (PyList_Append(near_ids, vid) || PyList_Append(near_rows, row)) goto fail;
        }
        const double x = r[0], y = r[1], yaw = r[2], v = r[3], length = r[4], width = r[5];
        double s, d, rel, bend[2] = {0.0, 0.0}, fl[6];
        int bent = 0;
        if (rotation) {
            const double dx = x - st[0], dy = y - st[1];
            s = st[4] + dx * st[2] + dy * st[3];
            d = dy * st[2] - dx * st[3];
            rel = yaw - st[5];
        } else if (packed_lane && lane_locate(&L, &hint, x, y, yaw, fl) == 0) {
            s = fl[5];
            d = fl[1];
            rel = fl[2];
            bend[0] = fl[4];
            bend[1] = fl[3];
            bent = 1;
        } else {
            PyObject *placed = NULL;
            if (packed_lane) { /* the Python method decides (it raises) from the same hint */
                PyObject *h = PyLong_FromSsize_t(hint);
                if (!h || PyObject_SetAttr(frame, s_hint_, h) < 0) { Py_XDECREF(h); goto fail; }
                Py_DECREF(h);
                placed = PyObject_CallMethod(frame, "place", "ddd", x, y, yaw) /* LanePolyline.place */;
            } else {
                placed = PyObject_CallFunction(frame, "ddd", x, y, yaw);
            }
            if (!placed) goto fail;
            if (packed_lane) { /* where the Python method left the hint */
                PyObject *h = PyObject_GetAttr(frame, s_hint_);
                hint = h ? PyLong_AsSsize_t(h) : -1;
                Py_XDECREF(h);
                if (hint == -1 && (!h || PyErr_Occurred())) { Py_DECREF(placed); goto fail; }
            }
            double f[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
            bent = PyTuple_Check(placed) && PyTuple_GET_SIZE(placed) == 5;
            int bad = read_doubles(placed, f, bent ? 5 : 4, "frame's result");
            Py_DECREF(placed);
            if (bad) goto fail;
            s = f[0];
            d = f[1];
            rel = f[2];
            bend[0] = f[3];
            bend[1] = f[4];
        }
        const double c = cos(rel), sn = sin(rel), ac = fabs(c), asn = fabs(sn);
        const double hs = 0.5 * (length * ac + width * asn);
        const double hd = 0.5 * (length * asn + width * ac);
        const double vs = v * c;
        double accel = 0.0;
        PyObject *prev = PyDict_GetItemWithError(previous, vid); /* borrowed */
        if (prev && rated) {
            double p;
            if (as_double(prev, &p)) goto fail;
            accel = (vs - p) / dt;
        } else if (!prev && PyErr_Occurred()) goto fail;
        PyObject *vs_o = PyFloat_FromDouble(vs);
        if (!vs_o) goto fail;
        if (PyDict_SetItem(speeds, vid, vs_o)) { Py_DECREF(vs_o); goto fail; }
        const int width_of = bent ? 11 : 9;
        PyObject *full = PyTuple_New(width_of);
        if (!full) { Py_DECREF(vs_o); goto fail; }
        Py_INCREF(vid);
        PyTuple_SET_ITEM(full, 0, vid);
        PyTuple_SET_ITEM(full, 1, PyFloat_FromDouble(s - hs));
        PyTuple_SET_ITEM(full, 2, PyFloat_FromDouble(s + hs));
        PyTuple_SET_ITEM(full, 3, PyFloat_FromDouble(d - hd));
        PyTuple_SET_ITEM(full, 4, PyFloat_FromDouble(d + hd));
        PyTuple_SET_ITEM(full, 5, vs_o); /* the reference made above, now the tuple's */
        PyTuple_SET_ITEM(full, 6, PyFloat_FromDouble(v * sn));
        PyTuple_SET_ITEM(full, 7, PyFloat_FromDouble(accel));
        PyTuple_SET_ITEM(full, 8, PyFloat_FromDouble(rel));
        if (bent) {
            PyTuple_SET_ITEM(full, 9, PyFloat_FromDouble(bend[0]));
            PyTuple_SET_ITEM(full, 10, PyFloat_FromDouble(bend[1]));
        }
        for (int k = 1; k < width_of; k++) {
            if (!PyTuple_GET_ITEM(full, k)) { Py_DECREF(full); goto fail; }
        }
        if (s - hs != s - hs) sortable = 0; /* a NaN edge: Python's own sort decides */
        int bad = PyList_Append(objects, full);
        Py_DECREF(full);
        if (bad) goto fail;
    }
    /* stable sort by s_lo: an insertion sort, moving an object left past strictly larger keys */
    const Py_ssize_t m = PyList_GET_SIZE(objects);
    if (sortable && m > 1) {
        keys = PyMem_Malloc((size_t)m * sizeof(double));
        if (!keys) { PyErr_NoMemory(); goto fail; }
        PyObject **items = ((PyListObject *)objects)->ob_item;
        for (Py_ssize_t i = 0; i < m; i++) keys[i] = PyFloat_AS_DOUBLE(PyTuple_GET_ITEM(items[i], 1));
        for (Py_ssize_t i = 1; i < m; i++) {
            const double key = keys[i];
            PyObject *item = items[i];
            Py_ssize_t j = i;
            while (j > 0 && key < keys[j - 1]) {
                keys[j] = keys[j - 1];
                items[j] = items[j - 1];
                j--;
            }
            keys[j] = key;
            items[j] = item;
        }
        PyMem_Free(keys);
        keys = NULL;
    } else if (m > 1) {
        PyObject *sort = PyObject_GetAttrString(objects, "sort");
        PyObject *kw = sort ? Py_BuildValue("{s:O}", "key", low_edge) : NULL;
        PyObject *empty = kw ? PyTuple_New(0) : NULL;
        PyObject *none = empty ? PyObject_Call(sort, empty, kw) : NULL;
        Py_XDECREF(sort);
        Py_XDECREF(kw);
        Py_XDECREF(empty);
        if (!none) goto fail;
        Py_DECREF(none);
    }
    if (packed_lane) {
        lane_release(&L);
        packed_lane = 0;
        PyObject *h = PyLong_FromSsize_t(hint);
        if (!h || PyObject_SetAttr(frame, s_hint_, h) < 0) { Py_XDECREF(h); goto fail; }
        Py_DECREF(h);
    }
    return Py_BuildValue("(NNNN)", near_ids, near_rows, objects, speeds);
fail:
    if (packed_lane) lane_release(&L);
    PyMem_Free(keys);
    Py_XDECREF(near_ids);
    Py_XDECREF(near_rows);
    Py_XDECREF(objects);
    Py_XDECREF(speeds);
    return NULL;
}

/* ---- the EgoState observation of ego.gym ------------------------------------------------ */

static int value_of(PyObject *o, double *out)
{
    if (o == Py_None) { *out = NAN; return 0; } /* as np.array(..., float64) reads None */
    return as_double(o, out);
}

/* the fields of fill_obs into out[0 .. n + m) (n = len(values), m = len(cst)); source not
 * NULL: values is a tuple of attribute names, each field read from source */
static int fill_fields(double *out, PyObject *values, PyObject *source, PyObject *norm, PyObject *cst)
{
    const Py_ssize_t n = PyTuple_GET_SIZE(values), m = PySequence_Fast_GET_SIZE(cst);
    for (Py_ssize_t i = 0; i < n; i++) {
        if (!source) {
            if (value_of(PyTuple_GET_ITEM(values, i), out + i)) return -1;
            continue;
        }
        PyObject *v = PyObject_GetAttr(source, PyTuple_GET_ITEM(values, i));
        const int bad = !v || value_of(v, out + i);
        Py_XDECREF(v);
        if (bad) return -1;
    }
    if (norm != Py_None) {
        double p[8];
        if (read_doubles(norm, p, 8, "norm")) return -1;
        const Py_ssize_t t = (Py_ssize_t)p[0], si = (Py_ssize_t)p[2], ri = (Py_ssize_t)p[3];
        if (t < 0 || t >= n || si >= n || ri >= n || (si >= 0 && p[4] != 0.0 && ri < 0)) {
            PyErr_SetString(PyExc_ValueError, "fill_obs: norm's indices out of range");
            return -1;
        }
        out[t] *= p[1];
        if (si >= 0) {
            if (p[4] != 0.0) { /* tracks: the station error, the reference since the reset */
                out[si] -= out[ri];
                out[ri] = (out[ri] - p[5]) * p[7];
            } else {
                out[si] = (out[si] - p[6]) * p[7];
            }
        }
    }
    PyObject **items = PySequence_Fast_ITEMS(cst);
    for (Py_ssize_t i = 0; i < m; i++)
        if (value_of(items[i], out + n + i)) return -1;
    return 0;
}

/* an ndarray's own float64 data to write in place (C-contiguous, aligned, writable, native
 * byte order), or NULL for anything else */
static double *own_doubles(PyObject *o)
{
    if (!PyArray_Check(o)) return NULL;
    PyArrayObject *a = (PyArrayObject *)o;
    if (PyArray_TYPE(a) != NPY_DOUBLE || !PyArray_ISCARRAY(a) || !PyArray_ISNOTSWAPPED(a)) return NULL;
    return (double *)PyArray_DATA(a);
}

/* fill_obs(out, values, norm, const) -> None
 * EgoStateObservation.observe into ``out`` (a writable float64 buffer of len(values) +
 * len(const)): ``values`` the fields read this step, normalised by ``norm`` = (t, per_duration,
 * s, s_ref, tracks, s_ref0, s0, per_distance) (s, s_ref: indices, -1 for none) or None, then
 * ``const``, the fields that hold still over a run. */
static PyObject *fill_obs(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 4 || !PyTuple_Check(args[1])) {
        PyErr_SetString(PyExc_TypeError, "fill_obs(out, values: tuple, norm, const)");
        return NULL;
    }
    PyObject *cst = PySequence_Fast(args[3], "fill_obs: const must be a sequence");
    if (!cst) return NULL;
    const Py_ssize_t size = PyTuple_GET_SIZE(args[1]) + PySequence_Fast_GET_SIZE(cst);
    Py_buffer view;
    view.obj = NULL;
    double *out = own_doubles(args[0]);
    Py_ssize_t len = out ? PyArray_NBYTES((PyArrayObject *)args[0]) : 0;
    if (!out) {
        if (PyObject_GetBuffer(args[0], &view, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0) {
            Py_DECREF(cst);
            return NULL;
        }
        out = (double *)view.buf;
        len = view.len;
    }
    PyObject *result = NULL;
    if (len != size * (Py_ssize_t)sizeof(double))
        PyErr_Format(PyExc_ValueError, "fill_obs: out holds %zd bytes, the fields %zd", len,
                     size * (Py_ssize_t)sizeof(double));
    else if (fill_fields(out, args[1], NULL, args[2], cst) == 0)
        result = Py_NewRef(Py_None);
    if (view.obj) PyBuffer_Release(&view);
    Py_DECREF(cst);
    return result;
}

/* observe(size, get, source, norm, const) -> array
 * EgoStateObservation.observe in one call (an env step's hot path): a new float64 array of
 * ``size`` (what numpy.empty(size) gives) filled as fill_obs(out, get(source), norm, const);
 * ``get`` a tuple of attribute names (str) reads those attributes of source, as
 * operator.attrgetter(*get) would, without building the tuple. */
static PyObject *observe(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 5) {
        PyErr_SetString(PyExc_TypeError, "observe(size, get, source, norm, const)");
        return NULL;
    }
    npy_intp dims[1];
    dims[0] = PyLong_AsSsize_t(args[0]);
    if (dims[0] < 0) {
        if (!PyErr_Occurred()) PyErr_SetString(PyExc_ValueError, "observe: size must be >= 0");
        return NULL;
    }
    PyObject *cst = PySequence_Fast(args[4], "observe: const must be a sequence");
    if (!cst) return NULL;
    const int names = PyTuple_Check(args[1]);
    PyObject *values = names ? Py_NewRef(args[1]) : PyObject_CallOneArg(args[1], args[2]);
    PyObject *out = NULL;
    if (!values) goto done;
    if (!PyTuple_Check(values) || PyTuple_GET_SIZE(values) + PySequence_Fast_GET_SIZE(cst) != dims[0]) {
        PyErr_SetString(PyExc_ValueError, "observe: get(source) must give a tuple of size - len(const) fields");
        goto done;
    }
    out = PyArray_SimpleNew(1, dims, NPY_DOUBLE);
    if (out && fill_fields((double *)PyArray_DATA((PyArrayObject *)out), values, names ? args[2] : NULL, args[3], cst))
        Py_CLEAR(out);
done:
    Py_XDECREF(values);
    Py_DECREF(cst);
    return out;
}

/* command(params, action) -> (longitudinal, lateral)
 * ego.gym's continuous action types' native() for an env step: params = (fallback, n,
 * scaled, longitudinal, clip, mid0, half0, mid1, half1, force_per_accel). A 1-D buffer of n
 * float32 or float64 values (a numpy array of the space's shape) gives the command: scaled,
 * each driven channel's mid + half * x (x clipped to [-1, 1] first when clip; NaN passes),
 * the longitudinal one times force_per_accel; else the values as they are; a channel not
 * driven is None. Anything else is fallback(action): the Python reference, its checks and
 * its messages. */
static PyObject *command(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 2 || !PyTuple_Check(args[0]) || PyTuple_GET_SIZE(args[0]) != 10) {
        PyErr_SetString(PyExc_TypeError, "command(params: 10-tuple, action)");
        return NULL;
    }
    PyObject *p = args[0], *action = args[1];
    PyObject *fallback = PyTuple_GET_ITEM(p, 0);
    const long n = PyLong_AsLong(PyTuple_GET_ITEM(p, 1));
    const int scaled = PyObject_IsTrue(PyTuple_GET_ITEM(p, 2));
    const int lon = PyObject_IsTrue(PyTuple_GET_ITEM(p, 3));
    const int clip = PyObject_IsTrue(PyTuple_GET_ITEM(p, 4));
    double c[5];
    for (int i = 0; i < 5; i++)
        if (as_double(PyTuple_GET_ITEM(p, 5 + i), c + i)) return NULL;
    if (PyErr_Occurred() || scaled < 0 || lon < 0 || clip < 0) return NULL;
    if (n != 1 && n != 2) {
        PyErr_SetString(PyExc_ValueError, "command: n must be 1 or 2");
        return NULL;
    }
    double x[2];
    if (PyArray_Check(action)) { /* an ndarray: its data read directly */
        PyArrayObject *a = (PyArrayObject *)action;
        const int type = PyArray_TYPE(a);
        if (PyArray_NDIM(a) != 1 || PyArray_DIM(a, 0) != n || !(type == NPY_FLOAT || type == NPY_DOUBLE) ||
            !PyArray_ISNOTSWAPPED(a))
            return PyObject_CallOneArg(fallback, action);
        const char *data = PyArray_BYTES(a);
        const npy_intp stride = PyArray_STRIDE(a, 0);
        for (long i = 0; i < n; i++) {
            if (type == NPY_FLOAT) {
                float v;
                memcpy(&v, data + i * stride, sizeof v);
                x[i] = (double)v;
            } else {
                memcpy(x + i, data + i * stride, sizeof(double));
            }
        }
    } else { /* another buffer: its format read */
        Py_buffer view;
        if (!PyObject_CheckBuffer(action) || PyObject_GetBuffer(action, &view, PyBUF_RECORDS_RO) < 0) {
            PyErr_Clear();
            return PyObject_CallOneArg(fallback, action);
        }
        const char *fmt = view.format;
        const int f32 = fmt && strcmp(fmt, "f") == 0, f64 = fmt && strcmp(fmt, "d") == 0;
        if (view.ndim != 1 || view.shape[0] != n || !(f32 || f64)) {
            PyBuffer_Release(&view);
            return PyObject_CallOneArg(fallback, action);
        }
        for (long i = 0; i < n; i++) {
            const char *at = (const char *)view.buf + i * view.strides[0];
            x[i] = f32 ? (double)*(const float *)at : *(const double *)at;
        }
        PyBuffer_Release(&view);
    }
    if (scaled) {
        for (long i = 0; i < n; i++) {
            if (clip && isfinite(x[i])) x[i] = x[i] < -1.0 ? -1.0 : (x[i] > 1.0 ? 1.0 : x[i]); /* NaN, inf: the env ends the run */
            x[i] = c[2 * i] + c[2 * i + 1] * x[i];
        }
    }
    PyObject *out = PyTuple_New(2), *first, *second;
    if (!out) return NULL;
    if (n == 2) {
        first = PyFloat_FromDouble(scaled ? x[0] * c[4] : x[0]);
        second = PyFloat_FromDouble(x[1]);
    } else if (lon) {
        first = PyFloat_FromDouble(scaled ? x[0] * c[4] : x[0]);
        second = Py_NewRef(Py_None);
    } else {
        first = Py_NewRef(Py_None);
        second = PyFloat_FromDouble(x[0]);
    }
    PyTuple_SET_ITEM(out, 0, first);
    PyTuple_SET_ITEM(out, 1, second);
    if (!first || !second) Py_CLEAR(out);
    return out;
}

/* reward(speed, error, a_lon, a_lat, crashed, params) -> (reward, terms)
 * ego.gym.env.Reward.__call__'s arithmetic: params = (lo, per_speed, cost, per_accel2,
 * w_crash, w_progress, w_centring, w_comfort); terms = {"crashed", "progress", "centring",
 * "discomfort"}; a non-finite term counts 0 in the reward (a diverged ego's signals). */
static PyObject *key_crashed, *key_progress, *key_centring, *key_discomfort;

/* reward's arithmetic: the reward into *r, the terms dict returned (NULL on error) */
static PyObject *reward_terms(double speed, double error, double a_lon, double a_lat, int crashed, const double *p,
                              double *r)
{
    double progress = (speed - p[0]) * p[1];
    progress = progress < 0.0 ? 0.0 : (progress > 1.0 ? 1.0 : progress);
    double centring = 1.0 / (1.0 + p[2] * error * error);
    double discomfort = (a_lon * a_lon + a_lat * a_lat) * p[3];
    if (discomfort > 1.0) discomfort = 1.0;
    const double crash = crashed ? 1.0 : 0.0;
    *r = p[4] * crash + p[5] * progress + p[6] * centring + p[7] * discomfort;
    if (*r - *r != 0.0) {
        if (!isfinite(progress)) progress = 0.0;
        if (!isfinite(centring)) centring = 0.0;
        if (!isfinite(discomfort)) discomfort = 0.0;
        *r = p[4] * crash + p[5] * progress + p[6] * centring + p[7] * discomfort;
    }
    PyObject *terms = PyDict_New();
    if (!terms) return NULL;
    const double values[4] = {crash, progress, centring, discomfort};
    PyObject *keys[4] = {key_crashed, key_progress, key_centring, key_discomfort};
    for (int k = 0; k < 4; k++) {
        PyObject *v = PyFloat_FromDouble(values[k]);
        if (!v || PyDict_SetItem(terms, keys[k], v)) {
            Py_XDECREF(v);
            Py_DECREF(terms);
            return NULL;
        }
        Py_DECREF(v);
    }
    return terms;
}

/* (reward, terms) as a new tuple; terms stolen (NULL: an error already set) */
static PyObject *reward_pair(double r, PyObject *terms)
{
    if (!terms) return NULL;
    PyObject *out = PyTuple_New(2), *value = out ? PyFloat_FromDouble(r) : NULL;
    if (!value) {
        Py_XDECREF(out);
        Py_DECREF(terms);
        return NULL;
    }
    PyTuple_SET_ITEM(out, 0, value);
    PyTuple_SET_ITEM(out, 1, terms);
    return out;
}

static PyObject *reward(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 6) {
        PyErr_SetString(PyExc_TypeError, "reward(speed, error, a_lon, a_lat, crashed, params)");
        return NULL;
    }
    double speed, error, a_lon, a_lat, p[8], r;
    if (as_double(args[0], &speed) || as_double(args[1], &error) || as_double(args[2], &a_lon) ||
        as_double(args[3], &a_lat) || read_doubles(args[5], p, 8, "params"))
        return NULL;
    const int crashed = PyObject_IsTrue(args[4]);
    if (crashed < 0) return NULL;
    return reward_pair(r, reward_terms(speed, error, a_lon, a_lat, crashed, p, &r));
}

/* reward_of(signals, obs, prev, params, crashed) -> (reward, terms)
 * reward() of signals() = (speed, error, a_lon, a_lat): an env step's reward in one call
 * (ego.gym.env.EgoView.bind_reward). a_lon None stands for the rate of the speed since the
 * last call, EgoView._rate's: (speed - ds0) / (t - t0) if t > t0 else 0, t = obs.t, with
 * prev = [t0, ds0] (a list) set to [t, speed]. */

/* reward_of's work on args = (signals, obs, prev, params, crashed): the reward into *r, the
 * terms returned */
static PyObject *reward_of_terms(PyObject *const *args, double *r)
{
    if (!PyList_Check(args[2]) || PyList_GET_SIZE(args[2]) != 2) {
        PyErr_SetString(PyExc_TypeError, "reward_of(signals, obs, prev: [t0, ds0], params, crashed)");
        return NULL;
    }
    double p[8], x[4];
    const int crashed = PyObject_IsTrue(args[4]);
    if (crashed < 0 || read_doubles(args[3], p, 8, "params")) return NULL;
    PyObject *sig = PyObject_CallNoArgs(args[0]);
    if (!sig) return NULL;
    PyObject *out = NULL;
    if (!PyTuple_Check(sig) || PyTuple_GET_SIZE(sig) != 4) {
        PyErr_SetString(PyExc_TypeError, "reward_of: signals() must give (speed, error, a_lon, a_lat)");
        goto done;
    }
    PyObject *speed = PyTuple_GET_ITEM(sig, 0), *a_lon = PyTuple_GET_ITEM(sig, 2);
    if (as_double(speed, x) || as_double(PyTuple_GET_ITEM(sig, 1), x + 1) || as_double(PyTuple_GET_ITEM(sig, 3), x + 3))
        goto done;
    if (a_lon == Py_None) { /* the rate of the speed since the last call (EgoView._rate) */
        PyObject *prev = args[2], *t = PyObject_GetAttr(args[1], s_t);
        double t1, t0, ds0;
        if (!t || as_double(t, &t1) || as_double(PyList_GET_ITEM(prev, 0), &t0) ||
            as_double(PyList_GET_ITEM(prev, 1), &ds0)) {
            Py_XDECREF(t);
            goto done;
        }
        PyList_SetItem(prev, 0, t); /* steals t */
        PyList_SetItem(prev, 1, Py_NewRef(speed));
        x[2] = t1 > t0 ? (x[0] - ds0) / (t1 - t0) : 0.0;
    } else if (as_double(a_lon, x + 2)) {
        goto done;
    }
    out = reward_terms(x[0], x[1], x[2], x[3], crashed, p, r);
done:
    Py_DECREF(sig);
    return out;
}

static PyObject *reward_of(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 5) {
        PyErr_SetString(PyExc_TypeError, "reward_of(signals, obs, prev: [t0, ds0], params, crashed)");
        return NULL;
    }
    double r;
    return reward_pair(r, reward_of_terms(args, &r));
}

/* env_step(ctx, action) -> (observation, reward, terminated, truncated, info)
 * ego.gym.env.EgoEnv._step for an env step that ends nothing (an EgoState observation, the
 * default reward, a continuous action, one scenario step an env step), in one call:
 * ctx = (fallback, ended, env, scenario, command_params, history, agent, reward_args,
 * observe_args, limit_steps). The command (command()), appended to history; the scenario's
 * step with it (agent None), or scenario.step_joint(agent, lon, lat) where the agent drives
 * ``agent``'s vehicle beside the scenario's controllers; env._elapsed counted; then, the run still running, the reward
 * (reward_of(*reward_args, False)), {"status", "rewards"} and the observation
 * (observe(*observe_args)); the run ended, ended(status) gives the step's return. The methods
 * are looked up at each step, as Python's step does. fallback(action) (the Python step) runs
 * the whole step instead where the run's SUMO is closed, the step reaches limit_steps (the
 * TimeLimit's truncation) or the command is not finite. */

static PyObject *env_step(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 2 || !PyTuple_Check(args[0]) || PyTuple_GET_SIZE(args[0]) != 10) {
        PyErr_SetString(PyExc_TypeError, "env_step(ctx: 10-tuple, action)");
        return NULL;
    }
    PyObject *ctx = args[0], *action = args[1];
    PyObject *fallback = PyTuple_GET_ITEM(ctx, 0), *env = PyTuple_GET_ITEM(ctx, 2), *sc = PyTuple_GET_ITEM(ctx, 3);
    PyObject *history = PyTuple_GET_ITEM(ctx, 5), *agent = PyTuple_GET_ITEM(ctx, 6);
    PyObject *rw_args = PyTuple_GET_ITEM(ctx, 7), *ob_args = PyTuple_GET_ITEM(ctx, 8);
    if (!PyList_Check(history) || !PyTuple_Check(rw_args) || PyTuple_GET_SIZE(rw_args) != 4 ||
        !PyTuple_Check(ob_args) || PyTuple_GET_SIZE(ob_args) != 5) {
        PyErr_SetString(PyExc_TypeError, "env_step: history must be a list, reward_args 4 and observe_args 5 items");
        return NULL;
    }
    PyObject *bridge = PyObject_GetAttr(sc, s_bridge);
    if (!bridge) return NULL;
    const int closed = bridge == Py_None;
    Py_DECREF(bridge);
    PyObject *count = PyObject_GetAttr(env, s_elapsed_);
    if (!count) return NULL;
    const long long elapsed = PyLong_AsLongLong(count);
    Py_DECREF(count);
    double limit;
    if ((elapsed == -1 && PyErr_Occurred()) || as_double(PyTuple_GET_ITEM(ctx, 9), &limit)) return NULL;
    if (closed || (double)(elapsed + 1) >= limit) return PyObject_CallOneArg(fallback, action);

    PyObject *const cmd_args[2] = {PyTuple_GET_ITEM(ctx, 4), action};
    PyObject *cmd = command(self, cmd_args, 2);
    if (!cmd) return NULL;
    if (!PyTuple_Check(cmd) || PyTuple_GET_SIZE(cmd) != 2) {
        Py_DECREF(cmd);
        PyErr_SetString(PyExc_TypeError, "env_step: the command must be a (longitudinal, lateral) tuple");
        return NULL;
    }
    PyObject *lon = PyTuple_GET_ITEM(cmd, 0), *lat = PyTuple_GET_ITEM(cmd, 1);
    double x = 0.0, y = 0.0;
    if ((lon != Py_None && as_double(lon, &x)) || (lat != Py_None && as_double(lat, &y))) {
        Py_DECREF(cmd);
        return NULL;
    }
    const double check = x + y;
    if (check - check != 0.0) { /* nan or inf: the Python step ends the run, saying why */
        Py_DECREF(cmd);
        return PyObject_CallOneArg(fallback, action);
    }
    if (PyList_Append(history, cmd)) {
        Py_DECREF(cmd);
        return NULL;
    }
    PyObject *done;
    if (agent == Py_None) {
        PyObject *const call[2] = {sc, cmd};
        done = PyObject_VectorcallMethod(s_step, call, 2 | PY_VECTORCALL_ARGUMENTS_OFFSET, NULL);
    } else {
        PyObject *const call[4] = {sc, agent, lon, lat};
        done = PyObject_VectorcallMethod(s_step_joint, call, 4 | PY_VECTORCALL_ARGUMENTS_OFFSET, NULL);
    }
    Py_DECREF(cmd);
    if (!done) return NULL;
    Py_DECREF(done);
    count = PyLong_FromLongLong(elapsed + 1);
    if (!count) return NULL;
    const int set = PyObject_SetAttr(env, s_elapsed_, count);
    Py_DECREF(count);
    if (set) return NULL;

    PyObject *status = PyObject_GetAttr(sc, s_status);
    if (!status) return NULL;
    int running = status == s_running;
    if (!running && PyUnicode_Check(status)) running = PyUnicode_Compare(status, s_running) == 0;
    if (!running) {
        PyObject *out = PyErr_Occurred() ? NULL : PyObject_CallOneArg(PyTuple_GET_ITEM(ctx, 1), status);
        Py_DECREF(status);
        return out;
    }
    PyObject *const rw_call[5] = {PyTuple_GET_ITEM(rw_args, 0), PyTuple_GET_ITEM(rw_args, 1),
                                  PyTuple_GET_ITEM(rw_args, 2), PyTuple_GET_ITEM(rw_args, 3), Py_False};
    double r;
    PyObject *terms = reward_of_terms(rw_call, &r), *info = NULL, *ob = NULL, *value = NULL, *out = NULL;
    if (!terms) goto fail;
    info = PyDict_New();
    if (!info || PyDict_SetItem(info, s_status, status) || PyDict_SetItem(info, s_rewards, terms)) goto fail;
    ob = observe(self, &PyTuple_GET_ITEM(ob_args, 0), 5);
    value = ob ? PyFloat_FromDouble(r) : NULL;
    out = value ? PyTuple_New(5) : NULL;
    if (!out) goto fail;
    PyTuple_SET_ITEM(out, 0, ob);
    PyTuple_SET_ITEM(out, 1, value);
    PyTuple_SET_ITEM(out, 2, Py_NewRef(Py_False));
    PyTuple_SET_ITEM(out, 3, Py_NewRef(Py_False));
    PyTuple_SET_ITEM(out, 4, info);
    ob = value = info = NULL; /* the tuple's now */
fail:
    Py_XDECREF(ob);
    Py_XDECREF(value);
    Py_XDECREF(info);
    Py_XDECREF(terms);
    Py_DECREF(status);
    return out;
}

/* bp_pid(ctx, e_x, i_lon, de_x, e_y, i_lat, de_y, report, eta, alpha) -> (u_x, u_y)
 * BPPIDController's step after its integrals (ego/control/bp_pid.py, _step_py): the
 * network's forward pass, the control law and the learning step, the weights updated in
 * place. The sums the reference leaves to numpy stay numpy's: its matmul (BLAS), tanh and exp
 * are called on the work arrays; the pairwise sum of numpy's add.reduce (8 accumulators under
 * 128 values) is written out. ctx = (work, w1, w2, w1_prev, w2_prev, coef, x, z1, h, z2,
 * tanh_in, tanh_out, expd, delta3, delta2, w2.T, matmul, tanh, exp, ("out",)) where work is
 * the float64 array the views x ... gains live in (offsets BP_*); report is the variant
 * (true: the report's), eta and alpha the learning rate and momentum. */
enum { BP_X = 0, BP_Z1 = 8, BP_H = 18, BP_Z2 = 28, BP_TIN = 34, BP_TOUT = 52, BP_EXP = 70, BP_D3 = 76,
       BP_D2 = 82, BP_GAINS = 92, BP_WORK = 98 };

static double np_max(double a, double b) { return isnan(a) ? a : (a > b ? a : b); }
static double np_min(double a, double b) { return isnan(a) ? a : (a < b ? a : b); }

/* numpy's pairwise summation (its add.reduce of a contiguous float64 array): blocks of up to
 * 128 values summed with 8 accumulators, longer runs split in halves (multiples of 8) */
static double np_pairwise(const double *a, Py_ssize_t n)
{
    double res;
    Py_ssize_t i;
    if (n < 8) {
        res = 0.0;
        for (i = 0; i < n; i++) res += a[i];
        return res;
    }
    if (n <= 128) {
        double r[8];
        for (i = 0; i < 8; i++) r[i] = a[i];
        for (i = 8; i < n - (n % 8); i += 8)
            for (int j = 0; j < 8; j++) r[j] += a[i + j];
        res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for (; i < n; i++) res += a[i];
        return res;
    }
    Py_ssize_t n2 = n / 2;
    n2 -= n2 % 8;
    return np_pairwise(a, n2) + np_pairwise(a + n2, n - n2);
}

/* numpy.add.reduce(a, None) of n contiguous doubles (the reduction starts from add's identity) */
static double np_sum(const double *a, Py_ssize_t n) { return 0.0 + np_pairwise(a, n); }

/* sum_squares(a) -> float: numpy.add.reduce(a * a, None) of a C-contiguous float64 array */
static PyObject *sum_squares(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 1) {
        PyErr_SetString(PyExc_TypeError, "sum_squares(a)");
        return NULL;
    }
    Py_buffer view;
    if (PyObject_GetBuffer(args[0], &view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) return NULL;
    if (view.itemsize != sizeof(double) || !view.format || strcmp(view.format, "d") != 0) {
        PyErr_SetString(PyExc_TypeError, "sum_squares: a float64 array");
        PyBuffer_Release(&view);
        return NULL;
    }
    const Py_ssize_t n = view.len / (Py_ssize_t)sizeof(double);
    double stack[128], *sq = n <= 128 ? stack : PyMem_Malloc(n * sizeof(double));
    if (!sq) {
        PyBuffer_Release(&view);
        return PyErr_NoMemory();
    }
    const double *a = (const double *)view.buf;
    for (Py_ssize_t i = 0; i < n; i++) sq[i] = a[i] * a[i];
    const double total = np_sum(sq, n);
    if (sq != stack) PyMem_Free(sq);
    PyBuffer_Release(&view);
    return PyFloat_FromDouble(total);
}

/* a writable C-contiguous float64 array of n values (n < 0: any number) */
static int writable_doubles(PyObject *arr, Py_buffer *view, Py_ssize_t n)
{
    if (PyObject_GetBuffer(arr, view, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) return -1;
    if (view->itemsize != sizeof(double) || !view->format || strcmp(view->format, "d") != 0) {
        PyErr_SetString(PyExc_TypeError, "a work or weight array is not float64");
        PyBuffer_Release(view);
        return -1;
    }
    if (n >= 0 && view->len != n * (Py_ssize_t)sizeof(double)) {
        PyErr_SetString(PyExc_ValueError, "a work or weight array has the wrong size");
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

/* the first n items of arrs as writable float64 buffers of sizes[i] values each (< 0: any);
 * -1 with the error set and none held */
static int acquire(PyObject *const *arrs, const Py_ssize_t *sizes, int n, Py_buffer *views)
{
    for (int i = 0; i < n; i++)
        if (writable_doubles(arrs[i], &views[i], sizes[i])) {
            while (i--) PyBuffer_Release(&views[i]);
            return -1;
        }
    return 0;
}

static void release(Py_buffer *views, int n)
{
    for (int i = 0; i < n; i++) PyBuffer_Release(&views[i]);
}

/* n float arguments into out; -1 with the error set */
static int doubles_of(PyObject *const *args, int n, double *out)
{
    for (int i = 0; i < n; i++) {
        out[i] = PyFloat_AsDouble(args[i]);
        if (out[i] == -1.0 && PyErr_Occurred()) return -1;
    }
    return 0;
}

static PyObject *bp_pid(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 10 || !PyTuple_Check(args[0]) || PyTuple_GET_SIZE(args[0]) != 20) {
        PyErr_SetString(PyExc_TypeError,
                        "bp_pid(ctx: 20-tuple, e_x, i_lon, de_x, e_y, i_lat, de_y, report, eta, alpha)");
        return NULL;
    }
    PyObject *const *c = &PyTuple_GET_ITEM(args[0], 0);
    double t[6];
    if (doubles_of(args + 1, 6, t)) return NULL;
    const int report = PyObject_IsTrue(args[7]);
    if (report < 0) return NULL;
    const double eta = PyFloat_AsDouble(args[8]), alpha = PyFloat_AsDouble(args[9]);
    if (PyErr_Occurred()) return NULL;
    PyObject *kw = c[19], *matmul = c[16];
    static const Py_ssize_t sizes[6] = {BP_WORK, 80, 60, 80, 60, 6};
    Py_buffer b[6]; /* work, w1, w2, w1_prev, w2_prev, coef */
    if (acquire(c, sizes, 6, b)) return NULL;
    PyObject *result = NULL;
    const double *coef = (const double *)b[5].buf;
    double *w = (double *)b[0].buf, *w1 = (double *)b[1].buf, *w2 = (double *)b[2].buf;
    double *w1p = (double *)b[3].buf, *w2p = (double *)b[4].buf;
    double *x = w + BP_X, *z1 = w + BP_Z1, *h = w + BP_H, *z2 = w + BP_Z2, *tin = w + BP_TIN;
    double *tout = w + BP_TOUT, *ex = w + BP_EXP, *d3 = w + BP_D3, *d2 = w + BP_D2, *gains = w + BP_GAINS;
    double cc[6], k[6], dk[6], g2[60], g1[80];
    for (int i = 0; i < 6; i++) cc[i] = coef[i] * t[i];
    if (report) { /* raw inputs */
        for (int i = 0; i < 3; i++) { x[i] = t[i]; x[4 + i] = t[3 + i]; }
    } else { /* tanh of the terms, of the errors and of the law's terms in one call */
        for (int i = 0; i < 6; i++) { tin[i] = t[i]; tin[12 + i] = cc[i]; }
        for (int i = 0; i < 3; i++) { tin[6 + i] = t[0]; tin[9 + i] = t[3]; }
        PyObject *argv[2] = {c[10], c[11]};
        PyObject *r = PyObject_Vectorcall(c[17], argv, 1, kw);
        if (!r) goto done;
        Py_DECREF(r);
        for (int i = 0; i < 3; i++) { x[i] = tout[i]; x[4 + i] = tout[3 + i]; }
    }
    { /* forward: z1 = w1 x, h = max(z1, 0), z2 = w2 h, k = sigmoid(clip(z2, -50, 50)) */
        PyObject *a1[3] = {c[1], c[6], c[7]};
        PyObject *r = PyObject_Vectorcall(matmul, a1, 2, kw);
        if (!r) goto done;
        Py_DECREF(r);
        for (int i = 0; i < 10; i++) h[i] = np_max(z1[i], 0.0);
        PyObject *a2[3] = {c[2], c[8], c[9]};
        r = PyObject_Vectorcall(matmul, a2, 2, kw);
        if (!r) goto done;
        Py_DECREF(r);
        for (int i = 0; i < 6; i++) ex[i] = -np_min(np_max(z2[i], -50.0), 50.0);
        PyObject *a3[2] = {c[12], c[12]};
        r = PyObject_Vectorcall(c[18], a3, 1, kw);
        if (!r) goto done;
        Py_DECREF(r);
    }
    for (int i = 0; i < 6; i++) {
        k[i] = 1.0 / (1.0 + ex[i]);
        gains[i] = 1.0 + k[i];
    }
    const double u_x = gains[0] * cc[0] + gains[1] * cc[1] + gains[2] * cc[2];
    const double u_y = gains[3] * cc[3] + gains[4] * cc[4] + gains[5] * cc[5];
    /* learning */
    for (int i = 0; i < 6; i++) {
        dk[i] = k[i] * (1.0 - k[i]);
        d3[i] = report ? dk[i] * t[i] : (-tout[6 + i]) * tout[12 + i] * dk[i];
    }
    {
        PyObject *a4[3] = {c[15], c[13], c[14]};
        PyObject *r = PyObject_Vectorcall(matmul, a4, 2, kw);
        if (!r) goto done;
        Py_DECREF(r);
    }
    for (int i = 0; i < 10; i++) d2[i] = d2[i] * (z1[i] > 0.0 ? 1.0 : 0.0);
    for (int i = 0; i < 6; i++)
        for (int j = 0; j < 10; j++) g2[10 * i + j] = d3[i] * h[j];
    for (int i = 0; i < 10; i++)
        for (int j = 0; j < 8; j++) g1[8 * i + j] = d2[i] * x[j];
    if (!report) { /* clip the step, not its direction */
        double sq2[60], sq1[80];
        for (int i = 0; i < 60; i++) sq2[i] = g2[i] * g2[i];
        for (int i = 0; i < 80; i++) sq1[i] = g1[i] * g1[i];
        const double norm = sqrt(np_sum(sq2, 60) + np_sum(sq1, 80));
        if (norm > 1.0) {
            for (int i = 0; i < 60; i++) g2[i] /= norm;
            for (int i = 0; i < 80; i++) g1[i] /= norm;
        }
    }
    {
        const double neg_eta = -eta, mom = (report ? -1.0 : 1.0) * alpha;
        for (int i = 0; i < 60; i++) {
            const double step = neg_eta * g2[i] + mom * (w2[i] - w2p[i]);
            w2p[i] = w2[i];
            w2[i] = w2[i] + step;
        }
        for (int i = 0; i < 80; i++) {
            const double step = neg_eta * g1[i] + mom * (w1[i] - w1p[i]);
            w1p[i] = w1[i];
            w1[i] = w1[i] + step;
        }
    }
    result = Py_BuildValue("(dd)", u_x, u_y);
done:
    release(b, 6);
    return result;
}

/* rbf_smc(ctx, s, d, ds, dd, neg_two_w2, scale, k_lon, k_lat, update_lat) -> (f_lon, f_lat)
 * RBFSMCController's network (ego/control/rbf_smc.py, _network_py): the basis h of x = (s,
 * d, ds, dd), the estimates f = w . h on both channels, then w_lon += k_lon h and, when
 * update_lat (not in the report's variant, whose channels share one array), w_lat += k_lat h.
 * numpy's einsum, exp and matmul (BLAS dot) are called on the work array's views, as the
 * reference calls them. ctx = (work,
 * centres, w_lon, w_lat, diff, d2, h, f_lon, f_lat, c_einsum, "ij,ij->i", exp, matmul,
 * ("out",)): work holds, for n nodes, diff (n x 4), d2 (n), h (n) and the two estimates. */
static PyObject *rbf_smc(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 10 || !PyTuple_Check(args[0]) || PyTuple_GET_SIZE(args[0]) != 14) {
        PyErr_SetString(PyExc_TypeError,
                        "rbf_smc(ctx: 14-tuple, s, d, ds, dd, neg_two_w2, scale, k_lon, k_lat, update_lat)");
        return NULL;
    }
    PyObject *const *c = &PyTuple_GET_ITEM(args[0], 0);
    double a[8];
    if (doubles_of(args + 1, 8, a)) return NULL;
    const double neg = a[4], scale = a[5], k_lon = a[6], k_lat = a[7];
    const int update_lat = PyObject_IsTrue(args[9]);
    if (update_lat < 0) return NULL;
    Py_buffer b[4]; /* work, centres, w_lon, w_lat */
    const Py_ssize_t any[4] = {-1, -1, -1, -1};
    if (acquire(c, any, 4, b)) return NULL;
    const Py_ssize_t n = b[2].len / (Py_ssize_t)sizeof(double);
    if (b[0].len != (6 * n + 2) * (Py_ssize_t)sizeof(double) || b[1].len != 4 * b[2].len || b[3].len != b[2].len) {
        PyErr_SetString(PyExc_ValueError, "rbf_smc: the work, centre and weight arrays do not fit n nodes");
        release(b, 4);
        return NULL;
    }
    PyObject *result = NULL;
    double *w = (double *)b[0].buf, *w_lon = (double *)b[2].buf, *w_lat = (double *)b[3].buf;
    const double *centres = (const double *)b[1].buf;
    double *diff = w, *d2 = w + 4 * n, *h = w + 5 * n, *f = w + 6 * n;
    PyObject *kw = c[13], *r;
    for (Py_ssize_t i = 0; i < n; i++)
        for (int j = 0; j < 4; j++) diff[4 * i + j] = centres[4 * i + j] - a[j];
    PyObject *ein[4] = {c[10], c[4], c[4], c[5]};
    if (!(r = PyObject_Vectorcall(c[9], ein, 3, kw))) goto done;
    Py_DECREF(r);
    for (Py_ssize_t i = 0; i < n; i++) h[i] = d2[i] / neg;
    PyObject *ex[2] = {c[6], c[6]};
    if (!(r = PyObject_Vectorcall(c[11], ex, 1, kw))) goto done;
    Py_DECREF(r);
    for (Py_ssize_t i = 0; i < n; i++) h[i] = scale * h[i];
    PyObject *m1[3] = {c[2], c[6], c[7]};
    if (!(r = PyObject_Vectorcall(c[12], m1, 2, kw))) goto done;
    Py_DECREF(r);
    PyObject *m2[3] = {c[3], c[6], c[8]};
    if (!(r = PyObject_Vectorcall(c[12], m2, 2, kw))) goto done;
    Py_DECREF(r);
    for (Py_ssize_t i = 0; i < n; i++) w_lon[i] = w_lon[i] + k_lon * h[i];
    if (update_lat) /* after w_lon, as the reference (the same array twice if they alias) */
        for (Py_ssize_t i = 0; i < n; i++) w_lat[i] = w_lat[i] + k_lat * h[i];
    result = Py_BuildValue("(dd)", f[0], f[1]);
done:
    release(b, 4);
    return result;
}

/* bp_pid_acc(ctx, x0, x1, e, t0, t1, t2, u, hi, lo, eta, alpha) -> u
 * BPPIDAcc's update (ego/control/following.py, _update_py) after its scalars: the 3-5-3
 * network's forward pass on x = (x0, x1, e), the incremental PID u + gains . terms clipped to
 * [lo, hi], the learning step with momentum, the weights updated in place. numpy's matmul
 * (BLAS) and tanh are called on the work array's views as the reference calls them. ctx =
 * (work, w1, w2, dw1, dw2, x, z1, h, z2, o, gains, terms, dot, delta3, delta2, w2.T, matmul,
 * tanh, ("out",)); work holds x (3), z1 (5), h (5), z2 (3), o (3), gains (3), terms (3), the
 * dot product (1), delta3 (3), delta2 (5). */
enum { BA_X = 0, BA_Z1 = 3, BA_H = 8, BA_Z2 = 13, BA_O = 16, BA_GAINS = 19, BA_TERMS = 22, BA_DOT = 25,
       BA_D3 = 26, BA_D2 = 29, BA_WORK = 34 };

static PyObject *bp_pid_acc(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 12 || !PyTuple_Check(args[0]) || PyTuple_GET_SIZE(args[0]) != 19) {
        PyErr_SetString(PyExc_TypeError, "bp_pid_acc(ctx: 19-tuple, x0, x1, e, t0, t1, t2, u, hi, lo, eta, alpha)");
        return NULL;
    }
    PyObject *const *c = &PyTuple_GET_ITEM(args[0], 0);
    double a[11];
    if (doubles_of(args + 1, 11, a)) return NULL;
    const double e = a[2], hi = a[7], lo = a[8], eta = a[9], alpha = a[10];
    static const Py_ssize_t sizes[5] = {BA_WORK, 15, 15, 15, 15};
    Py_buffer b[5]; /* work, w1, w2, dw1, dw2 */
    if (acquire(c, sizes, 5, b)) return NULL;
    PyObject *result = NULL, *kw = c[18], *matmul = c[16], *tanh_ = c[17], *r;
    double *w = (double *)b[0].buf, *w1 = (double *)b[1].buf, *w2 = (double *)b[2].buf;
    double *dw1 = (double *)b[3].buf, *dw2 = (double *)b[4].buf;
    double *x = w + BA_X, *h = w + BA_H, *o = w + BA_O, *gains = w + BA_GAINS, *terms = w + BA_TERMS;
    double *d3 = w + BA_D3, *d2 = w + BA_D2;
    x[0] = a[0], x[1] = a[1], x[2] = e;
    /* h = tanh(w1 x), o = tanh(w2 h) */
    PyObject *m1[3] = {c[1], c[5], c[6]}, *t1[2] = {c[6], c[7]}, *m2[3] = {c[2], c[7], c[8]}, *t2[2] = {c[8], c[9]};
    if (!(r = PyObject_Vectorcall(matmul, m1, 2, kw))) goto done;
    Py_DECREF(r);
    if (!(r = PyObject_Vectorcall(tanh_, t1, 1, kw))) goto done;
    Py_DECREF(r);
    if (!(r = PyObject_Vectorcall(matmul, m2, 2, kw))) goto done;
    Py_DECREF(r);
    if (!(r = PyObject_Vectorcall(tanh_, t2, 1, kw))) goto done;
    Py_DECREF(r);
    for (int i = 0; i < 3; i++) gains[i] = 0.5 * (1.0 + o[i]);
    terms[0] = a[3], terms[1] = a[4], terms[2] = a[5];
    PyObject *m3[3] = {c[10], c[11], c[12]};
    if (!(r = PyObject_Vectorcall(matmul, m3, 2, kw))) goto done;
    Py_DECREF(r);
    double u = a[6] + w[BA_DOT];
    u = u > hi ? hi : (u < lo ? lo : u);
    /* learning: dE/dK = -e du/dK, dK/dz = (1 - o^2)/2 */
    for (int i = 0; i < 3; i++) d3[i] = e * terms[i] * 0.5 * (1.0 - o[i] * o[i]);
    PyObject *m4[3] = {c[15], c[13], c[14]};
    if (!(r = PyObject_Vectorcall(matmul, m4, 2, kw))) goto done;
    Py_DECREF(r);
    for (int i = 0; i < 5; i++) d2[i] = d2[i] * (1.0 - h[i] * h[i]);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 5; j++) {
            double *dw = dw2 + 5 * i + j;
            *dw = *dw * alpha;
            *dw = *dw + eta * (d3[i] * h[j]);
        }
    for (int i = 0; i < 5; i++)
        for (int j = 0; j < 3; j++) {
            double *dw = dw1 + 3 * i + j;
            *dw = *dw * alpha;
            *dw = *dw + eta * (d2[i] * x[j]);
        }
    for (int i = 0; i < 15; i++) w2[i] = w2[i] + dw2[i];
    for (int i = 0; i < 15; i++) w1[i] = w1[i] + dw1[i];
    result = PyFloat_FromDouble(u);
done:
    release(b, 5);
    return result;
}

/* ---------------------------------------------------------------------------------------
 * The loop's per-control-period glue (ego/scenarios/base.py ComposedLoop._act):
 *  - plant_step: BicyclePlant.step of the nonlinear bicycle (ActuatorLimits.apply, the RK4
 *    step of bicycle_step, the standstill hold), the plant's attributes set as it sets them;
 *  - trace_write: Trace.bind's writer for a row in the declared order (the Python writer is
 *    called for anything else, so every check and message stays its own);
 *  - road_frame: RoadSensor.frame on a straight lane (else the Python method runs).
 * ------------------------------------------------------------------------------------- */

#define LIMITS_N 8 /* max_steer, max_steer_rate, min_command, max_command, stop_speed, dt, h, substeps */

static PyObject *float_tuple(const double *x, Py_ssize_t n)
{
    PyObject *t = PyTuple_New(n);
    if (!t) return NULL;
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *f = PyFloat_FromDouble(x[i]);
        if (!f) { Py_DECREF(t); return NULL; }
        PyTuple_SET_ITEM(t, i, f);
    }
    return t;
}

static int item_double(PyObject *seq, Py_ssize_t i, double *out)
{
    PyObject *o = PySequence_GetItem(seq, i);
    if (!o) return -1;
    *out = PyFloat_AsDouble(o);
    Py_DECREF(o);
    return (*out == -1.0 && PyErr_Occurred()) ? -1 : 0;
}

/* plant_step(plant, packed, action) -> None; packed: LIMITS_N + BIKE_NPARAM doubles (the
 * action last, so functools.partial can bind the plant and its packed numbers) */
static PyObject *plant_step(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 3) {
        PyErr_SetString(PyExc_TypeError, "plant_step(plant, packed, action)");
        return NULL;
    }
    PyObject *plant = args[0];
    const double *k = params_of(args[1], LIMITS_N + BIKE_NPARAM, "packed");
    if (!k) return NULL;
    double x[NX], y[NX], k1[NX], command, delta, previous;
    PyObject *state = PyObject_GetAttr(plant, s_state);
    if (!state) return NULL;
    int bad = read_doubles(state, x, NX, "state");
    Py_DECREF(state);
    if (bad < 0) return NULL;
    PyObject *applied = PyObject_GetAttr(plant, s_applied);
    if (!applied) return NULL;
    bad = item_double(applied, 1, &previous);
    Py_DECREF(applied);
    if (bad < 0 || item_double(args[2], 0, &command) < 0 || item_double(args[2], 1, &delta) < 0) return NULL;
    /* ActuatorLimits.apply, comparison for comparison */
    const double ms = k[0], rate = k[1], lo_c = k[2], hi_c = k[3], stop = k[4], dt = k[5];
    delta = delta > ms ? ms : (delta < -ms ? -ms : delta);
    if (rate != Py_HUGE_VAL) {
        const double step = rate * dt, lo = previous - step, hi = previous + step;
        delta = delta < lo ? lo : (delta > hi ? hi : delta);
    }
    if (command < lo_c) command = lo_c;
    else if (command > hi_c) command = hi_c;
    const double speed = x[1];
    if (stop > 0.0 && command < 0.0 && speed < stop) command = command * (speed > 0.0 ? speed : 0.0) / stop;
    /* the model's step (bicycle_step) */
    memcpy(y, x, sizeof x);
    const long substeps = (long)k[7];
    bike_rk4(k + LIMITS_N, y, command, delta, k[6], k1);
    for (long i = 1; i < substeps; i++) bike_rk4(k + LIMITS_N, y, command, delta, k[6], NULL);
    const double lateral = k1[3] + x[1] * x[5];
    /* at rest with no drive the brakes hold the car */
    if (y[1] < 0.0 && 0.0 <= x[1] && command <= 0.0 && stop > 0.0) y[1] = 0.0;
    const double pair_[2] = {command, delta};
    PyObject *new_applied = float_tuple(pair_, 2);
    if (!new_applied) return NULL;
    bad = PyObject_SetAttr(plant, s_applied, new_applied);
    Py_DECREF(new_applied);
    if (bad < 0) return NULL;
    PyObject *new_state = float_tuple(y, NX);
    if (!new_state) return NULL;
    bad = PyObject_SetAttr(plant, s_state, new_state);
    Py_DECREF(new_state);
    if (bad < 0) return NULL;
    PyObject *lat = PyFloat_FromDouble(lateral);
    if (!lat) return NULL;
    bad = PyObject_SetAttr(plant, s_lateral_accel, lat);
    Py_DECREF(lat);
    if (bad < 0) return NULL;
    Py_RETURN_NONE;
}

/* trace_write(rows, width, signals, fallback, sigs, values): rows.append(values +
 * tuple(sigs.values())) when values is a tuple of width items and sigs a dict whose keys are
 * signals in order; else fallback(sigs, values) (the Python writer: its checks, its errors) */
static PyObject *trace_write(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 6) {
        PyErr_SetString(PyExc_TypeError, "trace_write(rows, width, signals, fallback, sigs, values)");
        return NULL;
    }
    PyObject *rows = args[0], *names = args[2], *sigs = args[4], *values = args[5];
    const Py_ssize_t width = PyLong_AsSsize_t(args[1]);
    if (width == -1 && PyErr_Occurred()) return NULL;
    if (!PyList_CheckExact(rows) || !PyTuple_CheckExact(names)) {
        PyErr_SetString(PyExc_TypeError, "trace_write: rows must be a list and signals a tuple");
        return NULL;
    }
    const Py_ssize_t nsig = PyTuple_GET_SIZE(names);
    int fast = PyTuple_CheckExact(values) && PyTuple_GET_SIZE(values) == width && PyDict_CheckExact(sigs)
               && PyDict_GET_SIZE(sigs) == nsig;
    PyObject *key, *value;
    Py_ssize_t pos = 0, i = 0;
    while (fast && PyDict_Next(sigs, &pos, &key, &value)) {
        PyObject *name = PyTuple_GET_ITEM(names, i++);
        if (key != name) {
            int eq = PyObject_RichCompareBool(key, name, Py_EQ);
            if (eq < 0) return NULL;
            fast = eq;
        }
    }
    if (!fast) return PyObject_CallFunctionObjArgs(args[3], sigs, values, NULL);
    PyObject *row = PyTuple_New(width + nsig);
    if (!row) return NULL;
    for (i = 0; i < width; i++) {
        PyObject *v = PyTuple_GET_ITEM(values, i);
        Py_INCREF(v);
        PyTuple_SET_ITEM(row, i, v);
    }
    pos = 0;
    while (PyDict_Next(sigs, &pos, &key, &value)) {
        Py_INCREF(value);
        PyTuple_SET_ITEM(row, i++, value);
    }
    int bad = PyList_Append(rows, row);
    Py_DECREF(row);
    if (bad < 0) return NULL;
    Py_RETURN_NONE;
}

static int set_double(PyObject *obj, PyObject *name, double value)
{
    PyObject *f = PyFloat_FromDouble(value);
    if (!f) return -1;
    int bad = PyObject_SetAttr(obj, name, f);
    Py_DECREF(f);
    return bad;
}


/* road_frame(frame, view, plant, road, line) -> None: RoadSensor.frame on its records: the
 * plant's state in, the view's frame fields out (X, Y, s, d_road, heading_error, curvature,
 * ds, dd; on a curved lane turn and station too). ``road`` is the lane the view measured in
 * when the loop bound it, ``line`` its straight segment (LanePolyline.straight) or None: a
 * straight lane's rotation (LanePolyline.frame's arithmetic), a curved lane's
 * LanePolyline.locate on its packed data. view.road another lane, or a point the Python
 * method decides (it raises there): frame(), the Python method. */
static int frame_out(PyObject *view, double X, double Y, double s, double d, double err, double kappa, double u,
                     double v)
{
    const double c = cos(err), sn = sin(err);
    return (set_double(view, s_X, X) < 0 || set_double(view, s_Y, Y) < 0 || set_double(view, s_s, s) < 0
            || set_double(view, s_d_road, d) < 0 || set_double(view, s_heading_error, err) < 0
            || set_double(view, s_curvature, kappa) < 0 || set_double(view, s_ds, u * c - v * sn) < 0
            || set_double(view, s_dd, u * sn + v * c) < 0)
               ? -1
               : 0;
}

static PyObject *road_frame(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 5) {
        PyErr_SetString(PyExc_TypeError, "road_frame(frame, view, plant, road, line)");
        return NULL;
    }
    PyObject *frame = args[0], *view = args[1], *plant = args[2], *road = args[3], *line_obj = args[4];
    PyObject *now = PyObject_GetAttr(view, s_road);
    if (!now) return NULL;
    Py_DECREF(now);
    if (now != road) return PyObject_CallNoArgs(frame);
    double x[NX], line[6];
    PyObject *state = PyObject_GetAttr(plant, s_state);
    if (!state) return NULL;
    int bad = read_doubles(state, x, NX, "state");
    Py_DECREF(state);
    if (bad < 0) return NULL;
    const double X = x[0], u = x[1], Y = x[2], v = x[3], psi = x[4];
    if (line_obj == Py_None) { /* a curved lane: LanePolyline.locate on its packed data */
        LaneData L;
        const int got = lane_packed(road, &L);
        if (got < 0) return NULL;
        if (got > 0) return PyObject_CallNoArgs(frame);
        PyObject *hint_obj = PyObject_GetAttr(road, s_hint_);
        if (!hint_obj) { lane_release(&L); return NULL; }
        Py_ssize_t hint = PyLong_AsSsize_t(hint_obj);
        Py_DECREF(hint_obj);
        if (hint == -1 && PyErr_Occurred()) { lane_release(&L); return NULL; }
        double f[6];
        const int defer = lane_locate(&L, &hint, X, Y, psi, f);
        lane_release(&L);
        if (defer) return PyObject_CallNoArgs(frame);
        PyObject *h = PyLong_FromSsize_t(hint);
        if (!h) return NULL;
        bad = PyObject_SetAttr(road, s_hint_, h);
        Py_DECREF(h);
        if (bad < 0 || set_double(view, s_turn, f[4]) < 0 || set_double(view, s_station, f[5]) < 0
            || frame_out(view, X, Y, f[0], f[1], f[2], f[3], u, v) < 0)
            return NULL;
        Py_RETURN_NONE;
    }
    if (read_doubles(line_obj, line, 6, "line") < 0) return NULL;
    const double x0 = line[0], y0 = line[1], ux = line[2], uy = line[3], s0 = line[4], heading = line[5];
    const double dx = X - x0, dy = Y - y0;
    double err = psi - heading;
    if (isinf(err)) return PyObject_CallNoArgs(frame); /* math.fmod raises there */
    if (!(-Py_MATH_PI < err && err <= Py_MATH_PI)) { /* lane_frame.wrap_angle */
        double a = fmod(err + Py_MATH_PI, 2.0 * Py_MATH_PI);
        if (a <= 0.0) a += 2.0 * Py_MATH_PI;
        err = a - Py_MATH_PI;
    }
    if (frame_out(view, X, Y, s0 + dx * ux + dy * uy, dy * ux - dx * uy, err, 0.0, u, v) < 0) return NULL;
    Py_RETURN_NONE;
}

/* ---------------------------------------------------------------------------------------
 * The surround sensor's search (ego/scenarios/sensor.py SurroundSensor):
 *  - near(objects, lo, hi, h, m): the objects whose extent across the lane, widened by
 *    |v_d| h + m, overlaps (lo, hi): scan's and _scan_lane's filter (m = 0 there: x + 0.0
 *    compares as x);
 *  - nearest(objects, lo, hi, e_lo, e_hi, since, ahead, behind[, along]): _nearest, the
 *    Detections filled as Detection._found and Detection.clear fill them; with ``along`` =
 *    (d_min, d_max, turn, ego_front, ego_rear) (a curved lane), _nearest_along and Detection._found_along.
 * An object is the sensor's tuple (id, s_lo, s_hi, d_lo, d_hi, v_s, v_d, accel, rel).
 * ------------------------------------------------------------------------------------- */

static int object_doubles(PyObject *o, double *x)
{
    if (!PyTuple_CheckExact(o) || PyTuple_GET_SIZE(o) < 8) {
        PyErr_SetString(PyExc_TypeError, "a sensed object must be a tuple (id, s_lo, s_hi, d_lo, d_hi, v_s, v_d, accel, ...)");
        return -1;
    }
    for (int i = 1; i < 7; i++) {
        x[i] = PyFloat_AsDouble(PyTuple_GET_ITEM(o, i));
        if (x[i] == -1.0 && PyErr_Occurred()) return -1;
    }
    return 0;
}

static PyObject *near(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 5 || !PyList_CheckExact(args[0])) {
        PyErr_SetString(PyExc_TypeError, "near(objects: list, lo, hi, h, m)");
        return NULL;
    }
    PyObject *objects = args[0];
    double lim[4];
    for (int i = 0; i < 4; i++) {
        lim[i] = PyFloat_AsDouble(args[i + 1]);
        if (lim[i] == -1.0 && PyErr_Occurred()) return NULL;
    }
    const double lo = lim[0], hi = lim[1], h = lim[2], m = lim[3];
    PyObject *out = PyList_New(0);
    if (!out) return NULL;
    for (Py_ssize_t i = 0; i < PyList_GET_SIZE(objects); i++) {
        PyObject *o = PyList_GET_ITEM(objects, i);
        double x[8];
        if (object_doubles(o, x) < 0) { Py_DECREF(out); return NULL; }
        const double reach = fabs(x[6]) * h;
        if (x[4] + reach + m > lo && x[3] - reach - m < hi && PyList_Append(out, o) < 0) {
            Py_DECREF(out);
            return NULL;
        }
    }
    return out;
}

static int detection_found(PyObject *det, PyObject *o, double gap, PyObject *lo, PyObject *hi, PyObject *since)
{
    PyObject *g = PyFloat_FromDouble(gap);
    if (!g) return -1;
    int bad = PyObject_SetAttr(det, s_id, PyTuple_GET_ITEM(o, 0)) < 0 || PyObject_SetAttr(det, s_gap, g) < 0
              || PyObject_SetAttr(det, s_speed, PyTuple_GET_ITEM(o, 5)) < 0
              || PyObject_SetAttr(det, s_accel, PyTuple_GET_ITEM(o, 7)) < 0 || PyObject_SetAttr(det, s_gap0, g) < 0
              || PyObject_SetAttr(det, s_o, o) < 0 || PyObject_SetAttr(det, s_lo_, lo) < 0
              || PyObject_SetAttr(det, s_hi_, hi) < 0 || PyObject_SetAttr(det, s_since_, since) < 0;
    Py_DECREF(g);
    return bad ? -1 : 0;
}

/* Detection._found_along(o, gap, lo, hi, since, line, speed) */
static int detection_found_along(PyObject *det, PyObject *o, double gap, PyObject *lo, PyObject *hi, PyObject *since,
                                 double line, double speed)
{
    if (detection_found(det, o, gap, lo, hi, since) < 0) return -1;
    return (set_double(det, s_speed, speed) < 0 || set_double(det, s_d_, line) < 0) ? -1 : 0;
}

static int detection_clear(PyObject *det)
{
    return (PyObject_SetAttr(det, s_id, str_empty) < 0 || PyObject_SetAttr(det, s_gap, float_inf) < 0
            || PyObject_SetAttr(det, s_speed, float_zero) < 0 || PyObject_SetAttr(det, s_accel, float_zero) < 0
            || PyObject_SetAttr(det, s_o, Py_None) < 0)
               ? -1
               : 0;
}

/* SurroundSensor._nearest_along: the same arithmetic, in the same order */
static PyObject *nearest_along(PyObject *const *args, const double *lim, const double *along)
{
    PyObject *objects = args[0], *lo_obj = args[1], *hi_obj = args[2], *ahead = args[6], *behind = args[7];
    const double lo = lim[0], hi = lim[1], e_lo = lim[2], e_hi = lim[3], since = lim[4];
    const double d_min = along[0], d_max = along[1], turn = along[2], ego_front = along[3], ego_rear = along[4];
    const double twice_mid = e_lo + e_hi;
    double best_ahead = Py_HUGE_VAL, best_behind = Py_HUGE_VAL, d_ahead = 0.0, d_behind = 0.0;
    PyObject *front = NULL, *rear = NULL;
    for (Py_ssize_t i = 0; i < PyList_GET_SIZE(objects); i++) {
        PyObject *o = PyList_GET_ITEM(objects, i);
        double x[11];
        if (object_doubles(o, x) < 0) return NULL;
        if (PyTuple_GET_SIZE(o) < 11) {
            PyErr_SetString(PyExc_TypeError, "a sensed object on a curved lane must carry its turn and curvature");
            return NULL;
        }
        const double shift = x[6] * since;
        if (x[4] + shift <= lo || x[3] + shift >= hi) continue;
        for (int k = 9; k < 11; k++) {
            x[k] = PyFloat_AsDouble(PyTuple_GET_ITEM(o, k));
            if (x[k] == -1.0 && PyErr_Occurred()) return NULL;
        }
        const double move = x[5] * since;
        const double a = x[1] + move, b = x[2] + move;
        const double kappa = x[10];
        const double bend = x[9] + kappa * move - turn;
        const double d_o = 0.5 * (x[3] + x[4]) + shift;
        const double half = 0.5 * (x[2] - x[1]);
        const double grow = half * kappa / (1.0 - kappa * d_o);
        const double k = fabs(kappa), w = 0.5 * (x[4] - x[3]);
        const double corner = half * k * w / (1.0 - k * w);
        double g0, g1;
        if (a + b >= twice_mid) {
            const double raw = a - e_hi;
            g0 = raw - d_min * bend;
            g1 = raw - d_max * bend;
        } else {
            const double raw = e_lo - b;
            g0 = raw + d_min * bend;
            g1 = raw + d_max * bend;
        }
        double extra = grow * (d_o - d_min);
        if (extra > 0.0) g0 -= extra;
        extra = grow * (d_o - d_max);
        if (extra > 0.0) g1 -= extra;
        const int outer = g1 < g0;
        double gap = outer ? g1 : g0;
        const double line = outer ? d_max : d_min;
        if (a + b >= twice_mid) {
            gap = gap - corner - ego_front;
            if (gap < best_ahead) {
                best_ahead = gap;
                front = o;
                d_ahead = line;
            }
        } else {
            gap = gap - corner - ego_rear;
            if (gap < best_behind) {
                best_behind = gap;
                rear = o;
                d_behind = line;
            }
        }
    }
    PyObject *since_obj = args[5];
    PyObject *dets[2] = {ahead, behind}, *found[2] = {front, rear};
    const double gaps[2] = {best_ahead, best_behind}, lines[2] = {d_ahead, d_behind};
    for (int k = 0; k < 2; k++) {
        PyObject *o = found[k];
        if (!o) {
            if (detection_clear(dets[k]) < 0) return NULL;
            continue;
        }
        double x[11];
        if (object_doubles(o, x) < 0) return NULL;
        const double kappa = PyFloat_AsDouble(PyTuple_GET_ITEM(o, 10));
        if (kappa == -1.0 && PyErr_Occurred()) return NULL;
        const double rate = (1.0 - kappa * lines[k]) / (1.0 - kappa * (0.5 * (x[3] + x[4]) + x[6] * since));
        if (detection_found_along(dets[k], o, gaps[k], lo_obj, hi_obj, since_obj, lines[k], x[5] * rate) < 0)
            return NULL;
    }
    Py_RETURN_NONE;
}

static PyObject *nearest(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if ((nargs != 8 && nargs != 9) || !PyList_CheckExact(args[0])) {
        PyErr_SetString(PyExc_TypeError, "nearest(objects: list, lo, hi, e_lo, e_hi, since, ahead, behind[, along])");
        return NULL;
    }
    PyObject *objects = args[0], *lo_obj = args[1], *hi_obj = args[2], *ahead = args[6], *behind = args[7];
    double lim[5];
    for (int i = 0; i < 5; i++) {
        lim[i] = PyFloat_AsDouble(args[i + 1]);
        if (lim[i] == -1.0 && PyErr_Occurred()) return NULL;
    }
    if (nargs == 9 && args[8] != Py_None) {
        double along[5];
        if (read_doubles(args[8], along, 5, "along")) return NULL;
        return nearest_along(args, lim, along);
    }
    const double lo = lim[0], hi = lim[1], e_lo = lim[2], e_hi = lim[3], since = lim[4];
    const double twice_mid = e_lo + e_hi;
    double best_ahead = Py_HUGE_VAL, best_behind = Py_HUGE_VAL;
    PyObject *front = NULL, *rear = NULL;
    for (Py_ssize_t i = 0; i < PyList_GET_SIZE(objects); i++) {
        PyObject *o = PyList_GET_ITEM(objects, i);
        double x[8];
        if (object_doubles(o, x) < 0) return NULL;
        const double shift = x[6] * since;
        if (x[4] + shift <= lo || x[3] + shift >= hi) continue;
        const double move = x[5] * since;
        const double a = x[1] + move, b = x[2] + move;
        if (a + b >= twice_mid) {
            if (a - e_hi < best_ahead) {
                best_ahead = a - e_hi;
                front = o;
            }
        } else if (e_lo - b < best_behind) {
            best_behind = e_lo - b;
            rear = o;
        }
    }
    PyObject *since_obj = args[5];
    if ((front ? detection_found(ahead, front, best_ahead, lo_obj, hi_obj, since_obj) : detection_clear(ahead)) < 0
        || (rear ? detection_found(behind, rear, best_behind, lo_obj, hi_obj, since_obj) : detection_clear(behind)) < 0)
        return NULL;
    Py_RETURN_NONE;
}

#define FASTCALL(name, doc) {#name, (PyCFunction)(void (*)(void))name, METH_FASTCALL, doc}
static PyMethodDef methods[] = {
    FASTCALL(bicycle_step, "bicycle_step(state, Fx, delta, h, substeps, params) -> (state, lateral_accel)"),
    FASTCALL(mamdani2, "mamdani2(peaks0, peaks1, table, coef, out_peaks, grid, x0, x1) -> crisp output"),
    FASTCALL(boxes, "boxes(results, controlled, known, dims, p_key, a_key, v_key) -> (ids, rows)"),
    FASTCALL(fill_obs, "fill_obs(out, values, norm, const) -> None"),
    FASTCALL(command, "command(params, action) -> (longitudinal, lateral)"),
    FASTCALL(observe, "observe(size, get, source, norm, const) -> array"),
    FASTCALL(reward, "reward(speed, error, a_lon, a_lat, crashed, params) -> (reward, terms)"),
    FASTCALL(sum_squares, "sum_squares(a) -> numpy.add.reduce(a * a, None) of a float64 array"),
    FASTCALL(rbf_smc, "rbf_smc(ctx, s, d, ds, dd, neg_two_w2, scale, k_lon, k_lat, update_lat) -> (f_lon, f_lat)"),
    FASTCALL(bp_pid_acc, "bp_pid_acc(ctx, x0, x1, e, t0, t1, t2, u, hi, lo, eta, alpha) -> u"),
    FASTCALL(bp_pid, "bp_pid(ctx, e_x, i_lon, de_x, e_y, i_lat, de_y, report, eta, alpha) -> (u_x, u_y)"),
    FASTCALL(reward_of, "reward_of(signals, obs, prev, params, crashed) -> (reward, terms)"),
    FASTCALL(env_step, "env_step(ctx, action) -> (observation, reward, terminated, truncated, info) "
                       "(EgoEnv._step)"),
    FASTCALL(plant_step, "plant_step(plant, packed, action) -> None (BicyclePlant.step)"),
    FASTCALL(trace_write, "trace_write(rows, width, signals, fallback, sigs, values) -> None"),
    FASTCALL(road_frame, "road_frame(view) -> None (RoadSensor.frame)"),
    FASTCALL(near, "near(objects, lo, hi, h, m) -> the objects within reach (SurroundSensor.scan's filter)"),
    FASTCALL(nearest, "nearest(objects, lo, hi, e_lo, e_hi, since, ahead, behind[, along]) -> None "
                      "(SurroundSensor._nearest)"),
    FASTCALL(fields, "fields() -> ((record, field), ...): what the glue kernels read and write on Python objects"),
    FASTCALL(lane_mean_curvature, "lane_mean_curvature(lane, s, ahead) -> LanePolyline.mean_curvature(s, ahead)"),
    FASTCALL(place, "place(ids, rows, front, reach, straight, frame, previous, dt, rated, low_edge) -> "
                    "(ids, rows, objects, speeds)"),
    {NULL, NULL, 0, NULL},
};
#undef FASTCALL

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "ego._native", "Native twins of ego's hottest numerical kernels.", -1,
    methods,
};

PyMODINIT_FUNC PyInit__native(void)
{
    PyObject *math = PyImport_ImportModule("math");
    if (!math) return NULL;
    math_hypot = PyObject_GetAttrString(math, "hypot");
    Py_DECREF(math);
    if (!math_hypot) return NULL;
    key_crashed = PyUnicode_InternFromString("crashed");
    key_progress = PyUnicode_InternFromString("progress");
    key_centring = PyUnicode_InternFromString("centring");
    key_discomfort = PyUnicode_InternFromString("discomfort");
    s_t = PyUnicode_InternFromString("t");
    if (!s_t) return NULL;
    if (!key_crashed || !key_progress || !key_centring || !key_discomfort) return NULL;
    if (intern_fields() < 0) return NULL;
    import_array(); /* numpy's C API: returns NULL with numpy's error when it cannot */
    return PyModule_Create(&module);
}
