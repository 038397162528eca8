/* The world's input taps in C: the extension `simatch.sim._inputs`, behind `simatch.sim.inputs` (see its
 * docstring).
 *
 * `Tap` is what the simulator's velocity and action commands are replaced by while its input log is on: one C
 * call that appends the command to the input log's lists in the compact form (VEL: robot, vx, vy, w; ACTION:
 * robot, dribble 0/1, kick speed, lob 0/1, window or NaN) and then calls the simulator's method, so that
 * logging the commands a match sends adds no Python frame per command. Any other call (keywords, another
 * count of arguments, a robot index that is not a small int, a call made while the log is busy) goes to
 * `general`, which logs it as a call.
 *
 * `pack` turns the log's lists into the machine arrays of the WorldInputs message.
 *
 * What this unit reads by offset, and who declares it: the log's `busy` mark, in the slot that the member
 * descriptor handed to `Tap` reads (`InputLog.busy`, declared by `InputLog.__slots__`); `Tap` checks that it
 * is a slot of the log's class.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <string.h>
#include <structmember.h>

enum { TAP_VEL = 1, TAP_ACTION = 2 };

typedef struct {
    PyObject_HEAD
    vectorcallfunc vectorcall;
    int form;                      /* TAP_VEL or TAP_ACTION */
    PyObject *original, *general, *log, *kind, *robot, *values, *code; /* code: the kind's int */
    Py_ssize_t busy_at;            /* where the log holds its `busy` mark */
} Tap;

static PyObject *zero = NULL, *one = NULL, *nan_value = NULL;

/* the log's `busy` mark (read as its member descriptor reads it): 1, 0, or -1 with an exception set */
static int tap_busy(Tap *tap) {
    PyObject *busy = *(PyObject **)((char *)tap->log + tap->busy_at);
    if (busy == Py_False)
        return 0;
    if (busy == Py_True)
        return 1;
    if (busy == NULL) {
        PyErr_SetString(PyExc_AttributeError, "the input log's busy mark is not set");
        return -1;
    }
    return PyObject_IsTrue(busy);
}

static int tap_append(Tap *tap, PyObject *index, PyObject *const *numbers, int n) {
    if (PyList_Append(tap->kind, tap->code) < 0 || PyList_Append(tap->robot, index) < 0)
        return -1;
    for (int k = 0; k < n; k++)
        if (PyList_Append(tap->values, numbers[k]) < 0)
            return -1;
    return 0;
}

/* is this call one the compact form holds (positional, the form's count of arguments, a small robot index)? */
static int compact_call(const Tap *tap, PyObject *const *args, Py_ssize_t nargs, PyObject *kwnames) {
    if ((kwnames != NULL && PyTuple_GET_SIZE(kwnames) != 0)
        || !(tap->form == TAP_VEL ? nargs == 4 : (nargs >= 2 && nargs <= 5)) || !PyLong_CheckExact(args[0]))
        return 0;
    int overflow = 0;
    long i = PyLong_AsLongAndOverflow(args[0], &overflow);
    return !overflow && i >= 0 && i < 32768;
}

static PyObject *tap_vectorcall(PyObject *self, PyObject *const *args, size_t nargsf, PyObject *kwnames) {
    Tap *tap = (Tap *)self;
    Py_ssize_t nargs = PyVectorcall_NARGS(nargsf);
    int compact = compact_call(tap, args, nargs, kwnames);
    if (compact) {
        int busy = tap_busy(tap);
        if (busy < 0)
            return NULL;
        compact = !busy;
    }
    if (!compact)
        return PyObject_Vectorcall(tap->general, args, nargsf, kwnames);
    int r;
    if (tap->form == TAP_VEL) {
        r = tap_append(tap, args[0], args + 1, 3);
    } else {                       /* dribble (0/1), kick_speed as given, lob (0/1), window (NaN: none) */
        int dribble = PyObject_IsTrue(args[1]), lob = nargs > 3 ? PyObject_IsTrue(args[3]) : 0;
        if (dribble < 0 || lob < 0)
            return NULL;
        PyObject *numbers[4] = {
            dribble ? one : zero,
            nargs > 2 ? args[2] : zero,
            lob ? one : zero,
            nargs > 4 && args[4] != Py_None ? args[4] : nan_value,
        };
        r = tap_append(tap, args[0], numbers, 4);
    }
    if (r < 0)
        return NULL;
    return PyObject_Vectorcall(tap->original, args, nargs, NULL);
}

/* the Python objects a Tap holds, for the garbage collector's visit and clear */
#define TAP_OBJECTS(X) X(original) X(general) X(log) X(kind) X(robot) X(values) X(code)
#define VISIT_MEMBER(field) Py_VISIT(self->field);
#define CLEAR_MEMBER(field) Py_CLEAR(self->field);

static int tap_traverse(Tap *self, visitproc visit, void *arg) {
    TAP_OBJECTS(VISIT_MEMBER)
    return 0;
}

static int tap_clear(Tap *self) {
    TAP_OBJECTS(CLEAR_MEMBER)
    return 0;
}

static void tap_dealloc(Tap *tap) {
    PyObject_GC_UnTrack(tap);
    tap_clear(tap);
    Py_TYPE(tap)->tp_free((PyObject *)tap);
}

/* where `log` holds the slot that `descr` (a member descriptor: InputLog.busy) reads; -1 (TypeError) if it is not
 * an object slot of the log's class */
static Py_ssize_t busy_offset(PyObject *log, PyObject *descr) {
    if (Py_IS_TYPE(descr, &PyMemberDescr_Type) && PyObject_TypeCheck(log, PyDescr_TYPE(descr))) {
        PyMemberDef *member = ((PyMemberDescrObject *)descr)->d_member;
        if (member->type == T_OBJECT_EX && !(member->flags & READ_RESTRICTED) && member->offset > 0)
            return member->offset;
    }
    PyErr_SetString(PyExc_TypeError, "Tap: busy must be the member descriptor of an object slot of the log's "
                                     "class (InputLog.busy)");
    return -1;
}

static PyObject *tap_new(PyTypeObject *type, PyObject *args, PyObject *kwds) {
    static char *kwlist[] = {"form", "original", "general", "log", "busy", "kind", "robot", "values", "code", NULL};
    const char *form;
    PyObject *original, *general, *log, *busy, *kind, *robot, *values, *code;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "sOOOOO!O!O!O", kwlist, &form, &original, &general, &log, &busy,
                                     &PyList_Type, &kind, &PyList_Type, &robot, &PyList_Type, &values, &code))
        return NULL;
    int f = strcmp(form, "vel") == 0 ? TAP_VEL : strcmp(form, "action") == 0 ? TAP_ACTION : 0;
    if (!f || !PyCallable_Check(original) || !PyCallable_Check(general)) {
        PyErr_SetString(PyExc_ValueError,
                        "Tap(form: \"vel\" or \"action\", original, general, log, busy, kind, robot, values, code)");
        return NULL;
    }
    Py_ssize_t busy_at = busy_offset(log, busy);
    if (busy_at < 0)
        return NULL;
    Tap *tap = (Tap *)type->tp_alloc(type, 0);
    if (tap == NULL)
        return NULL;
    tap->vectorcall = tap_vectorcall;
    tap->form = f;
    tap->busy_at = busy_at;
    tap->original = Py_NewRef(original);
    tap->general = Py_NewRef(general);
    tap->log = Py_NewRef(log);
    tap->kind = Py_NewRef(kind);
    tap->robot = Py_NewRef(robot);
    tap->values = Py_NewRef(values);
    tap->code = Py_NewRef(code);
    return (PyObject *)tap;
}

static PyObject *tap_get_wrapped(Tap *tap, void *closure) {
    return Py_NewRef(tap->original);
}

static PyGetSetDef tap_getset[] = {
    {"__wrapped__", (getter)tap_get_wrapped, NULL, "the simulator's method", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyTypeObject TapType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "simatch.sim._inputs.Tap",
    .tp_doc = "Tap(form, original, general, log, busy, kind, robot, values, code): a world input that logs its calls",
    .tp_basicsize = sizeof(Tap),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_new = tap_new,
    .tp_dealloc = (destructor)tap_dealloc,
    .tp_traverse = (traverseproc)tap_traverse,
    .tp_clear = (inquiry)tap_clear,
    .tp_call = PyVectorcall_Call,
    .tp_vectorcall_offset = offsetof(Tap, vectorcall),
    .tp_getset = tap_getset,
};
/* pack(list, code) -> bytearray | None: the list's numbers as one machine array ("d": float64 from exact floats,
 * exact ints (correctly rounded, as float() rounds them) and bools; "B": uint8 and "h": int16 from exact ints
 * in range), or None if an item is anything else (the caller converts those lists itself, one by one). */
static PyObject *pack(PyObject *self, PyObject *args) {
    PyObject *list;
    int code;
    if (!PyArg_ParseTuple(args, "O!C", &PyList_Type, &list, &code))
        return NULL;
    if (code != 'd' && code != 'B' && code != 'h') {
        PyErr_SetString(PyExc_ValueError, "pack: code 'd', 'B' or 'h'");
        return NULL;
    }
    Py_ssize_t n = PyList_GET_SIZE(list), size = code == 'd' ? 8 : code == 'h' ? 2 : 1;
    PyObject *result = PyByteArray_FromStringAndSize(NULL, n * size);
    if (result == NULL)
        return NULL;
    char *p = PyByteArray_AS_STRING(result);
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *v = PyList_GET_ITEM(list, i);
        if (code == 'd') {
            double d;
            if (PyFloat_CheckExact(v))
                d = PyFloat_AS_DOUBLE(v);
            else if (v == Py_True || v == Py_False)
                d = v == Py_True;
            else if (PyLong_CheckExact(v)) {
                d = PyLong_AsDouble(v);
                if (d == -1.0 && PyErr_Occurred())
                    goto other;                        /* beyond float64: the caller's */
            } else
                goto other;
            memcpy(p + 8 * i, &d, 8);
            continue;
        }
        if (!PyLong_CheckExact(v))
            goto other;
        int overflow;
        long x = PyLong_AsLongAndOverflow(v, &overflow);
        if (overflow || (code == 'B' ? (x < 0 || x > 255) : (x < -32768 || x > 32767)))
            goto other;
        if (code == 'B')
            p[i] = (char)(unsigned char)x;
        else {
            short h = (short)x;
            memcpy(p + 2 * i, &h, 2);
        }
    }
    return result;
other:
    PyErr_Clear();
    Py_DECREF(result);
    Py_RETURN_NONE;
}


static PyMethodDef methods[] = {
    {"pack", pack, METH_VARARGS, "pack(list, 'd'|'B'|'h') -> the numbers as a bytearray, or None: convert them yourself"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_inputs", NULL, -1, methods};

/* what this build was made from (setup.py: the first 16 hex digits of the SHA-256 of its source) */
#ifndef SIMATCH_SOURCE_DIGEST
#define SIMATCH_SOURCE_DIGEST ""
#endif

PyMODINIT_FUNC PyInit__inputs(void) {
    if (PyType_Ready(&TapType) < 0 || (zero = PyFloat_FromDouble(0.0)) == NULL
        || (one = PyFloat_FromDouble(1.0)) == NULL || (nan_value = PyFloat_FromDouble(Py_NAN)) == NULL)
        return NULL;
    PyObject *m = PyModule_Create(&module);
    if (m == NULL)
        return NULL;
    if (PyModule_AddObjectRef(m, "Tap", (PyObject *)&TapType) < 0
        || PyModule_AddStringConstant(m, "SOURCE_DIGEST", SIMATCH_SOURCE_DIGEST) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
