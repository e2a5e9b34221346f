/*
 * Native twins of ego's two hottest numerical kernels.
 *
 *  - bicycle_step: report 000's nonlinear bicycle integrated by classical RK4, the same
 *    arithmetic, term for term, as NonlinearBicycle.rhs + ego.models.integrate.unrolled_rk4;
 *  - mamdani2: the closed-form Mamdani centroid of ego.control.fuzzy_engine for two inputs
 *    and one output (FastMamdani.single2).
 *
 * The Python implementations stay the references: the tests require these kernels to agree
 * with them (and with scikit-fuzzy) on random inputs. Compiled with -ffp-contract=off so the
 * arithmetic is not fused differently from CPython's. When the extension is missing, ego
 * falls back to the Python code (slower, same results).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>

#include "_bicycle.h"

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

static PyMethodDef methods[] = {
    {"bicycle_step", (PyCFunction)(void (*)(void))bicycle_step, METH_FASTCALL,
     "bicycle_step(state, Fx, delta, h, substeps, params) -> (state, lateral_accel)"},
    {"mamdani2", (PyCFunction)(void (*)(void))mamdani2, METH_FASTCALL,
     "mamdani2(peaks0, peaks1, table, coef, out_peaks, grid, x0, x1) -> crisp output"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "ego._native", "Native twins of ego's hottest numerical kernels.", -1,
    methods,
};

PyMODINIT_FUNC PyInit__native(void) { return PyModule_Create(&module); }
