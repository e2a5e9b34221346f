/* ego._fmu_guard: FMU calls under a watchdog (see ego/fmi/guard.py).
 *
 * Every FMI function ego calls goes through this module. Around each call it notes the
 * thread and the start time; a watchdog thread (started once, every signal blocked) checks
 * the calls in progress every limit/20 (1 ms .. 100 ms) and sends the calling thread
 * GUARD_SIGNAL when one has run past the limit. The handler of that signal, and of SIGINT,
 * SIGTERM, SIGSEGV, SIGBUS, SIGFPE, SIGILL and SIGABRT, leaves the FMU's code with
 * siglongjmp back to the guarded call when - and only when - the signal arrived while this
 * thread was inside an FMU function; otherwise it passes the signal to the handler that was
 * there before (Python's, faulthandler's, the default action). No Python code runs inside
 * a guarded call: the FMU's log messages go to a C buffer, handed to Python after the call.
 *
 * Per call the cost is one clock_gettime (vDSO) and a few stores: no system call. The
 * exchange of one communication step (set inputs, doStep, get outputs) is one call from
 * Python, cheaper than the three ctypes calls it replaces.
 *
 * After a jump the FMU instance is abandoned (its state is whatever the jump left): Python
 * never calls it again, nor frees it or unloads its library.
 */
#define PY_SSIZE_T_CLEAN
#ifndef _GNU_SOURCE
#define _GNU_SOURCE
#endif
#include <Python.h>
#include <pthread.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifdef SIGRTMIN
#define GUARD_SIGNAL (SIGRTMIN + 5)
#else
#define GUARD_SIGNAL SIGUSR2
#endif

#define NSLOTS 64

typedef struct {
    volatile sig_atomic_t used;
    volatile sig_atomic_t in_call;
    volatile sig_atomic_t fired;
    volatile int64_t start_ns;
    pthread_t thread;
    sigjmp_buf env;
} Slot;

static Slot slots[NSLOTS];
static __thread Slot *my_slot;
static pthread_mutex_t slots_lock = PTHREAD_MUTEX_INITIALIZER;
static volatile int64_t limit_ns = 30000000000LL;
static volatile int watchdog_started;
static int caught[] = {SIGINT, SIGTERM, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, 0};
static struct sigaction previous[65];
static volatile sig_atomic_t installed[65];
static void *alt_stack;

static PyObject *FmiStatus, *Aborted;

static int64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static void chain(int sig, siginfo_t *si, void *uc)
{
    struct sigaction *o = &previous[sig];
    if (o->sa_flags & SA_SIGINFO) {
        if (o->sa_sigaction) o->sa_sigaction(sig, si, uc);
        return;
    }
    if (o->sa_handler == SIG_IGN) return;
    if (o->sa_handler == SIG_DFL) {
        /* the default action: for a fault the instruction runs again and faults with it */
        signal(sig, SIG_DFL);
        if (sig != SIGSEGV && sig != SIGBUS && sig != SIGFPE && sig != SIGILL) raise(sig);
        return;
    }
    o->sa_handler(sig);
}

static void on_signal(int sig, siginfo_t *si, void *uc)
{
    Slot *s = my_slot;
    if (s != NULL && s->in_call) {
        if (sig == GUARD_SIGNAL && !s->fired) return; /* a late tick for a call that ended */
        s->in_call = 0;
        siglongjmp(s->env, sig);
    }
    if (sig == GUARD_SIGNAL) return;
    chain(sig, si, uc);
}

static void *watchdog(void *arg)
{
    (void)arg;
    sigset_t all;
    sigfillset(&all);
    pthread_sigmask(SIG_BLOCK, &all, NULL);
    for (;;) {
        int64_t lim = limit_ns;
        int64_t tick = lim / 20;
        if (tick < 1000000) tick = 1000000;
        if (tick > 100000000) tick = 100000000;
        struct timespec ts = {(time_t)(tick / 1000000000LL), (long)(tick % 1000000000LL)};
        nanosleep(&ts, NULL);
        int64_t now = now_ns();
        for (int i = 0; i < NSLOTS; i++) {
            Slot *s = &slots[i];
            if (s->used && s->in_call && !s->fired && now - s->start_ns > lim) {
                s->fired = 1;
                pthread_kill(s->thread, GUARD_SIGNAL);
            }
        }
    }
    return NULL;
}

static void after_fork_child(void)
{
    watchdog_started = 0;
    memset((void *)slots, 0, sizeof slots);
    my_slot = NULL;
}

static Slot *slot(void)
{
    Slot *s = my_slot;
    if (s != NULL) return s;
    pthread_mutex_lock(&slots_lock);
    for (int i = 0; i < NSLOTS; i++) {
        if (!slots[i].used) {
            s = &slots[i];
            s->thread = pthread_self();
            s->in_call = 0;
            s->fired = 0;
            s->used = 1;
            break;
        }
    }
    if (s != NULL && !watchdog_started) {
        pthread_t t;
        pthread_attr_t attr;
        pthread_attr_init(&attr);
        pthread_attr_setdetachstate(&attr, PTHREAD_CREATE_DETACHED);
        if (pthread_create(&t, &attr, watchdog, NULL) == 0) watchdog_started = 1;
        pthread_attr_destroy(&attr);
    }
    pthread_mutex_unlock(&slots_lock);
    my_slot = s;
    return s;
}

/* (Re)install the handlers: a signal whose handler is not ours any more (Python's
 * signal.signal replaced it) gets ours again, chained to the one found. A signal ignored
 * (SIG_IGN: a worker leaves Ctrl-C to its parent) stays ignored. */
static PyObject *install(PyObject *self, PyObject *unused)
{
    (void)self;
    (void)unused;
    if (alt_stack == NULL) { /* a handler for a stack overflow in the FMU needs a stack */
        stack_t cur;
        if (sigaltstack(NULL, &cur) == 0 && (cur.ss_flags & SS_DISABLE)) {
            size_t size = 1 << 16;
            alt_stack = malloc(size);
            if (alt_stack != NULL) {
                stack_t st = {.ss_sp = alt_stack, .ss_size = size, .ss_flags = 0};
                sigaltstack(&st, NULL);
            }
        } else {
            alt_stack = (void *)1;
        }
    }
    struct sigaction ours;
    memset(&ours, 0, sizeof ours);
    ours.sa_sigaction = on_signal;
    ours.sa_flags = SA_SIGINFO | SA_ONSTACK | SA_RESTART;
    sigemptyset(&ours.sa_mask);
    int sigs[16];
    int n = 0;
    for (int i = 0; caught[i]; i++) sigs[n++] = caught[i];
    sigs[n++] = GUARD_SIGNAL;
    for (int i = 0; i < n; i++) {
        int sig = sigs[i];
        struct sigaction cur;
        if (sigaction(sig, NULL, &cur) != 0) continue;
        if ((cur.sa_flags & SA_SIGINFO) && cur.sa_sigaction == on_signal) continue;
        if (!(cur.sa_flags & SA_SIGINFO) && cur.sa_handler == SIG_IGN && (sig == SIGINT || sig == SIGTERM)) continue;
        previous[sig] = cur;
        sigaction(sig, &ours, NULL);
        installed[sig] = 1;
    }
    slot();
    Py_RETURN_NONE;
}

static PyObject *set_limit(PyObject *self, PyObject *arg)
{
    (void)self;
    double s = PyFloat_AsDouble(arg);
    if (s == -1.0 && PyErr_Occurred()) return NULL;
    limit_ns = (int64_t)(s * 1e9);
    Py_RETURN_NONE;
}

static PyObject *get_limit(PyObject *self, PyObject *unused)
{
    (void)self;
    (void)unused;
    return PyFloat_FromDouble((double)limit_ns / 1e9);
}

/* -- the guarded region ------------------------------------------------------------------- */

#define GUARD_BEGIN(s, code)                                                                  \
    (s)->fired = 0;                                                                           \
    (s)->start_ns = now_ns();                                                                 \
    code = sigsetjmp((s)->env, 0);                                                            \
    if (code == 0) {                                                                          \
        __atomic_signal_fence(__ATOMIC_SEQ_CST);                                              \
        (s)->in_call = 1;                                                                     \
        __atomic_signal_fence(__ATOMIC_SEQ_CST);

#define GUARD_END(s)                                                                          \
    __atomic_signal_fence(__ATOMIC_SEQ_CST);                                                  \
    (s)->in_call = 0;                                                                         \
    }

/* after a jump: the signal unblocked again (the handler ran with it blocked), the
 * exception Aborted(signal number, seconds in the call) */
static PyObject *aborted(int code, int64_t start)
{
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, code);
    pthread_sigmask(SIG_UNBLOCK, &set, NULL);
    double secs = (double)(now_ns() - start) / 1e9;
    if ((code == SIGINT || code == SIGTERM) && previous[code].sa_handler != SIG_DFL &&
        previous[code].sa_handler != SIG_IGN) {
        PyErr_SetInterruptEx(code); /* Python's own handler sees the signal too */
    }
    PyObject *args = Py_BuildValue("(iid)", code == GUARD_SIGNAL ? 0 : code, code == GUARD_SIGNAL, secs);
    if (args != NULL) {
        PyErr_SetObject(Aborted, args);
        Py_DECREF(args);
    }
    return NULL;
}

/* -- the FMU's log messages ------------------------------------------------------------------ */

typedef struct Msg {
    struct Msg *next;
    int status;
    char *category;
    char *text;
} Msg;

typedef void *(*alloc_fn)(size_t, size_t);
typedef void (*free_fn)(void *);

typedef struct {
    void *logger;
    alloc_fn allocate;
    free_fn release;
    void *step_finished;
    void *env;
} Fmi2Callbacks;

typedef struct {
    PyObject_HEAD
    Msg *head, *tail;
    int count, dropped;
    Fmi2Callbacks cb;
} LogBuffer;

static char *dup_text(const char *s)
{
    if (s == NULL) s = "";
    size_t n = strnlen(s, 4000);
    char *out = malloc(n + 1);
    if (out != NULL) {
        memcpy(out, s, n);
        out[n] = 0;
    }
    return out;
}

static void add_msg(LogBuffer *b, int status, const char *category, const char *text)
{
    if (b == NULL) return;
    if (b->count >= 1000) {
        b->dropped++;
        return;
    }
    Msg *m = malloc(sizeof(Msg));
    if (m == NULL) return;
    m->next = NULL;
    m->status = status;
    m->category = dup_text(category);
    m->text = dup_text(text);
    if (b->tail) b->tail->next = m;
    else b->head = m;
    b->tail = m;
    b->count++;
}

static void fmi2_logger(void *env, const char *instance, int status, const char *category, const char *fmt, ...)
{
    (void)instance;
    char text[4000];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt ? fmt : "", ap);
    va_end(ap);
    add_msg((LogBuffer *)env, status, category, text);
}

static void fmi3_logger(void *env, int status, const char *category, const char *message)
{
    add_msg((LogBuffer *)env, status, category, message);
}

static void *fmi_calloc(size_t n, size_t size) { return calloc(n, size); }
static void fmi_free(void *p) { free(p); }

static void free_msgs(LogBuffer *b)
{
    Msg *m = b->head;
    while (m) {
        Msg *next = m->next;
        free(m->category);
        free(m->text);
        free(m);
        m = next;
    }
    b->head = b->tail = NULL;
    b->count = 0;
}

static PyObject *LogBuffer_new(PyTypeObject *type, PyObject *args, PyObject *kw)
{
    (void)args;
    (void)kw;
    LogBuffer *b = (LogBuffer *)type->tp_alloc(type, 0);
    if (b == NULL) return NULL;
    b->cb.logger = (void *)fmi2_logger;
    b->cb.allocate = fmi_calloc;
    b->cb.release = fmi_free;
    b->cb.step_finished = NULL;
    b->cb.env = b;
    return (PyObject *)b;
}

static void LogBuffer_dealloc(LogBuffer *b)
{
    free_msgs(b);
    Py_TYPE(b)->tp_free((PyObject *)b);
}

/* [(status, category, message)] of the messages since the last call; empties the buffer */
static PyObject *LogBuffer_drain(LogBuffer *b, PyObject *unused)
{
    (void)unused;
    PyObject *out = PyList_New(0);
    if (out == NULL) return NULL;
    for (Msg *m = b->head; m; m = m->next) {
        PyObject *item = Py_BuildValue("(iNN)", m->status, PyUnicode_DecodeUTF8(m->category, strlen(m->category), "replace"),
                                       PyUnicode_DecodeUTF8(m->text, strlen(m->text), "replace"));
        if (item == NULL || PyList_Append(out, item) < 0) {
            Py_XDECREF(item);
            Py_DECREF(out);
            free_msgs(b);
            return NULL;
        }
        Py_DECREF(item);
    }
    free_msgs(b);
    return out;
}

static PyObject *LogBuffer_addresses(LogBuffer *b, PyObject *unused)
{
    (void)unused;
    /* (environment, fmi2CallbackFunctions*, fmi3 log message function) */
    return Py_BuildValue("(KKK)", (unsigned long long)(uintptr_t)b, (unsigned long long)(uintptr_t)&b->cb,
                         (unsigned long long)(uintptr_t)fmi3_logger);
}

static PyObject *LogBuffer_pending(LogBuffer *b, void *closure)
{
    (void)closure;
    return PyLong_FromLong(b->count);
}

static PyMethodDef LogBuffer_methods[] = {
    {"drain", (PyCFunction)LogBuffer_drain, METH_NOARGS, "the messages so far (emptied)"},
    {"addresses", (PyCFunction)LogBuffer_addresses, METH_NOARGS, "(env, fmi2 callbacks, fmi3 logger)"},
    {NULL, NULL, 0, NULL},
};

static PyGetSetDef LogBuffer_getset[] = {
    {"pending", (getter)LogBuffer_pending, NULL, "messages waiting", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyTypeObject LogBufferType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "ego._fmu_guard.LogBuffer",
    .tp_basicsize = sizeof(LogBuffer),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_new = LogBuffer_new,
    .tp_dealloc = (destructor)LogBuffer_dealloc,
    .tp_methods = LogBuffer_methods,
    .tp_getset = LogBuffer_getset,
};

/* -- one guarded call of any FMI function ego uses --------------------------------------- */

typedef int (*f_p)(void *);
typedef void (*f_v)(void *);
typedef int (*f_setup2)(void *, int, double, double, int, double);
typedef int (*f_real2)(void *, const void *, size_t, void *);
typedef int (*f_real3)(void *, const void *, size_t, void *, size_t);
typedef int (*f_init3)(void *, bool, double, double, bool, double);
typedef void *(*f_inst2)(const char *, int, const char *, const char *, const void *, int, int);
typedef void *(*f_inst3)(const char *, const char *, const char *, bool, bool, bool, bool, const void *, size_t, void *,
                         void *, void *);

static uintptr_t as_ptr(PyObject *o)
{
    if (o == Py_None) return 0;
    if (PyBytes_Check(o)) return (uintptr_t)PyBytes_AS_STRING(o);
    return (uintptr_t)PyLong_AsUnsignedLongLongMask(o);
}

/* call(kind, function address, *args) -> int (the status, or the instance's address):
 * kind "p" int f(c), "v" void f(c), "setup2", "real2", "real3", "init3", "inst2", "inst3" */
static PyObject *call(PyObject *self, PyObject *args)
{
    (void)self;
    Py_ssize_t n = PyTuple_GET_SIZE(args);
    if (n < 2) {
        PyErr_SetString(PyExc_TypeError, "call(kind, address, *args)");
        return NULL;
    }
    const char *kind = PyUnicode_AsUTF8(PyTuple_GET_ITEM(args, 0));
    if (kind == NULL) return NULL;
    void *fn = (void *)as_ptr(PyTuple_GET_ITEM(args, 1));
    uintptr_t a[12] = {0};
    double d[4] = {0};
    int na = 0, nd = 0;
    for (Py_ssize_t i = 2; i < n; i++) {
        PyObject *o = PyTuple_GET_ITEM(args, i);
        if (PyFloat_Check(o)) {
            if (nd < 4) d[nd++] = PyFloat_AS_DOUBLE(o);
        } else if (na < 12) {
            a[na++] = as_ptr(o);
        }
    }
    if (PyErr_Occurred()) return NULL;
    if (fn == NULL) {
        PyErr_SetString(PyExc_ValueError, "no such FMI function");
        return NULL;
    }
    static const char *kinds[] = {"p", "v", "setup2", "real2", "real3", "init3", "inst2", "inst3", NULL};
    int k = 0;
    while (kinds[k] && strcmp(kinds[k], kind)) k++;
    if (kinds[k] == NULL) {
        PyErr_Format(PyExc_ValueError, "unknown call kind %s", kind);
        return NULL;
    }
    Slot *s = slot();
    if (s == NULL) {
        PyErr_SetString(PyExc_RuntimeError, "too many threads calling FMUs");
        return NULL;
    }
    volatile uintptr_t result = 0;
    int code;
    PyThreadState *ts = PyEval_SaveThread();
    GUARD_BEGIN(s, code)
    switch (k) {
    case 0: result = (uintptr_t)(intptr_t)((f_p)fn)((void *)a[0]); break;
    case 1: ((f_v)fn)((void *)a[0]); break;
    case 2: result = (uintptr_t)(intptr_t)((f_setup2)fn)((void *)a[0], (int)a[1], d[0], d[1], (int)a[2], d[2]); break;
    case 3: result = (uintptr_t)(intptr_t)((f_real2)fn)((void *)a[0], (void *)a[1], (size_t)a[2], (void *)a[3]); break;
    case 4:
        result = (uintptr_t)(intptr_t)((f_real3)fn)((void *)a[0], (void *)a[1], (size_t)a[2], (void *)a[3], (size_t)a[2]);
        break;
    case 5: result = (uintptr_t)(intptr_t)((f_init3)fn)((void *)a[0], a[1] != 0, d[0], d[1], a[2] != 0, d[2]); break;
    case 6:
        result = (uintptr_t)((f_inst2)fn)((const char *)a[0], (int)a[1], (const char *)a[2], (const char *)a[3],
                                          (const void *)a[4], (int)a[5], (int)a[6]);
        break;
    default:
        result = (uintptr_t)((f_inst3)fn)((const char *)a[0], (const char *)a[1], (const char *)a[2], a[3] != 0,
                                          a[4] != 0, a[5] != 0, a[6] != 0, (const void *)a[7], (size_t)a[8],
                                          (void *)a[9], (void *)a[10], (void *)a[11]);
    }
    GUARD_END(s)
    PyEval_RestoreThread(ts);
    if (code != 0) return aborted(code, s->start_ns);
    if (k >= 6) return PyLong_FromUnsignedLongLong(result);
    return PyLong_FromLong((long)(intptr_t)result);
}

/* -- the hot path: one communication step ------------------------------------------------- */

typedef struct {
    PyObject_HEAD
    void *comp;
    int v3;
    void *set, *get, *step;
    void *in_vr, *out_vr;
    Py_ssize_t n_in, n_out;
    double *in_val, *out_val;
    bool flags[3];
    double last_t;
    LogBuffer *log;
    PyObject *on_log;
} Stepper;

static void Stepper_dealloc(Stepper *st)
{
    free(st->in_vr);
    free(st->out_vr);
    free(st->in_val);
    free(st->out_val);
    Py_XDECREF(st->log);
    Py_XDECREF(st->on_log);
    Py_TYPE(st)->tp_free((PyObject *)st);
}

static int fill_vrs(PyObject *seq, void **out, Py_ssize_t *n)
{
    PyObject *fast = PySequence_Fast(seq, "value references: a sequence");
    if (fast == NULL) return -1;
    *n = PySequence_Fast_GET_SIZE(fast);
    uint32_t *vr = calloc((size_t)(*n ? *n : 1), sizeof(uint32_t));
    if (vr == NULL) {
        Py_DECREF(fast);
        PyErr_NoMemory();
        return -1;
    }
    for (Py_ssize_t i = 0; i < *n; i++) vr[i] = (uint32_t)PyLong_AsUnsignedLongMask(PySequence_Fast_GET_ITEM(fast, i));
    Py_DECREF(fast);
    *out = vr;
    return PyErr_Occurred() ? -1 : 0;
}

/* Stepper(v3, component, set, get, doStep, in_vrs, out_vrs, log, on_log) */
static int Stepper_init(Stepper *st, PyObject *args, PyObject *kw)
{
    (void)kw;
    int v3;
    unsigned long long comp, set, get, step;
    PyObject *ins, *outs, *log, *on_log;
    if (!PyArg_ParseTuple(args, "pKKKKOOO!O", &v3, &comp, &set, &get, &step, &ins, &outs, &LogBufferType, &log, &on_log))
        return -1;
    st->v3 = v3;
    st->comp = (void *)(uintptr_t)comp;
    st->set = (void *)(uintptr_t)set;
    st->get = (void *)(uintptr_t)get;
    st->step = (void *)(uintptr_t)step;
    if (fill_vrs(ins, &st->in_vr, &st->n_in) < 0 || fill_vrs(outs, &st->out_vr, &st->n_out) < 0) return -1;
    st->in_val = calloc((size_t)(st->n_in ? st->n_in : 1), sizeof(double));
    st->out_val = calloc((size_t)(st->n_out ? st->n_out : 1), sizeof(double));
    if (st->in_val == NULL || st->out_val == NULL) {
        PyErr_NoMemory();
        return -1;
    }
    Py_INCREF(log);
    st->log = (LogBuffer *)log;
    Py_INCREF(on_log);
    st->on_log = on_log;
    return 0;
}

static int deliver_logs(LogBuffer *log, PyObject *on_log)
{
    if (log->count == 0 || on_log == Py_None) return 0;
    PyObject *msgs = LogBuffer_drain(log, NULL);
    if (msgs == NULL) return -1;
    for (Py_ssize_t i = 0; i < PyList_GET_SIZE(msgs); i++) {
        PyObject *r = PyObject_CallObject(on_log, PyList_GET_ITEM(msgs, i));
        if (r == NULL) {
            Py_DECREF(msgs);
            return -1;
        }
        Py_DECREF(r);
    }
    Py_DECREF(msgs);
    return 0;
}

/* exchange(values, t, h) -> outputs (a tuple): inputs set at t, doStep(t, h), outputs read;
 * FmiStatus(stage, status) when the FMU answers error or worse; Aborted(...) after a jump */
static PyObject *Stepper_exchange(Stepper *st, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 3) {
        PyErr_SetString(PyExc_TypeError, "exchange(values, t, h)");
        return NULL;
    }
    if (st->n_in) {
        PyObject *fast = PySequence_Fast(args[0], "values: a sequence");
        if (fast == NULL) return NULL;
        if (PySequence_Fast_GET_SIZE(fast) != st->n_in) {
            Py_DECREF(fast);
            PyErr_Format(PyExc_ValueError, "%zd input values expected", st->n_in);
            return NULL;
        }
        for (Py_ssize_t i = 0; i < st->n_in; i++) {
            double v = PyFloat_AsDouble(PySequence_Fast_GET_ITEM(fast, i));
            if (v == -1.0 && PyErr_Occurred()) {
                Py_DECREF(fast);
                return NULL;
            }
            st->in_val[i] = v;
        }
        Py_DECREF(fast);
    }
    double t = PyFloat_AsDouble(args[1]);
    double h = PyFloat_AsDouble(args[2]);
    if (PyErr_Occurred()) return NULL;
    Slot *s = my_slot ? my_slot : slot();
    if (s == NULL) {
        PyErr_SetString(PyExc_RuntimeError, "too many threads calling FMUs");
        return NULL;
    }
    volatile int status = 0;
    volatile int stage = 0; /* 0 set inputs, 1 doStep, 2 get outputs */
    int code;
    void *comp = st->comp;
    size_t n_in = (size_t)st->n_in, n_out = (size_t)st->n_out;
    PyThreadState *ts = PyEval_SaveThread();
    GUARD_BEGIN(s, code)
    if (st->v3) {
        if (n_in) status = ((f_real3)st->set)(comp, st->in_vr, n_in, st->in_val, n_in);
        if (status <= 1) {
            stage = 1;
            status = ((int (*)(void *, double, double, bool, bool *, bool *, bool *, double *))st->step)(
                comp, t, h, true, &st->flags[0], &st->flags[1], &st->flags[2], &st->last_t);
        }
        if (status <= 1 && n_out) {
            stage = 2;
            status = ((f_real3)st->get)(comp, st->out_vr, n_out, st->out_val, n_out);
        }
    } else {
        if (n_in) status = ((f_real2)st->set)(comp, st->in_vr, n_in, st->in_val);
        if (status <= 1) {
            stage = 1;
            status = ((int (*)(void *, double, double, int))st->step)(comp, t, h, 1);
        }
        if (status <= 1 && n_out) {
            stage = 2;
            status = ((f_real2)st->get)(comp, st->out_vr, n_out, st->out_val);
        }
    }
    GUARD_END(s)
    PyEval_RestoreThread(ts);
    if (code != 0) return aborted(code, s->start_ns);
    if (st->log->count && deliver_logs(st->log, st->on_log) < 0) return NULL;
    if (status > 1) {
        PyObject *a = Py_BuildValue("(ii)", (int)stage, (int)status);
        if (a != NULL) {
            PyErr_SetObject(FmiStatus, a);
            Py_DECREF(a);
        }
        return NULL;
    }
    PyObject *out = PyTuple_New(st->n_out);
    if (out == NULL) return NULL;
    for (Py_ssize_t i = 0; i < st->n_out; i++) {
        PyObject *f = PyFloat_FromDouble(st->out_val[i]);
        if (f == NULL) {
            Py_DECREF(out);
            return NULL;
        }
        PyTuple_SET_ITEM(out, i, f);
    }
    return out;
}

static PyMethodDef Stepper_methods[] = {
    {"exchange", (PyCFunction)(void (*)(void))Stepper_exchange, METH_FASTCALL, "one communication step"},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject StepperType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "ego._fmu_guard.Stepper",
    .tp_basicsize = sizeof(Stepper),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_new = PyType_GenericNew,
    .tp_init = (initproc)Stepper_init,
    .tp_dealloc = (destructor)Stepper_dealloc,
    .tp_methods = Stepper_methods,
};

/* a test's helper: a guarded call of a function that never returns */
static PyObject *hang(PyObject *self, PyObject *unused)
{
    (void)self;
    (void)unused;
    Slot *s = slot();
    int code;
    PyThreadState *ts = PyEval_SaveThread();
    GUARD_BEGIN(s, code)
    for (;;) pause();
    GUARD_END(s)
    PyEval_RestoreThread(ts);
    return aborted(code, s->start_ns);
}

static PyMethodDef methods[] = {
    {"install", install, METH_NOARGS, "(re)install the signal handlers"},
    {"set_limit", set_limit, METH_O, "the time limit of one FMU call, in seconds"},
    {"get_limit", get_limit, METH_NOARGS, "the time limit of one FMU call, in seconds"},
    {"call", call, METH_VARARGS, "one guarded call of an FMI function"},
    {"hang", hang, METH_NOARGS, "a guarded call that never returns (tests)"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "ego._fmu_guard", NULL, -1, methods};

PyMODINIT_FUNC PyInit__fmu_guard(void)
{
    if (PyType_Ready(&LogBufferType) < 0 || PyType_Ready(&StepperType) < 0) return NULL;
    PyObject *m = PyModule_Create(&module);
    if (m == NULL) return NULL;
    FmiStatus = PyErr_NewException("ego._fmu_guard.FmiStatus", NULL, NULL);
    Aborted = PyErr_NewException("ego._fmu_guard.Aborted", NULL, NULL);
    Py_INCREF(&LogBufferType);
    Py_INCREF(&StepperType);
    PyModule_AddObject(m, "FmiStatus", FmiStatus);
    PyModule_AddObject(m, "Aborted", Aborted);
    PyModule_AddObject(m, "LogBuffer", (PyObject *)&LogBufferType);
    PyModule_AddObject(m, "Stepper", (PyObject *)&StepperType);
    PyModule_AddIntConstant(m, "TIMEOUT_SIGNAL", GUARD_SIGNAL);
    pthread_atfork(NULL, NULL, after_fork_child);
    return m;
}
