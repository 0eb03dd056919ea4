/*
 * _engine.c -- the harness's compiled evaluation path (CPython extension module).
 *
 * Everything the co-simulation does once per sample, done in C and called
 * once per move:
 *
 *  - plan a move with the FMU's own generator core (fmu_src/djl_*.c: the
 *    very code the FMU runs, linked in, not re-implemented), shape it with the
 *    FMU's input shaper (djl_shaper.c, shaper_source = 1) and sample it on
 *    the FMU's time grid (start time + n Te, the motion starting at the first
 *    sample at or after t_start: the core's djl_start_offset, which the FMU
 *    calls too); the FMU's parameters are read by name through the table the
 *    FMU uses (djl_vars.h, generated from harness/fmu/spec.py);
 *  - synchronise the Z move (bisection on v_max, the same arithmetic as
 *    harness.simulation.fmu_axis.FMUAxis.sync_velocity);
 *  - step the scheduled plant: every mode advanced exactly over each step for
 *    the input a_k + j_k tau (constant jerk over the step), with its frequency
 *    given per step (the same arithmetic as harness.plant.step_mode_jerk).
 *
 * Arrays are exchanged through the buffer protocol (numpy arrays allocated by
 * the Python side, harness/engine.py): the module needs no numpy headers.
 * Only CPython's limited API of 3.11 (Py_LIMITED_API, set by CMake for an abi3 wheel; the
 * buffer protocol is in it from 3.11): the Plan type is made from a spec, no macros that
 * reach into objects; the same code builds version-specific on 3.10.
 * No FMI code here.  Units: SI.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <math.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "djl_core.h"
#define DJL_VARS_PARAMETERS /* djl_param_table: where each FMU parameter is stored */
#define DJL_VARS_TABLES     /* djl_var_table: every variable (run_program) */
#include "djl_vars.h"
#include "fmu_instance.h"   /* the FMU's model, for run_program (no FMI layer) */

/* 2 pi as Python's 2.0 * math.pi (doubling is exact) */
#define DJL_TWO_PI 6.283185307179586476925286766559

static PyObject *PlanError; /* subclass of ValueError */

/* ---------------------------------------------------------------- Plan */

typedef struct {
    PyObject_HEAD
    djl_plan plan;
    djl_shaper shaper; /* the FMU's input shaper (n = 0: none), designed with the plan */
    double t_start;    /* s, requested start of the motion */
    double start_time; /* s, start of the sample grid */
    double offset;     /* samples from start_time to the motion start (integral) */
    int shifted;       /* t_start was not on the grid: moved to the next sample */
} PlanObject;

static PyTypeObject *PlanType; /* created from plan_spec at import */

static int get_double(PyObject *v, const char *key, double *out)
{
    double x;
    if (PyBool_Check(v) || !(PyFloat_Check(v) || PyLong_Check(v))) {
        PyErr_Format(PyExc_TypeError, "parameter %s must be a number, got %R", key, v);
        return -1;
    }
    x = PyFloat_AsDouble(v);
    if (x == -1.0 && PyErr_Occurred()) {
        PyErr_Clear();
        PyErr_Format(PyExc_ValueError, "parameter %s = %R is not representable as a double",
                     key, v);
        return -1;
    }
    *out = x;
    return 0;
}

static int get_int32(PyObject *v, const char *key, int32_t *out)
{
    long x;
    if (PyFloat_Check(v)) {
        double d = PyFloat_AsDouble(v);
        if (!(isfinite(d) && d == floor(d) && fabs(d) < 2147483647.0)) {
            PyErr_Format(PyExc_ValueError, "parameter %s must be an integer, got %R", key, v);
            return -1;
        }
        *out = (int32_t)d;
        return 0;
    }
    if (PyBool_Check(v) || !PyLong_Check(v)) {
        PyErr_Format(PyExc_TypeError, "parameter %s must be an integer, got %R", key, v);
        return -1;
    }
    x = PyLong_AsLong(v);
    if ((x == -1 && PyErr_Occurred()) || x < INT32_MIN || x > INT32_MAX) {
        PyErr_Clear();
        PyErr_Format(PyExc_ValueError, "parameter %s = %R is out of the Int32 range", key, v);
        return -1;
    }
    *out = (int32_t)x;
    return 0;
}

/* An array parameter: a sequence of at most n numbers into out (type 'R': doubles; 'I':
 * int32_t), the elements not given left as they are. */
static int get_array(PyObject *v, const char *key, char type, void *out, int n)
{
    PyObject *seq = PySequence_Tuple(v);
    Py_ssize_t len, i;
    if (!seq) {
        PyErr_Clear();
        PyErr_Format(PyExc_TypeError, "parameter %s must be a sequence of numbers", key);
        return -1;
    }
    len = PyTuple_Size(seq);
    if (len > n) {
        Py_DECREF(seq);
        PyErr_Format(PyExc_ValueError, "parameter %s has %zd values, at most %d", key, len, n);
        return -1;
    }
    for (i = 0; i < len; i++) {
        PyObject *item = PyTuple_GetItem(seq, i);
        int rc = type == 'R' ? get_double(item, key, (double *)out + i)
                             : get_int32(item, key, (int32_t *)out + i);
        if (rc < 0) {
            Py_DECREF(seq);
            return -1;
        }
    }
    Py_DECREF(seq);
    return 0;
}

/* The FMU parameters the engine takes: the core's, the input shaper's, the replayed
 * table's and t_start (not jerk_source: the engine plans the parametric move, jerk times
 * from the parameters). */
typedef struct {
    djl_params p;
    djl_shaper_params sp;
    djl_table table;
    double t_start;
} engine_params;

/* Where the table's parameter is stored in e, NULL if the engine does not take it. */
static void *param_field(engine_params *e, const djl_param_info *pi)
{
    switch (pi->home) {
    case DJL_HOME_PARAMS: return (char *)&e->p + pi->offset;
    case DJL_HOME_SHAPER: return (char *)&e->sp + pi->offset;
    case DJL_HOME_TABLE: return (char *)&e->table + pi->offset;
    case DJL_HOME_T_START: return &e->t_start;
    default: return NULL;
    }
}

/* Fill e (from the defaults) from a dict of FMU parameter names. */
static int parse_params(PyObject *dict, engine_params *out)
{
    PyObject *key, *value;
    Py_ssize_t pos = 0;
    engine_params e;
    djl_params_default(&e.p);
    djl_shaper_params_default(&e.sp);
    djl_table_default(&e.table);
    e.t_start = 0.0;
    if (!PyDict_Check(dict)) {
        PyErr_SetString(PyExc_TypeError, "params must be a dict of FMU parameter names");
        return -1;
    }
    while (PyDict_Next(dict, &pos, &key, &value)) {
        const djl_param_info *pi = NULL;
        const char *k;
        void *field = NULL;
        int i, rc;
        if (!PyUnicode_Check(key)) {
            PyErr_Format(PyExc_TypeError, "parameter names must be strings, got %R", key);
            return -1;
        }
        k = PyUnicode_AsUTF8AndSize(key, NULL);
        if (!k) return -1;
        for (i = 0; i < DJL_N_PARAMS && !pi; i++)
            if (!strcmp(k, djl_param_table[i].name)) pi = &djl_param_table[i];
        if (pi) field = param_field(&e, pi);
        if (!field) {
            PyErr_Format(PyExc_KeyError, "unknown generator parameter %R", key);
            return -1;
        }
        if (pi->size > 1)
            rc = get_array(value, k, pi->type == 'R' ? 'R' : 'I', field, pi->size);
        else if (pi->type == 'R')
            rc = get_double(value, k, (double *)field);
        else
            rc = get_int32(value, k, (int32_t *)field);
        if (rc < 0) return -1;
    }
    *out = e;
    return 0;
}

static int set_attr_new(PyObject *obj, const char *name, PyObject *value)
{
    int rc;
    if (!value) return -1;
    rc = PyObject_SetAttrString(obj, name, value);
    Py_DECREF(value);
    return rc;
}

static PyObject *raise_plan_error(const djl_error *err, djl_status st)
{
    PyObject *exc, *args;
    args = Py_BuildValue("(s)", err->message);
    if (!args) return NULL;
    exc = PyObject_Call(PlanError, args, NULL);
    Py_DECREF(args);
    if (!exc) return NULL;
    if (set_attr_new(exc, "status", PyUnicode_FromString(djl_status_name(st))) < 0 ||
        set_attr_new(exc, "param", PyUnicode_FromString(err->param)) < 0 ||
        set_attr_new(exc, "value", PyFloat_FromDouble(err->value)) < 0) {
        Py_DECREF(exc);
        return NULL;
    }
    PyErr_SetObject(PlanError, exc);
    Py_DECREF(exc);
    return NULL;
}

/* An error of the engine's own, in the core's form. */
static djl_status set_engine_error(djl_error *err, const char *param, double value,
                                   const char *message)
{
    err->status = DJL_E_PARAM;
    strncpy(err->param, param, sizeof err->param - 1);
    err->param[sizeof err->param - 1] = '\0';
    err->value = value;
    strncpy(err->message, message, sizeof err->message - 1);
    err->message[sizeof err->message - 1] = '\0';
    return DJL_E_PARAM;
}

/* Plan p (profile 4: the table t) into plan and place it on the grid of start_time (the
 * FMU's ensure_plan, without FMI): the core's status and error. */
static djl_status plan_into(const djl_params *p, const djl_table *t, double t_start,
                            double start_time, djl_plan *plan, djl_error *err, double *offset,
                            int *shifted)
{
    djl_status st = p->profile == DJL_PROFILE_TABLE ? djl_plan_table(p, t, plan, err)
                                                    : djl_plan_motion(p, plan, err);
    if (st != DJL_OK) return st;
    return djl_start_offset(t_start, start_time, p->Te, offset, shifted, err);
}

/* The input shaper of sp for the plan (the FMU's design_shaper): shaper_source = 2 needs the
 * input f_mode, which the engine does not have (PlanError naming shaper_source). */
static djl_status shaper_into(const djl_shaper_params *sp, const djl_plan *plan, djl_shaper *sh,
                              djl_error *err)
{
    djl_status st;
    if (sp->kind != DJL_SHAPER_NONE && sp->source == DJL_SHAPER_SOURCE_F_MODE)
        return set_engine_error(err, "shaper_source", (double)sp->source,
                                "shaper_source = 2: the impulses are timed by the input f_mode, "
                                "which the compiled engine does not have (it plans the "
                                "parametric move: use shaper_source = 1, or the FMU)");
    st = djl_shaper_design(sp, plan->p.Te, 0.0, sh, err);
    if (st != DJL_OK) return st;
    if (sh->n > 0 && !((double)plan->k_end + sh->d_max <= (double)DJL_MAX_MOTION_SAMPLES))
        return set_engine_error(err, "shaper", (double)sp->kind,
                                "invalid parameter shaper: the motion and the shaper's last "
                                "impulse exceed the samples a motion may take");
    return DJL_OK;
}

static PyObject *engine_plan(PyObject *self, PyObject *args, PyObject *kwds)
{
    static char *kwlist[] = {"params", "start_time", NULL};
    PyObject *dict;
    double start_time = 0.0;
    engine_params *e;
    djl_error err;
    djl_status st;
    PlanObject *obj;
    (void)self;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "O|d", kwlist, &dict, &start_time))
        return NULL;
    e = (engine_params *)PyMem_Malloc(sizeof *e); /* the table: kept off the stack */
    if (!e) return PyErr_NoMemory();
    obj = PyObject_New(PlanObject, PlanType);
    if (!obj) {
        PyMem_Free(e);
        return NULL;
    }
    if (parse_params(dict, e) < 0) {
        PyMem_Free(e);
        Py_DECREF(obj);
        return NULL;
    }
    obj->t_start = e->t_start;
    obj->start_time = start_time;
    memset(&err, 0, sizeof err);
    st = plan_into(&e->p, &e->table, obj->t_start, start_time, &obj->plan, &err, &obj->offset,
                   &obj->shifted);
    if (st == DJL_OK) st = shaper_into(&e->sp, &obj->plan, &obj->shaper, &err);
    PyMem_Free(e);
    if (st != DJL_OK) {
        Py_DECREF(obj);
        return raise_plan_error(&err, st);
    }
    return (PyObject *)obj;
}

/* A C-contiguous float64 buffer of at least n elements (writable if asked). */
static int get_buffer(PyObject *o, Py_buffer *view, Py_ssize_t n, const char *what, int writable)
{
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(o, view, flags) < 0) return -1;
    if (view->itemsize != 8 || !view->format || strcmp(view->format, "d") != 0 ||
        view->len < n * 8) {
        PyErr_Format(PyExc_ValueError, "%s must be a C-contiguous float64 array of at least %zd "
                     "values", what, n);
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

#define get_out_buffer(o, view, n, what) get_buffer(o, view, n, what, 1)
#define get_in_buffer(o, view, n, what) get_buffer(o, view, n, what, 0)

#define N_SAMPLE_VARS 7

/* Plan.sample_into(out, n0, step, count): out[i, k] for k < count holds variable i
 * (x, v, a, j, x_AL, v_AL, a_AL) at the FMU sample n0 + k * step. */
static PyObject *plan_sample_into(PlanObject *self, PyObject *args)
{
    PyObject *out;
    long long n0, step;
    Py_ssize_t count, k;
    Py_buffer view;
    double *buf;
    int32_t cursor = 0, cursors[DJL_MAX_SHAPER_IMPULSES] = {0};
    djl_sample s;
    if (!PyArg_ParseTuple(args, "OLLn", &out, &n0, &step, &count)) return NULL;
    if (count < 0 || step < 1) {
        PyErr_SetString(PyExc_ValueError, "count must be >= 0 and step >= 1");
        return NULL;
    }
    if (get_out_buffer(out, &view, (Py_ssize_t)N_SAMPLE_VARS * count, "out") < 0) return NULL;
    buf = (double *)view.buf;
    Py_BEGIN_ALLOW_THREADS
    for (k = 0; k < count; k++) {
        double u = (double)(n0 + (long long)k * step) - self->offset;
        djl_shaper_eval(&self->shaper, &self->plan, u, self->offset, NULL, 0, &cursor, cursors,
                        &s);
        buf[k] = s.x;
        buf[count + k] = s.v;
        buf[2 * count + k] = s.a;
        buf[3 * count + k] = s.j;
        buf[4 * count + k] = s.x_al;
        buf[5 * count + k] = s.v_al;
        buf[6 * count + k] = s.a_al;
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&view);
    Py_RETURN_NONE;
}

/* Plan.at(n): (x, v, a, j, x_AL, v_AL, a_AL, done, segment) at FMU sample n (may be fractional). */
static PyObject *plan_at(PlanObject *self, PyObject *args)
{
    double n;
    int32_t cursor = 0, cursors[DJL_MAX_SHAPER_IMPULSES] = {0};
    djl_sample s;
    if (!PyArg_ParseTuple(args, "d", &n)) return NULL;
    djl_shaper_eval(&self->shaper, &self->plan, n - self->offset, self->offset, NULL, 0, &cursor,
                    cursors, &s);
    return Py_BuildValue("(dddddddii)", s.x, s.v, s.a, s.j, s.x_al, s.v_al, s.a_al, s.done,
                         s.segment);
}

/* Plan.eval(times, side="right") -> (x, v, a, j): the shaped profile at times (s, FMU time;
 * a time within 1e-9 of a sample of the grid start_time + n Te is taken as that sample, whose
 * values are sample_into's bit for bit), the limits from the right (side="right": the jerk
 * over the interval that starts there) or from the left ("left": the jerk over the interval
 * that ends there).  numpy arrays (numpy is imported, not compiled against). */
static PyObject *plan_eval(PlanObject *self, PyObject *args, PyObject *kwds)
{
    static char *kwlist[] = {"times", "side", NULL};
    PyObject *times, *np, *arr = NULL, *out = NULL, *res = NULL;
    const char *side = "right";
    Py_buffer bt, bo;
    Py_ssize_t n, k;
    int left;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "O|s", kwlist, &times, &side)) return NULL;
    if (strcmp(side, "right") != 0 && strcmp(side, "left") != 0) {
        PyErr_Format(PyExc_ValueError, "side must be \"right\" or \"left\", got %R",
                     PyTuple_GetItem(args, PyTuple_Size(args) > 1 ? 1 : 0));
        return NULL;
    }
    left = side[0] == 'l';
    np = PyImport_ImportModule("numpy"); /* deferred: the module needs no numpy headers */
    if (!np) return NULL;
    arr = PyObject_CallMethod(np, "ascontiguousarray", "(O)", times);
    if (arr) {
        PyObject *flat = PyObject_CallMethod(arr, "ravel", NULL);
        Py_DECREF(arr);
        arr = flat ? PyObject_CallMethod(flat, "astype", "(s)", "float64") : NULL;
        Py_XDECREF(flat);
    }
    if (!arr) goto done;
    if (get_in_buffer(arr, &bt, 0, "times") < 0) goto done;
    n = bt.len / 8;
    out = PyObject_CallMethod(np, "empty", "((nn))", (Py_ssize_t)4, n);
    if (!out || get_out_buffer(out, &bo, 4 * n, "out") < 0) {
        PyBuffer_Release(&bt);
        goto done;
    }
    {
        const double *t = bt.buf;
        double *o = bo.buf, Te = self->plan.p.Te;
        int32_t cursor = 0, cursors[DJL_MAX_SHAPER_IMPULSES] = {0};
        djl_sample smp;
        Py_BEGIN_ALLOW_THREADS
        for (k = 0; k < n; k++) {
            double r = (t[k] - self->start_time) / Te, rr = floor(r + 0.5);
            if (fabs(r - rr) <= 1e-9 * (1.0 + fabs(rr))) r = rr; /* a sample of the grid */
            djl_shaper_eval(&self->shaper, &self->plan, r - self->offset, self->offset, NULL,
                            left, &cursor, cursors, &smp);
            o[k] = smp.x;
            o[n + k] = smp.v;
            o[2 * n + k] = smp.a;
            o[3 * n + k] = smp.j;
        }
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&bo);
    PyBuffer_Release(&bt);
    res = Py_BuildValue("(NNNN)", PySequence_GetItem(out, 0), PySequence_GetItem(out, 1),
                        PySequence_GetItem(out, 2), PySequence_GetItem(out, 3));
done:
    Py_XDECREF(out);
    Py_XDECREF(arr);
    Py_DECREF(np);
    return res;
}

/* Plan.breakpoints() -> list: the times (s, FMU time, sorted, each once) at which the shaped
 * profile's jerk may change: each piece start of the plan, delayed by each impulse.  Between
 * two of them the profile is one cubic: evaluate it inside (at the midpoint, say), where the
 * side of a breakpoint cannot be mistaken by rounding. */
static PyObject *plan_breakpoints(PlanObject *self, PyObject *noargs)
{
    PyObject *list = PyList_New(0), *uniq = NULL;
    int32_t i, q, nq = self->shaper.n > 0 ? self->shaper.n : 1;
    Py_ssize_t k;
    (void)noargs;
    if (!list) return NULL;
    for (i = 0; i < self->plan.n_pieces; i++) {
        for (q = 0; q < nq; q++) {
            double d = self->shaper.n > 0 ? self->shaper.d[q] : 0.0;
            double t = self->start_time +
                       (self->offset + (double)self->plan.piece[i].k + d) * self->plan.p.Te;
            PyObject *f = PyFloat_FromDouble(t);
            if (!f || PyList_Append(list, f) < 0) {
                Py_XDECREF(f);
                Py_DECREF(list);
                return NULL;
            }
            Py_DECREF(f);
        }
    }
    if (PyList_Sort(list) < 0) {
        Py_DECREF(list);
        return NULL;
    }
    uniq = PyList_New(0);
    for (k = 0; uniq && k < PyList_Size(list); k++) {
        PyObject *f = PyList_GetItem(list, k);
        if (k > 0 && PyFloat_AsDouble(f) == PyFloat_AsDouble(PyList_GetItem(list, k - 1)))
            continue;
        if (PyList_Append(uniq, f) < 0) Py_CLEAR(uniq);
    }
    Py_DECREF(list);
    return uniq;
}

static PyObject *plan_get_shaper(PlanObject *self, void *c)
{
    PyObject *A, *t;
    int32_t i;
    (void)c;
    A = PyTuple_New(self->shaper.n);
    t = PyTuple_New(self->shaper.n);
    if (!A || !t) {
        Py_XDECREF(A);
        Py_XDECREF(t);
        return NULL;
    }
    for (i = 0; i < self->shaper.n; i++) {
        if (PyTuple_SetItem(A, i, PyFloat_FromDouble(self->shaper.A[i])) < 0 ||
            PyTuple_SetItem(t, i, PyFloat_FromDouble(self->shaper.t[i])) < 0) {
            Py_DECREF(A);
            Py_DECREF(t);
            return NULL;
        }
    }
    return Py_BuildValue("(NN)", A, t);
}

static PyObject *plan_get_motion_time(PlanObject *self, void *c)
{
    (void)c;
    return PyFloat_FromDouble(djl_shaper_motion_time(&self->plan, &self->shaper));
}

static PyObject *plan_get_N_F(PlanObject *self, void *c)
{
    (void)c;
    return Py_BuildValue("(iiii)", self->plan.N[0], self->plan.N[1], self->plan.N[2],
                         self->plan.N[3]);
}

#define PLAN_DOUBLE_GETTER(name, expr)                                                       \
    static PyObject *plan_get_##name(PlanObject *self, void *c)                              \
    {                                                                                        \
        (void)c;                                                                             \
        return PyFloat_FromDouble(expr);                                                     \
    }
PLAN_DOUBLE_GETTER(v_reached, self->plan.v_reached)
PLAN_DOUBLE_GETTER(a_reached, self->plan.a_reached)
PLAN_DOUBLE_GETTER(d_reached, self->plan.d_reached)
PLAN_DOUBLE_GETTER(x_target, self->plan.x_target)
PLAN_DOUBLE_GETTER(offset, self->offset)
PLAN_DOUBLE_GETTER(Te, self->plan.p.Te)
PLAN_DOUBLE_GETTER(t_start, self->t_start)
PLAN_DOUBLE_GETTER(start_time, self->start_time)

static PyObject *plan_get_k_end(PlanObject *self, void *c)
{
    (void)c;
    return PyLong_FromLongLong((long long)self->plan.k_end);
}

static PyObject *plan_get_shifted(PlanObject *self, void *c)
{
    (void)c;
    return PyBool_FromLong(self->shifted);
}

/* Plan.residuals(m, k_end, h, f_mid, zeta, gain, f_end, factors, out):
 * the free-oscillation amplitude, summed over the modes, at communication point k_end of a
 * co-simulation with step h = m Te, for each frequency factor c (every mode frequency
 * scaled by c): the plant stepped from rest with the input a_k + j_k tau of this plan and
 * the frequencies f_mid[mode, k] c, as step_modes does; no array of samples is built. */
static PyObject *plan_residuals(PlanObject *self, PyObject *args)
{
    PyObject *of, *oz, *og, *ofe, *ofac, *oout;
    long long m;
    Py_ssize_t k_end, nm, nf, k, i, q;
    double h;
    Py_buffer bf, bz, bg, bfe, bfac, bout;
    double *st;
    const double two_pi = DJL_TWO_PI;
    int32_t cursor = 0, cursors[DJL_MAX_SHAPER_IMPULSES] = {0};
    int bad = 0;
    if (!PyArg_ParseTuple(args, "LndOOOOOO", &m, &k_end, &h, &of, &oz, &og, &ofe, &ofac, &oout))
        return NULL;
    if (m < 1 || k_end < 0 || !(h > 0.0)) {
        PyErr_SetString(PyExc_ValueError, "m must be >= 1, k_end >= 0 and h > 0");
        return NULL;
    }
    if (PyObject_GetBuffer(oz, &bz, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) return NULL;
    nm = bz.len / 8;
    PyBuffer_Release(&bz);
    if (PyObject_GetBuffer(ofac, &bfac, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) return NULL;
    nf = bfac.len / 8;
    PyBuffer_Release(&bfac);
    if (nm < 1 || nf < 1) {
        PyErr_SetString(PyExc_ValueError, "at least one mode and one factor are needed");
        return NULL;
    }
    if (get_in_buffer(of, &bf, nm * k_end, "f_mid") < 0) return NULL;
    if (get_in_buffer(oz, &bz, nm, "zeta") < 0) goto f1;
    if (get_in_buffer(og, &bg, nm, "gain") < 0) goto f2;
    if (get_in_buffer(ofe, &bfe, nm, "f_end") < 0) goto f3;
    if (get_in_buffer(ofac, &bfac, nf, "factors") < 0) goto f4;
    if (get_out_buffer(oout, &bout, nf, "out") < 0) goto f5;
    for (i = 0; i < nm && !bad; i++)
        bad = !(((const double *)bz.buf)[i] >= 0.0 && ((const double *)bz.buf)[i] < 1.0);
    for (k = 0; k < nm * k_end && !bad; k++)
        bad = !(((const double *)bf.buf)[k] > 0.0 && isfinite(((const double *)bf.buf)[k]));
    for (q = 0; q < nf && !bad; q++)
        bad = !(((const double *)bfac.buf)[q] > 0.0 && isfinite(((const double *)bfac.buf)[q]));
    if (bad) {
        PyErr_SetString(PyExc_ValueError, "damping ratios must be in [0, 1), frequencies and "
                        "factors finite and > 0");
        goto f6;
    }
    st = (double *)PyMem_Calloc((size_t)(2 * nm * nf), sizeof(double));
    if (!st) {
        PyErr_NoMemory();
        goto f6;
    }
    {
        const double *f = bf.buf, *zeta = bz.buf, *gain = bg.buf, *fe = bfe.buf;
        const double *fac = bfac.buf;
        double *out = bout.buf;
        Py_BEGIN_ALLOW_THREADS
        for (k = 0; k < k_end; k++) {
            djl_sample smp;
            djl_shaper_eval(&self->shaper, &self->plan, (double)(k * m) - self->offset,
                            self->offset, NULL, 0, &cursor, cursors, &smp);
            for (q = 0; q < nf; q++) {
                for (i = 0; i < nm; i++) {
                    double *e = &st[2 * (q * nm + i)];
                    double omega = two_pi * (f[i * k_end + k] * fac[q]);
                    double z = zeta[i], g = gain[i];
                    double sig = z * omega;
                    double w2 = omega * omega;
                    double wd = omega * sqrt(1.0 - z * z);
                    double ex = exp(-sig * h);
                    double c = cos(wd * h);
                    double s = sin(wd * h) / wd;
                    double beta = -g * smp.j / w2;
                    double alpha = (-g * smp.a - 2.0 * sig * beta) / w2;
                    double d1 = e[0] - alpha;
                    double d2 = e[1] - beta;
                    e[0] = alpha + beta * h + ex * ((c + sig * s) * d1 + s * d2);
                    e[1] = beta + ex * (-w2 * s * d1 + (c - sig * s) * d2);
                }
            }
        }
        for (q = 0; q < nf; q++) {
            double total = 0.0;
            for (i = 0; i < nm; i++) {
                const double *e = &st[2 * (q * nm + i)];
                double omega = two_pi * (fe[i] * fac[q]);
                double z = zeta[i];
                total += hypot(e[0], (e[1] + z * omega * e[0]) / (omega * sqrt(1.0 - z * z)));
            }
            out[q] = total;
        }
        Py_END_ALLOW_THREADS
    }
    PyMem_Free(st);
    PyBuffer_Release(&bout);
    PyBuffer_Release(&bfac);
    PyBuffer_Release(&bfe);
    PyBuffer_Release(&bg);
    PyBuffer_Release(&bz);
    PyBuffer_Release(&bf);
    Py_RETURN_NONE;
f6:
    PyBuffer_Release(&bout);
f5:
    PyBuffer_Release(&bfac);
f4:
    PyBuffer_Release(&bfe);
f3:
    PyBuffer_Release(&bg);
f2:
    PyBuffer_Release(&bz);
f1:
    PyBuffer_Release(&bf);
    return NULL;
}

#define ADJ_FRESH 32    /* steps between two evaluations of exp, cos, sin by libm */
#define ADJ_SMALL 1e-3  /* largest change of wd h or sig h carried by the series */

/* The adjoint suffix sums of one row (adjoint_sums) into S[6 (n + 1)]: the frequencies
 * f[k] * factor (Hz), the damping ratio z and gain g. */
static void adjoint_row(double h, const double *f, double factor, double z, double g,
                        Py_ssize_t n, double *S)
{
    const double two_pi = DJL_TWO_PI;
    const Py_ssize_t L = n + 1;
    double L11 = 1.0, L12 = 0.0, L21 = 0.0, L22 = 1.0, sq = sqrt(1.0 - z * z), isq = 1.0 / sq;
    double *ea0 = &S[0], *ea1 = &S[L], *ej = &S[2 * L];
    double *da0 = &S[3 * L], *da1 = &S[4 * L], *dj = &S[5 * L];
    double x_prev = 0.0, y_prev = 0.0, e = 1.0, c = 1.0, sn = 0.0;
    double sa0 = 0.0, sa1 = 0.0, sj = 0.0, sd0 = 0.0, sd1 = 0.0, sdj = 0.0;
    int fresh = 0;
    Py_ssize_t k;
    ea0[n] = ea1[n] = ej[n] = da0[n] = da1[n] = dj[n] = 0.0;
    for (k = n - 1; k >= 0; k--) {
        /* as adjoint_modes (on f factor); the step's exp(-sig h), cos and sin(wd h) carried
         * from the next step's by the small change of the frequency (angle addition, series
         * to within an ulp), taken from libm again every ADJ_FRESH steps and whenever the
         * change is not small: within ~1e-14 of adjoint_modes' (tested), half the cost */
        double omega = two_pi * (factor == 1.0 ? f[k] : f[k] * factor);
        double sig = z * omega, w2 = omega * omega, wd = omega * sq;
        double x = wd * h, y = sig * h, d = x - x_prev, dy = y_prev - y, s, iw, iw2;
        if (fresh > 0 && fabs(d) <= ADJ_SMALL && fabs(dy) <= ADJ_SMALL) {
            double d2 = d * d, cd, sd, nc;
            if (d != 0.0) {
                cd = 1.0 - d2 * (0.5 - d2 * (1.0 / 24.0 - d2 * (1.0 / 720.0)));
                sd = d * (1.0 - d2 * (1.0 / 6.0 - d2 * (1.0 / 120.0)));
                nc = c * cd - sn * sd;
                sn = sn * cd + c * sd;
                c = nc;
            }
            if (dy != 0.0)
                e *= 1.0 + dy * (1.0 + dy * (0.5 + dy * (1.0 / 6.0 + dy * (1.0 / 24.0))));
            fresh--;
        } else {
            e = exp(-y);
            c = cos(x);
            sn = sin(x);
            fresh = ADJ_FRESH;
        }
        x_prev = x;
        y_prev = y;
        iw = 1.0 / omega; /* the one division of the step */
        iw2 = iw * iw;
        s = sn * (iw * isq);
        double P11 = e * (c + sig * s), P12 = e * s, P21 = -e * w2 * s;
        double P22 = e * (c - sig * s);
        double ka = -g * iw2, kj = 2.0 * sig * g * (iw2 * iw2);
        double G1a = (1.0 - P11) * ka, G1j = (1.0 - P11) * kj + (h - P12) * ka;
        double G2a = -P21 * ka, G2j = -P21 * kj + (1.0 - P22) * ka;
        double o0 = L11 * G1a + L12 * G2a, o1 = L11 * G1j + L12 * G2j;
        double o2 = L21 * G1a + L22 * G2a, o3 = L21 * G1j + L22 * G2j;
        double N11, N12, N21, N22, kk = (double)k;
        ea0[k] = sa0 += o0;
        ea1[k] = sa1 += kk * o0;
        ej[k] = sj += o1;
        da0[k] = sd0 += o2;
        da1[k] = sd1 += kk * o2;
        dj[k] = sdj += o3;
        N11 = L11 * P11 + L12 * P21;
        N12 = L11 * P12 + L12 * P22;
        N21 = L21 * P11 + L22 * P21;
        N22 = L21 * P12 + L22 * P22;
        L11 = N11;
        L12 = N12;
        L21 = N21;
        L22 = N22;
    }
}

/* Plan.adjoint_residuals(m, k_end, S, sig, wd, n_modes, order, bound, out, ready, start,
 *                         fill=None) -> int
 *   The residual of this (unshaped) plan under each point of a perturbation set, from the
 *   suffix sums S of the plant's adjoint (adjoint_sums): the final state of row r is
 *   sum_k psi[r, k] (a_k, j_k) over the steps k < k_end (FMU sample k m), and over one
 *   constant-jerk piece a_k is linear in k, so each piece costs three differences of S per
 *   row instead of a sum over its samples.  Rows are point-major (row = point * n_modes +
 *   mode); sig = zeta omega and wd = omega sqrt(1 - zeta^2) of each row at the end.
 *   out[p] = the free-oscillation amplitude summed over the modes, for p = order[q],
 *   q = start, start + 1, ..., until one is >= bound: returns how many entries of order
 *   are then done (len(order) when none reached bound); or -(q + 1) when the rows of
 *   order[q] are not computed yet (ready[order[q]] == 0, uint8), the entries before it
 *   done.  With fill = (h, f_nom, zeta, gain, f_end, factors), a point of a map-scale set
 *   (its rows the nominal ones, every frequency times factors[point]) that is not ready is
 *   computed here (its rows of S, sig and wd, as adjoint_sums and the Python side do) and
 *   marked ready. */
static PyObject *plan_adjoint_residuals(PlanObject *self, PyObject *args)
{
    PyObject *oS, *osig, *owd, *oord, *oout, *ordy, *fill = Py_None;
    long long m;
    Py_ssize_t k_end, nm, R, n_pts, n_ord, q, start, done;
    double bound, fh = 0.0;
    Py_buffer bS, bsig, bwd, bord, bout, brdy, bfill[5];
    int filling = 0, nfill = 0, j;
    if (!PyArg_ParseTuple(args, "LnOOOnOdOOn|O", &m, &k_end, &oS, &osig, &owd, &nm, &oord,
                          &bound, &oout, &ordy, &start, &fill))
        return NULL;
    if (m < 1 || k_end < 0 || nm < 1 || start < 0) {
        PyErr_SetString(PyExc_ValueError, "m must be >= 1, k_end >= 0, n_modes >= 1 and "
                        "start >= 0");
        return NULL;
    }
    done = start;
    if (self->shaper.n > 0) {
        PyErr_SetString(PyExc_ValueError, "adjoint_residuals needs an unshaped plan");
        return NULL;
    }
    if (PyObject_GetBuffer(osig, &bsig, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) return NULL;
    R = bsig.len / 8;
    PyBuffer_Release(&bsig);
    if (R < nm || R % nm) {
        PyErr_SetString(PyExc_ValueError, "sig must hold n_points * n_modes values");
        return NULL;
    }
    n_pts = R / nm;
    if (PyObject_GetBuffer(oord, &bord, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) return NULL;
    if (bord.itemsize != 8 || !bord.format || (strcmp(bord.format, "q") != 0 &&
                                                strcmp(bord.format, "l") != 0)) {
        PyErr_SetString(PyExc_ValueError, "order must be a C-contiguous int64 array");
        PyBuffer_Release(&bord);
        return NULL;
    }
    n_ord = bord.len / 8;
    for (q = 0; q < n_ord; q++) {
        long long p = ((const long long *)bord.buf)[q];
        if (p < 0 || p >= n_pts) {
            PyErr_Format(PyExc_ValueError, "order[%zd] = %lld is not a point index", q, p);
            PyBuffer_Release(&bord);
            return NULL;
        }
    }
    if (get_out_buffer(oS, &bS, R * 6 * (k_end + 1), "S") < 0) goto f1;
    if (get_out_buffer(osig, &bsig, R, "sig") < 0) goto f2;
    if (get_out_buffer(owd, &bwd, R, "wd") < 0) goto f3;
    if (get_out_buffer(oout, &bout, n_pts, "out") < 0) goto f4;
    if (PyObject_GetBuffer(ordy, &brdy, PyBUF_C_CONTIGUOUS | PyBUF_WRITABLE) < 0) goto f5;
    if (brdy.len < n_pts) {
        PyErr_SetString(PyExc_ValueError, "ready must hold one byte per point");
        goto f6;
    }
    {
        unsigned char *ready = brdy.buf;
        const djl_plan *pl = &self->plan;
        double *S = bS.buf, *sig = bsig.buf, *wd = bwd.buf;
        const long long *ord = bord.buf;
        double *out = bout.buf;
        const double Te = pl->p.Te;
        const long long off = (long long)self->offset;
        const Py_ssize_t L = k_end + 1;
        /* each piece: the steps [k0, k1) it covers, and a_k = c0 + c1 k, j_k = j over them */
        Py_ssize_t np = 0, i;
        Py_ssize_t K0[DJL_MAX_PIECES], K1[DJL_MAX_PIECES];
        double C0[DJL_MAX_PIECES], C1[DJL_MAX_PIECES], J[DJL_MAX_PIECES];
        for (i = 0; i < pl->n_pieces; i++) {
            const djl_piece *pc = &pl->piece[i];
            long long lo = pc->k + off, hi;
            long long k0 = lo <= 0 ? 0 : (lo + m - 1) / m, k1;
            if (i + 1 < pl->n_pieces) {
                hi = pl->piece[i + 1].k + off;
                k1 = hi <= 0 ? 0 : (hi + m - 1) / m;
            } else {
                k1 = k_end;
            }
            if (k1 > k_end) k1 = k_end;
            if (k0 >= k1 || (pc->a == 0.0 && pc->j == 0.0)) continue;
            K0[np] = (Py_ssize_t)k0;
            K1[np] = (Py_ssize_t)k1;
            /* a_k = C0 + C1 (k - k0): C0 as djl_eval gives it at step k0 */
            C0[np] = pc->a + (double)(k0 * m - off - pc->k) * Te * pc->j;
            C1[np] = pc->j * Te * (double)m;
            J[np] = pc->j;
            np++;
        }
        for (q = start; q < n_ord; q++) {
            Py_ssize_t p = (Py_ssize_t)ord[q];
            double total = 0.0;
            if (!ready[p] && fill != Py_None && !filling) {
                /* fill = (h, f_nom (n_modes, k_end), zeta, gain, f_end (n_modes),
                 * factors (n_points)): a point is the nominal rows, every frequency times
                 * its factor; read once, when a point is first missing */
                static const char *what[5] = {"f_nom", "zeta", "gain", "f_end", "factors"};
                Py_ssize_t sizes[5];
                sizes[0] = nm * k_end;
                sizes[1] = sizes[2] = sizes[3] = nm;
                sizes[4] = n_pts;
                if (!PyTuple_Check(fill) || PyTuple_Size(fill) != 6) {
                    PyErr_SetString(PyExc_ValueError, "fill must be (h, f_nom, zeta, gain, "
                                    "f_end, factors)");
                    done = PY_SSIZE_T_MIN;
                    break;
                }
                fh = PyFloat_AsDouble(PyTuple_GetItem(fill, 0));
                if (fh == -1.0 && PyErr_Occurred()) {
                    done = PY_SSIZE_T_MIN;
                    break;
                }
                for (j = 0; j < 5; j++) {
                    if (get_in_buffer(PyTuple_GetItem(fill, j + 1), &bfill[j], sizes[j],
                                      what[j]) < 0)
                        break;
                    nfill++;
                }
                if (nfill < 5) {
                    done = PY_SSIZE_T_MIN;
                    break;
                }
                filling = 1;
            }
            if (!ready[p] && filling) {
                const double *fn = bfill[0].buf, *zt = bfill[1].buf, *gn = bfill[2].buf;
                const double *fe = bfill[3].buf, *fac = bfill[4].buf;
                for (i = 0; i < nm; i++) {
                    Py_ssize_t r = p * nm + i;
                    /* as the Python side: w = 2 pi (f_end c) */
                    double w = DJL_TWO_PI * (fe[i] * fac[p]);
                    adjoint_row(fh, &fn[i * k_end], fac[p], zt[i], gn[i], k_end,
                                &S[r * 6 * L]);
                    sig[r] = zt[i] * w;
                    wd[r] = w * sqrt(1.0 - zt[i] * zt[i]);
                }
                ready[p] = 1;
            }
            if (!ready[p]) {
                done = -(q + 1);
                break;
            }
            for (i = 0; i < nm; i++) {
                Py_ssize_t r = p * nm + i;
                double st[2];
                int c;
                for (c = 0; c < 2; c++) {
                    const double *A0 = &S[((r * 2 + c) * 3 + 0) * L];
                    const double *A1 = &S[((r * 2 + c) * 3 + 1) * L];
                    const double *J0 = &S[((r * 2 + c) * 3 + 2) * L];
                    double acc = 0.0;
                    Py_ssize_t e;
                    for (e = 0; e < np; e++) {
                        Py_ssize_t a = K0[e], b = K1[e];
                        double s0 = A0[a] - A0[b], sj = J0[a] - J0[b];
                        /* sum over the piece of (k - k0) psi_a */
                        double s1 = (A1[a] - A1[b]) - (double)a * s0;
                        acc += C0[e] * s0 + C1[e] * s1 + J[e] * sj;
                    }
                    st[c] = acc;
                }
                total += hypot(st[0], (st[1] + sig[r] * st[0]) / wd[r]);
            }
            out[p] = total;
            done = q + 1;
            if (total >= bound) break;
        }
    }
    for (j = 0; j < nfill; j++) PyBuffer_Release(&bfill[j]);
    PyBuffer_Release(&brdy);
    PyBuffer_Release(&bout);
    PyBuffer_Release(&bwd);
    PyBuffer_Release(&bsig);
    PyBuffer_Release(&bS);
    PyBuffer_Release(&bord);
    if (done == PY_SSIZE_T_MIN) return NULL;
    return PyLong_FromSsize_t(done);
f6:
    PyBuffer_Release(&brdy);
f5:
    PyBuffer_Release(&bout);
f4:
    PyBuffer_Release(&bwd);
f3:
    PyBuffer_Release(&bsig);
f2:
    PyBuffer_Release(&bS);
f1:
    PyBuffer_Release(&bord);
    return NULL;
}

/* Plan.replan(T_F1, T_F2, T_F3, T_F4) -> Plan: the same (unshaped) move planned again with
 * other jerk times (s), its other parameters and start as this plan's: what plan() gives for
 * the same parameters, without reading them from a dict (the tuning searches plan
 * thousands of moves that differ in their jerk times only). */
static PyObject *plan_replan(PlanObject *self, PyObject *args)
{
    double T[4];
    djl_params p;
    djl_error err;
    djl_status st;
    PlanObject *obj;
    int i;
    if (!PyArg_ParseTuple(args, "dddd", &T[0], &T[1], &T[2], &T[3])) return NULL;
    if (self->shaper.n > 0) {
        PyErr_SetString(PyExc_ValueError, "replan needs an unshaped plan");
        return NULL;
    }
    if (self->plan.p.profile == DJL_PROFILE_TABLE) {
        PyErr_SetString(PyExc_ValueError, "replan re-times the stages of an AL, JL or DJL "
                        "plan: a table (profile 4) has its own jerk");
        return NULL;
    }
    obj = PyObject_New(PlanObject, PlanType);
    if (!obj) return NULL;
    p = self->plan.p;
    for (i = 0; i < 4; i++) p.T_F[i] = T[i];
    obj->t_start = self->t_start;
    obj->start_time = self->start_time;
    obj->shaper = self->shaper;
    memset(&err, 0, sizeof err);
    st = plan_into(&p, NULL, obj->t_start, obj->start_time, &obj->plan, &err, &obj->offset,
                   &obj->shifted);
    if (st != DJL_OK) {
        Py_DECREF(obj);
        return raise_plan_error(&err, st);
    }
    return (PyObject *)obj;
}

static PyGetSetDef plan_getset[] = {
    {"motion_time", (getter)plan_get_motion_time, NULL,
     "Duration of the motion, filters included (s); with a shaper, until its last delayed "
     "copy ends (the FMU's motion_time).", NULL},
    {"shaper", (getter)plan_get_shaper, NULL,
     "The input shaper applied: (amplitudes, delays in s), both empty without one.", NULL},
    {"N_F", (getter)plan_get_N_F, NULL, "Jerk times applied, in samples (N_F1..N_F4).", NULL},
    {"v_reached", (getter)plan_get_v_reached, NULL, "Largest peak velocity (m/s).", NULL},
    {"a_reached", (getter)plan_get_a_reached, NULL, "Largest acceleration level (m/s2).", NULL},
    {"d_reached", (getter)plan_get_d_reached, NULL, "Largest deceleration level (m/s2).", NULL},
    {"x_target", (getter)plan_get_x_target, NULL, "Final position (m).", NULL},
    {"offset", (getter)plan_get_offset, NULL,
     "FMU sample (counted from start_time) at which the motion starts.", NULL},
    {"Te", (getter)plan_get_Te, NULL, "Sampling period (s).", NULL},
    {"t_start", (getter)plan_get_t_start, NULL, "Requested start of the motion (s).", NULL},
    {"start_time", (getter)plan_get_start_time, NULL, "Start of the sample grid (s).", NULL},
    {"k_end", (getter)plan_get_k_end, NULL, "Samples from the motion start to its end.", NULL},
    {"shifted", (getter)plan_get_shifted, NULL,
     "t_start was not on the sample grid: the motion starts at the next sample.", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyMethodDef plan_methods[] = {
    {"sample_into", (PyCFunction)plan_sample_into, METH_VARARGS,
     "sample_into(out, n0, step, count): out[i, k] = variable i (x, v, a, j, x_AL, v_AL, a_AL) "
     "at FMU sample n0 + k*step (out: float64 array of shape (7, count))."},
    {"residuals", (PyCFunction)plan_residuals, METH_VARARGS,
     "residuals(m, k_end, h, f_mid, zeta, gain, f_end, factors, out): free-oscillation "
     "amplitude (sum over the modes) at communication point k_end, for each frequency factor."},
    {"replan", (PyCFunction)plan_replan, METH_VARARGS,
     "replan(T_F1, T_F2, T_F3, T_F4) -> Plan: this (unshaped) move planned again with other "
     "jerk times (s), as plan() would for the same parameters."},
    {"adjoint_residuals", (PyCFunction)plan_adjoint_residuals, METH_VARARGS,
     "adjoint_residuals(m, k_end, S, sig, wd, n_modes, order, bound, out, ready, start, "
     "fill=None) -> int: the residual (sum over the modes) under each point in order from start, from the "
     "suffix sums S of adjoint_sums, until one is >= bound; returns how many entries are "
     "done, or -(q + 1) when the point order[q] is not ready (fill: computed here)."},
    {"eval", (PyCFunction)(void (*)(void))plan_eval, METH_VARARGS | METH_KEYWORDS,
     "eval(times, side=\"right\") -> (x, v, a, j): the (shaped) profile at times (s, FMU time; "
     "a time within 1e-9 of a sample is that sample), limits from the right (jerk over the "
     "interval starting there) or the left; numpy arrays."},
    {"breakpoints", (PyCFunction)plan_breakpoints, METH_NOARGS,
     "breakpoints() -> list: times (s) at which the shaped jerk may change (each piece start "
     "of the plan delayed by each impulse), sorted, each once."},
    {"at", (PyCFunction)plan_at, METH_VARARGS,
     "at(n): (x, v, a, j, x_AL, v_AL, a_AL, done, segment) at FMU sample n (fractional allowed)."},
    {NULL, NULL, 0, NULL},
};

/* A heap type from a spec (the limited API: the wheel is abi3 where the Python allows it). */
static PyType_Slot plan_slots[] = {
    {Py_tp_doc, (void *)"A move planned by the generator core (create it with plan())."},
    {Py_tp_methods, plan_methods},
    {Py_tp_getset, plan_getset},
    {0, NULL},
};

static PyType_Spec plan_spec = {
    "harness._engine.Plan", sizeof(PlanObject), 0, Py_TPFLAGS_DEFAULT, plan_slots,
};

/* motion_start(t_start, start_time, Te) -> float: the time of the generator sample at which
 * the motion starts (djl_start_offset), start_time + k Te. */
static PyObject *engine_motion_start(PyObject *self, PyObject *args)
{
    double t_start, start_time, Te, off = 0.0;
    int shifted = 0;
    djl_error err;
    djl_status st;
    (void)self;
    if (!PyArg_ParseTuple(args, "ddd", &t_start, &start_time, &Te)) return NULL;
    memset(&err, 0, sizeof err);
    st = djl_start_offset(t_start, start_time, Te, &off, &shifted, &err);
    if (st != DJL_OK) return raise_plan_error(&err, st);
    return PyFloat_FromDouble(start_time + off * Te);
}

/* ------------------------------------------------------- Z synchronisation */

typedef struct {
    engine_params e;
    djl_shaper shaper;
    double start_time;
    djl_plan plan; /* scratch: large, kept off the stack */
} sync_ctx;

static djl_status time_at(sync_ctx *c, double v, double *T, djl_error *err)
{
    double off;
    int shifted;
    djl_status st;
    c->e.p.v_max = v;
    st = plan_into(&c->e.p, &c->e.table, c->e.t_start, c->start_time, &c->plan, err, &off,
                   &shifted);
    if (st == DJL_OK) st = shaper_into(&c->e.sp, &c->plan, &c->shaper, err);
    if (st == DJL_OK) *T = djl_shaper_motion_time(&c->plan, &c->shaper);
    return st;
}

/* sync_velocity(params, target_time, v_cap, start_time=0) -> (v_max, motion_time, synced)
 * The same bisection as harness.simulation.fmu_axis.FMUAxis.sync_velocity. */
static PyObject *engine_sync_velocity(PyObject *self, PyObject *args, PyObject *kwds)
{
    static char *kwlist[] = {"params", "target_time", "v_cap", "start_time", NULL};
    PyObject *dict;
    double target, v_cap, start_time = 0.0, d, lo, hi, mid, T = 0.0, t_cap = 0.0;
    djl_error err;
    djl_status st = DJL_OK;
    sync_ctx *c;
    int i, synced = 1;
    double v_out = 0.0, t_out = 0.0;
    (void)self;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "Odd|d", kwlist, &dict, &target, &v_cap,
                                     &start_time))
        return NULL;
    c = (sync_ctx *)PyMem_Malloc(sizeof *c);
    if (!c) return PyErr_NoMemory();
    if (parse_params(dict, &c->e) < 0) {
        PyMem_Free(c);
        return NULL;
    }
    c->start_time = start_time;
    memset(&err, 0, sizeof err);
    d = fabs(c->e.p.distance);
    Py_BEGIN_ALLOW_THREADS
    st = time_at(c, v_cap, &t_cap, &err);
    if (st == DJL_OK) {
        if (t_cap > target) {
            v_out = v_cap;
            t_out = t_cap;
            synced = 0;
        } else {
            lo = d / target < v_cap ? d / target : v_cap;
            st = time_at(c, lo, &T, &err);
            if (st == DJL_OK && T <= target) {
                v_out = lo;
                t_out = T;
            } else if (st == DJL_OK) {
                hi = v_cap;
                for (i = 0; i < 60; i++) {
                    mid = 0.5 * (lo + hi);
                    st = time_at(c, mid, &T, &err);
                    if (st != DJL_OK) break;
                    if (T <= target)
                        hi = mid;
                    else
                        lo = mid;
                    if (hi - lo <= 1e-9 * hi) break;
                }
                if (st == DJL_OK) st = time_at(c, hi, &T, &err);
                v_out = hi;
                t_out = T;
            }
        }
    }
    Py_END_ALLOW_THREADS
    PyMem_Free(c);
    if (st != DJL_OK) return raise_plan_error(&err, st);
    return Py_BuildValue("(ddO)", v_out, t_out, synced ? Py_True : Py_False);
}

/* ------------------------------------------------------------ the plant */

/* step_modes(a, j, h, f, zeta, gain, n, state, eps, states)
 *   a, j: n values (acceleration at the start of each step, jerk over it);
 *   f: (n_modes, n) frequencies (Hz) per step; zeta, gain: n_modes values;
 *   state: 2 n_modes values (eps_i, deps_i), initial state, updated in place;
 *   eps: n + 1 outputs (total deflection at each point, eps[0] from state);
 *   states: (n + 1, 2 n_modes) outputs. */
/* The modes of step_modes, the rows of adjoint_modes / adjoint_sums (``what``): damping
 * ratios in [0, 1), frequencies finite and > 0 (n steps each).  Returns -1 with a
 * ValueError naming the mode or row (and step).  (PyErr_Format knows no %g: the message
 * is formatted by snprintf.) */
static int check_rows(const double *zeta, const double *f, Py_ssize_t R, Py_ssize_t n,
                      const char *what)
{
    char msg[160];
    Py_ssize_t r, k;
    for (r = 0; r < R; r++)
        if (!(zeta[r] >= 0.0 && zeta[r] < 1.0)) {
            snprintf(msg, sizeof msg, "%s %ld: damping ratio %g not in [0, 1)", what, (long)r,
                     zeta[r]);
            PyErr_SetString(PyExc_ValueError, msg);
            return -1;
        }
    for (k = 0; k < R * n; k++)
        if (!(f[k] > 0.0) || !isfinite(f[k])) {
            snprintf(msg, sizeof msg, "%s %ld: frequency %g Hz at step %ld is not a finite "
                     "number > 0", what, (long)(k / (n ? n : 1)), f[k], (long)(k % (n ? n : 1)));
            PyErr_SetString(PyExc_ValueError, msg);
            return -1;
        }
    return 0;
}

static PyObject *engine_step_modes(PyObject *self, PyObject *args)
{
    PyObject *oa, *oj, *of, *oz, *og, *ost, *oe, *oss;
    double h;
    Py_ssize_t n, nm, k, i;
    Py_buffer ba, bj, bf, bz, bg, bst, be, bss;
    const double *a, *j, *f, *zeta, *gain;
    double *st, *eps, *states, *cache = NULL;
    const double two_pi = DJL_TWO_PI;
    (void)self;
    if (!PyArg_ParseTuple(args, "OOdOOOnOOO", &oa, &oj, &h, &of, &oz, &og, &n, &ost, &oe, &oss))
        return NULL;
    if (n < 0 || !(h > 0.0)) {
        PyErr_SetString(PyExc_ValueError, "n must be >= 0 and h > 0");
        return NULL;
    }
    if (PyObject_GetBuffer(oz, &bz, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) return NULL;
    nm = bz.len / 8;
    PyBuffer_Release(&bz);
    if (nm < 1) {
        PyErr_SetString(PyExc_ValueError, "at least one mode is needed");
        return NULL;
    }
    if (get_in_buffer(oa, &ba, n, "a") < 0) return NULL;
    if (get_in_buffer(oj, &bj, n, "j") < 0) goto fail_a;
    if (get_in_buffer(of, &bf, nm * n, "f") < 0) goto fail_j;
    if (get_in_buffer(oz, &bz, nm, "zeta") < 0) goto fail_f;
    if (get_in_buffer(og, &bg, nm, "gain") < 0) goto fail_z;
    if (get_out_buffer(ost, &bst, 2 * nm, "state") < 0) goto fail_g;
    if (get_out_buffer(oe, &be, n + 1, "eps") < 0) goto fail_st;
    if (get_out_buffer(oss, &bss, (n + 1) * 2 * nm, "states") < 0) goto fail_e;
    a = ba.buf;
    j = bj.buf;
    f = bf.buf;
    zeta = bz.buf;
    gain = bg.buf;
    st = bst.buf;
    eps = be.buf;
    states = bss.buf;
    if (check_rows(zeta, f, nm, n, "mode") < 0) goto fail_all;
    cache = (double *)PyMem_Calloc((size_t)(6 * nm), sizeof(double));
    if (!cache) {
        PyErr_NoMemory();
        goto fail_all;
    }
    Py_BEGIN_ALLOW_THREADS
    {
        double total = 0.0;
        for (i = 0; i < nm; i++) {
            states[2 * i] = st[2 * i];
            states[2 * i + 1] = st[2 * i + 1];
            total += st[2 * i];
        }
        eps[0] = total;
    }
    for (k = 0; k < n; k++) {
        double total = 0.0;
        for (i = 0; i < nm; i++) {
            /* harness.plant.step_mode_jerk, operation for operation; the transition terms
             * depend on the frequency only: reused while it does not change (after the
             * motions, most of a record), the same values, not recomputed */
            double *cc = &cache[6 * i];
            double f_ik = f[i * n + k];
            double z = zeta[i], g = gain[i];
            double sig, w2, e, c, s;
            if (f_ik != cc[0] || k == 0) {
                double omega = two_pi * f_ik;
                double wd = omega * sqrt(1.0 - z * z);
                cc[0] = f_ik;
                cc[1] = sig = z * omega;
                cc[2] = w2 = omega * omega;
                cc[3] = e = exp(-sig * h);
                cc[4] = c = cos(wd * h);
                cc[5] = s = sin(wd * h) / wd;
            } else {
                sig = cc[1];
                w2 = cc[2];
                e = cc[3];
                c = cc[4];
                s = cc[5];
            }
            {
                double beta = -g * j[k] / w2;
                double alpha = (-g * a[k] - 2.0 * sig * beta) / w2;
                double d1 = st[2 * i] - alpha;
                double d2 = st[2 * i + 1] - beta;
                double e1 = alpha + beta * h + e * ((c + sig * s) * d1 + s * d2);
                double e2 = beta + e * (-w2 * s * d1 + (c - sig * s) * d2);
                st[2 * i] = e1;
                st[2 * i + 1] = e2;
                states[(k + 1) * 2 * nm + 2 * i] = e1;
                states[(k + 1) * 2 * nm + 2 * i + 1] = e2;
                total += e1;
            }
        }
        eps[k + 1] = total;
    }
    Py_END_ALLOW_THREADS
    PyMem_Free(cache);
    PyBuffer_Release(&bss);
    PyBuffer_Release(&be);
    PyBuffer_Release(&bst);
    PyBuffer_Release(&bg);
    PyBuffer_Release(&bz);
    PyBuffer_Release(&bf);
    PyBuffer_Release(&bj);
    PyBuffer_Release(&ba);
    Py_RETURN_NONE;
fail_all:
    PyBuffer_Release(&bss);
fail_e:
    PyBuffer_Release(&be);
fail_st:
    PyBuffer_Release(&bst);
fail_g:
    PyBuffer_Release(&bg);
fail_z:
    PyBuffer_Release(&bz);
fail_f:
    PyBuffer_Release(&bf);
fail_j:
    PyBuffer_Release(&bj);
fail_a:
    PyBuffer_Release(&ba);
    return NULL;
}

/* adjoint_modes(h, f, zeta, gain, n, psi)
 *   For R independent modes (rows: a mode under one perturbation), each stepped over n steps
 *   of h with the frequency f[r, k] (Hz) as step_modes does, the sensitivity of the final
 *   state (eps, deps) to the input of every step: psi[r, k, i, c] = d state_i(n) / d u_c(k),
 *   u = (a_k, j_k).  The final state of any input from rest is sum_k psi[r, k] u_k: the
 *   robust tuning evaluates a move under every perturbation with one dot product each.
 *   f: (R, n); zeta, gain: R values; psi: (R, n, 2, 2) output. */
static PyObject *engine_adjoint_modes(PyObject *self, PyObject *args)
{
    PyObject *of, *oz, *og, *op;
    double h;
    Py_ssize_t n, R, r, k;
    Py_buffer bf, bz, bg, bp;
    const double *f, *zeta, *gain;
    double *psi;
    const double two_pi = DJL_TWO_PI;
    (void)self;
    if (!PyArg_ParseTuple(args, "dOOOnO", &h, &of, &oz, &og, &n, &op)) return NULL;
    if (n < 0 || !(h > 0.0) || !isfinite(h)) {
        PyErr_SetString(PyExc_ValueError, "n must be >= 0 and h a finite number > 0");
        return NULL;
    }
    if (PyObject_GetBuffer(oz, &bz, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) return NULL;
    R = bz.len / 8;
    PyBuffer_Release(&bz);
    if (get_in_buffer(of, &bf, R * n, "f") < 0) return NULL;
    if (get_in_buffer(oz, &bz, R, "zeta") < 0) goto fail_f;
    if (get_in_buffer(og, &bg, R, "gain") < 0) goto fail_z;
    if (get_out_buffer(op, &bp, R * n * 4, "psi") < 0) goto fail_g;
    f = bf.buf;
    zeta = bz.buf;
    gain = bg.buf;
    psi = bp.buf;
    if (check_rows(zeta, f, R, n, "row") < 0) goto fail_all;
    Py_BEGIN_ALLOW_THREADS
    for (r = 0; r < R; r++) {
        /* L = d state(n) / d state(k+1), from the last step back */
        double L11 = 1.0, L12 = 0.0, L21 = 0.0, L22 = 1.0;
        double z = zeta[r], g = gain[r];
        for (k = n - 1; k >= 0; k--) {
            double omega = two_pi * f[r * n + k];
            double sig = z * omega, w2 = omega * omega, wd = omega * sqrt(1.0 - z * z);
            double e = exp(-sig * h), c = cos(wd * h), s = sin(wd * h) / wd;
            double P11 = e * (c + sig * s), P12 = e * s, P21 = -e * w2 * s;
            double P22 = e * (c - sig * s);
            double ka = -g / w2, kj = 2.0 * sig * g / (w2 * w2); /* alpha = ka a + kj j */
            double G1a = (1.0 - P11) * ka, G1j = (1.0 - P11) * kj + (h - P12) * ka;
            double G2a = -P21 * ka, G2j = -P21 * kj + (1.0 - P22) * ka;
            double *out = &psi[(r * n + k) * 4];
            double N11, N12, N21, N22;
            out[0] = L11 * G1a + L12 * G2a; /* d eps(n)  / d a_k */
            out[1] = L11 * G1j + L12 * G2j; /* d eps(n)  / d j_k */
            out[2] = L21 * G1a + L22 * G2a; /* d deps(n) / d a_k */
            out[3] = L21 * G1j + L22 * G2j; /* d deps(n) / d j_k */
            N11 = L11 * P11 + L12 * P21;
            N12 = L11 * P12 + L12 * P22;
            N21 = L21 * P11 + L22 * P21;
            N22 = L21 * P12 + L22 * P22;
            L11 = N11;
            L12 = N12;
            L21 = N21;
            L22 = N22;
        }
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&bp);
    PyBuffer_Release(&bg);
    PyBuffer_Release(&bz);
    PyBuffer_Release(&bf);
    Py_RETURN_NONE;
fail_all:
    PyBuffer_Release(&bp);
fail_g:
    PyBuffer_Release(&bg);
fail_z:
    PyBuffer_Release(&bz);
fail_f:
    PyBuffer_Release(&bf);
    return NULL;
}

/* adjoint_sums(h, f, zeta, gain, n, S, factor=1.0)
 *   The adjoint of adjoint_modes (the same psi, computed the same way), kept as suffix sums:
 *   S[r, i, 0, k] = sum_{k' >= k} psi[r, k', i, a], S[r, i, 1, k] = sum_{k' >= k} k' psi[r, k',
 *   i, a], S[r, i, 2, k] = sum_{k' >= k} psi[r, k', i, j], for k = 0..n (S[.., n] = 0).  The
 *   final state of an input whose a_k is linear and j_k constant over steps [k0, k1) is then a
 *   few differences of S (Plan.adjoint_residuals).  S: (R, 2, 3, n + 1) output.  With
 *   factor, every frequency is f[r, k] * factor (a map scaled by it). */
static PyObject *engine_adjoint_sums(PyObject *self, PyObject *args)
{
    PyObject *of, *oz, *og, *op;
    double h, factor = 1.0;
    Py_ssize_t n, R, r, L;
    Py_buffer bf, bz, bg, bp;
    const double *f, *zeta, *gain;
    double *S;
    (void)self;
    if (!PyArg_ParseTuple(args, "dOOOnO|d", &h, &of, &oz, &og, &n, &op, &factor)) return NULL;
    if (n < 0 || !(h > 0.0) || !isfinite(h) || !(factor > 0.0) || !isfinite(factor)) {
        PyErr_SetString(PyExc_ValueError, "n must be >= 0, h and factor finite numbers > 0");
        return NULL;
    }
    if (PyObject_GetBuffer(oz, &bz, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) return NULL;
    R = bz.len / 8;
    PyBuffer_Release(&bz);
    L = n + 1;
    if (get_in_buffer(of, &bf, R * n, "f") < 0) return NULL;
    if (get_in_buffer(oz, &bz, R, "zeta") < 0) goto fail_f;
    if (get_in_buffer(og, &bg, R, "gain") < 0) goto fail_z;
    if (get_out_buffer(op, &bp, R * 6 * L, "S") < 0) goto fail_g;
    f = bf.buf;
    zeta = bz.buf;
    gain = bg.buf;
    S = bp.buf;
    if (check_rows(zeta, f, R, n, "row") < 0) goto fail_all;
    Py_BEGIN_ALLOW_THREADS
    for (r = 0; r < R; r++)
        adjoint_row(h, &f[r * n], factor, zeta[r], gain[r], n, &S[r * 6 * L]);
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&bp);
    PyBuffer_Release(&bg);
    PyBuffer_Release(&bz);
    PyBuffer_Release(&bf);
    Py_RETURN_NONE;
fail_all:
    PyBuffer_Release(&bp);
fail_g:
    PyBuffer_Release(&bg);
fail_z:
    PyBuffer_Release(&bz);
fail_f:
    PyBuffer_Release(&bf);
    return NULL;
}

/* ---------------------------------------------------------------- module */

/* ------------------------------------------------- programs of commands (issue 34) */

/* The FMU's own model (fmu_model.c under fmu_instance.c, no FMI layer): a whole program of
 * commands stepped in C, the same code and arithmetic as the FMU's DoStep. */

typedef struct {
    char message[1100]; /* the last error the model logged */
} program_log;

static void program_logger(void *env, model_status status, const char *category,
                           const char *message)
{
    program_log *lg = (program_log *)env;
    (void)category;
    if (status >= ST_ERROR && lg && message) {
        strncpy(lg->message, message, sizeof lg->message - 1);
        lg->message[sizeof lg->message - 1] = '\0';
    }
}

static const djl_var_info *program_var(const char *name, char causality)
{
    size_t i;
    for (i = 0; i < sizeof djl_var_table / sizeof djl_var_table[0]; i++)
        if (djl_var_table[i].causality == causality && !strcmp(djl_var_table[i].name, name))
            return &djl_var_table[i];
    return NULL;
}

/* Set every entry of a dict of variables of the given causality ('p' parameters, 'i'
 * inputs): a number, or a sequence for an array.  -1 with a Python error. */
static int program_set(model_instance *m, PyObject *dict, char causality, const char *what,
                       program_log *lg)
{
    PyObject *key, *value;
    Py_ssize_t pos = 0;
    if (!PyDict_Check(dict)) {
        PyErr_Format(PyExc_TypeError, "%s must be a dict of FMU variable names", what);
        return -1;
    }
    while (PyDict_Next(dict, &pos, &key, &value)) {
        const djl_var_info *v;
        const char *k;
        char type;
        double x[DJL_MAX_TABLE];
        unsigned int i, n = 1;
        if (!PyUnicode_Check(key)) {
            PyErr_Format(PyExc_TypeError, "%s: names must be strings, got %R", what, key);
            return -1;
        }
        k = PyUnicode_AsUTF8AndSize(key, NULL);
        if (!k) return -1;
        v = program_var(k, causality);
        if (!v) {
            PyErr_Format(PyExc_KeyError, "%s: %R is not an FMU %s", what, key,
                         causality == 'p' ? "parameter" : "input");
            return -1;
        }
        type = v->type == 'E' ? 'I' : v->type;
        if (v->size > 1) {
            if (get_array(value, k, 'R', x, v->size) < 0) return -1;
            n = v->size;
        } else if (get_double(value, k, &x[0]) < 0) {
            return -1;
        }
        for (i = 0; i < n; i++) {
            double xi = x[i];
            if (type == 'B') xi = xi != 0.0;
            if (model_set(m, v->vr + i, type, xi) != ST_OK) {
                PyErr_Format(PlanError, "%s: %s refused: %s", what, k, lg->message);
                return -1;
            }
        }
    }
    return 0;
}

/* run_program(params, program, count, h, out, start_time=0.0): see engine_methods. */
static PyObject *engine_run_program(PyObject *self, PyObject *args, PyObject *kwds)
{
    static char *kwlist[] = {"params", "program", "count", "h", "out", "start_time", NULL};
    PyObject *params, *program, *out_obj, *seq = NULL;
    Py_ssize_t count, n_cmd, c = 0, k;
    double h, start_time = 0.0, t;
    Py_buffer view;
    model_instance *m;
    program_log lg;
    unsigned int outs[64];
    char otype[64];
    int n_out = 0;
    size_t i;
    (void)self;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "OOndO|d", kwlist, &params, &program, &count,
                                     &h, &out_obj, &start_time))
        return NULL;
    for (i = 0; i < sizeof djl_var_table / sizeof djl_var_table[0] && n_out < 64; i++)
        if (djl_var_table[i].causality == 'o') {
            outs[n_out] = djl_var_table[i].vr;
            otype[n_out++] = djl_var_table[i].type == 'E' ? 'I' : djl_var_table[i].type;
        }
    if (count < 0) {
        PyErr_SetString(PyExc_ValueError, "count must be >= 0");
        return NULL;
    }
    seq = PySequence_List(program); /* (a sequence of (step, inputs) pairs) */
    if (!seq) return NULL;
    n_cmd = PyList_Size(seq);
    if (get_out_buffer(out_obj, &view, (Py_ssize_t)n_out * count, "out") < 0) {
        Py_DECREF(seq);
        return NULL;
    }
    m = (model_instance *)calloc(1, sizeof *m);
    if (!m) {
        PyBuffer_Release(&view);
        Py_DECREF(seq);
        return PyErr_NoMemory();
    }
    lg.message[0] = '\0';
    model_init(m, 3, "engine", program_logger, &lg, 0, calloc, free);
    if (program_set(m, params, 'p', "params", &lg) < 0) goto fail;
    if (model_setup(m, start_time) != ST_OK || model_enter_init(m) != ST_OK ||
        model_exit_init(m) != ST_OK) {
        PyErr_Format(PlanError, "initialisation refused: %s", lg.message);
        goto fail;
    }
    t = start_time;
    for (k = 0; k < count; k++) {
        double *row = (double *)view.buf;
        /* the inputs of the commands at this step, in order */
        while (c < n_cmd) {
            PyObject *item = PyList_GetItem(seq, c), *inputs;
            Py_ssize_t at;
            if (!PyTuple_Check(item) || PyTuple_Size(item) != 2) {
                PyErr_Format(PyExc_TypeError, "program[%zd] must be a (step, inputs) tuple", c);
                goto fail;
            }
            at = PyLong_AsSsize_t(PyTuple_GetItem(item, 0));
            if (at == -1 && PyErr_Occurred()) goto fail;
            if (at < k) {
                PyErr_Format(PyExc_ValueError, "program[%zd]: step %zd is out of order", c, at);
                goto fail;
            }
            if (at > k) break;
            inputs = PyTuple_GetItem(item, 1);
            if (program_set(m, inputs, 'i', "inputs", &lg) < 0) goto fail;
            c++;
        }
        if (model_do_step(m, t, h) != ST_OK) {
            PyErr_Format(PlanError, "DoStep at t = %.17g s refused: %s", t, lg.message);
            goto fail;
        }
        t = m->d.t_now;
        for (i = 0; i < (size_t)n_out; i++) {
            double x = 0.0;
            (void)model_get(m, outs[i], otype[i], &x);
            row[(Py_ssize_t)i * count + k] = x;
        }
    }
    model_free(m);
    free(m);
    PyBuffer_Release(&view);
    Py_DECREF(seq);
    Py_RETURN_NONE;
fail:
    model_free(m);
    free(m);
    PyBuffer_Release(&view);
    Py_DECREF(seq);
    return NULL;
}

/* output_names() -> tuple: the FMU's outputs, in the rows run_program writes. */
static PyObject *engine_output_names(PyObject *self, PyObject *noargs)
{
    PyObject *names = PyList_New(0), *tup;
    size_t i;
    (void)self;
    (void)noargs;
    if (!names) return NULL;
    for (i = 0; i < sizeof djl_var_table / sizeof djl_var_table[0]; i++) {
        if (djl_var_table[i].causality != 'o') continue;
        PyObject *s = PyUnicode_FromString(djl_var_table[i].name);
        if (!s || PyList_Append(names, s) < 0) {
            Py_XDECREF(s);
            Py_DECREF(names);
            return NULL;
        }
        Py_DECREF(s);
    }
    tup = PyList_AsTuple(names);
    Py_DECREF(names);
    return tup;
}

static PyMethodDef engine_methods[] = {
    {"plan", (PyCFunction)(void (*)(void))engine_plan, METH_VARARGS | METH_KEYWORDS,
     "plan(params, start_time=0.0) -> Plan: plan a move with the generator core; params are FMU "
     "parameter names (the rest at the FMU's start values). Raises PlanError as the FMU refuses."},
    {"motion_start", engine_motion_start, METH_VARARGS,
     "motion_start(t_start, start_time, Te) -> float: the first generator sample "
     "(start_time + k Te) at or after t_start, a t_start within rounding of a sample counting "
     "as on it: where the FMU starts the motion. Raises PlanError as the FMU refuses t_start."},
    {"sync_velocity", (PyCFunction)(void (*)(void))engine_sync_velocity,
     METH_VARARGS | METH_KEYWORDS,
     "sync_velocity(params, target_time, v_cap, start_time=0.0) -> (v_max, motion_time, synced):"
     " the smallest v_max whose motion lasts at most target_time (bisection)."},
    {"step_modes", engine_step_modes, METH_VARARGS,
     "step_modes(a, j, h, f, zeta, gain, n, state, eps, states): advance the modes exactly over "
     "n steps of h with the input a[k] + j[k] tau and the frequencies f[mode, k] (Hz)."},
    {"adjoint_modes", engine_adjoint_modes, METH_VARARGS,
     "adjoint_modes(h, f, zeta, gain, n, psi): psi[r, k] = d (eps, deps)(n) / d (a_k, j_k) of "
     "each row r (a mode, frequencies f[r, k]) stepped as step_modes does."},
    {"adjoint_sums", engine_adjoint_sums, METH_VARARGS,
     "adjoint_sums(h, f, zeta, gain, n, S, factor=1.0): the adjoint of adjoint_modes as suffix sums, "
     "S[r, i, (a, k a, j), k] = sum over k' >= k of psi[r, k', i, .] (times k' for the "
     "second); S: (R, 2, 3, n + 1); frequencies f * factor."},
    {"run_program", (PyCFunction)(void (*)(void))engine_run_program,
     METH_VARARGS | METH_KEYWORDS,
     "run_program(params, program, count, h, out, start_time=0.0): the FMU's model (its "
     "DoStep, no FMI layer) initialised with params (FMU parameter names), then count steps "
     "of h s; program: (step, inputs) pairs in step order, the inputs (FMU input names) set "
     "before that step; out[i, k]: output i (output_names()) after step k. Raises PlanError "
     "as the FMU refuses."},
    {"output_names", engine_output_names, METH_NOARGS,
     "output_names() -> tuple: the FMU's outputs, in the order of run_program's rows."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef engine_module = {
    PyModuleDef_HEAD_INIT, "_engine",
    "Compiled evaluation path of the harness: the FMU's generator core and the plant.", -1,
    engine_methods, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit__engine(void)
{
    PyObject *m;
    m = PyModule_Create(&engine_module);
    if (!m) return NULL;
    PlanType = (PyTypeObject *)PyType_FromSpec(&plan_spec);
    if (!PlanType) {
        Py_DECREF(m);
        return NULL;
    }
    PlanError = PyErr_NewExceptionWithDoc(
        "harness._engine.PlanError",
        "The generator refused the parameters (the message is the FMU's). Attributes: status, "
        "param, value.", PyExc_ValueError, NULL);
    if (!PlanError || PyModule_AddObject(m, "PlanError", PlanError) < 0) {
        Py_XDECREF(PlanError);
        Py_DECREF(m);
        return NULL;
    }
    Py_INCREF((PyObject *)PlanType);
    if (PyModule_AddObject(m, "Plan", (PyObject *)PlanType) < 0) {
        Py_DECREF((PyObject *)PlanType);
        Py_DECREF(m);
        return NULL;
    }
    if (PyModule_AddIntConstant(m, "N_SAMPLE_VARS", N_SAMPLE_VARS) < 0 ||
        PyModule_AddIntConstant(m, "MAX_SEGMENTS", DJL_MAX_SEGMENTS) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
