/* Positional construction of slotted message classes without running their Python __init__.
 *
 * simatch's message classes (see simatch/msgs/__init__.py, `_with_slots`) are dataclasses with
 * __slots__ whose generated __init__ only stores each argument in its slot. The hot paths build a few
 * thousand of them per simulated second (perception, robot commands, model states), and calling the
 * class costs a Python frame per message: type_call, slot_tp_init, the argument tuple, one STORE_ATTR
 * per field. A `Maker` does the same in C: it allocates an instance of the class and puts each argument
 * into its slot at the slot's offset (read from the class's member descriptors when the Maker is made),
 * the fields not given taking their defaults. The result is an ordinary instance of the class, the same
 * as the class's own constructor makes from the same arguments (tests/msgs/test_positional.py holds them
 * equal for every message type).
 *
 * A Maker is made only for a class it can build exactly: every field a writable object slot, no
 * instance dict, object's own __new__ (checked here), and a generated __init__ that stores its
 * arguments and nothing else (checked by `simatch.msgs.positional`, which makes Makers). Anything else
 * a caller passes (keyword arguments, a wrong number of arguments) goes to the class itself, which
 * raises its usual error.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <structmember.h>

typedef struct {
    PyObject_HEAD
    PyTypeObject *cls;     /* the message class (a strong reference) */
    Py_ssize_t nfields;    /* its fields, in constructor order */
    Py_ssize_t nrequired;  /* how many a call must give (the rest have defaults) */
    PyObject *defaults;    /* tuple: the defaults of fields nrequired .. nfields-1 */
    Py_ssize_t *offsets;   /* each field's slot offset in an instance */
    vectorcallfunc vectorcall;
} Maker;

static PyObject *
maker_vectorcall(PyObject *self, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    Maker *mk = (Maker *)self;
    Py_ssize_t n = PyVectorcall_NARGS(nargsf);
    if (kwnames != NULL || n < mk->nrequired || n > mk->nfields) {
        /* not the positional form this Maker was made for: the class's own constructor decides */
        return PyObject_Vectorcall((PyObject *)mk->cls, args, nargsf, kwnames);
    }
    PyObject *obj = mk->cls->tp_alloc(mk->cls, 0); /* zeroed: every slot starts empty */
    if (obj == NULL) {
        return NULL;
    }
    char *base = (char *)obj;
    Py_ssize_t i = 0;
    for (; i < n; i++) {
        PyObject *v = args[i];
        Py_INCREF(v);
        *(PyObject **)(base + mk->offsets[i]) = v;
    }
    for (; i < mk->nfields; i++) {
        PyObject *v = PyTuple_GET_ITEM(mk->defaults, i - mk->nrequired);
        Py_INCREF(v);
        *(PyObject **)(base + mk->offsets[i]) = v;
    }
    return obj;
}

static void
maker_dealloc(Maker *mk)
{
    PyObject_GC_UnTrack(mk);
    Py_CLEAR(mk->cls);
    Py_CLEAR(mk->defaults);
    PyMem_Free(mk->offsets);
    PyObject_GC_Del(mk);
}

static int
maker_traverse(Maker *mk, visitproc visit, void *arg)
{
    Py_VISIT(mk->cls);
    Py_VISIT(mk->defaults);
    return 0;
}

static PyObject *
maker_repr(Maker *mk)
{
    return PyUnicode_FromFormat("<positional maker of %s>", mk->cls->tp_name);
}

static PyObject *
maker_get_cls(Maker *mk, void *closure)
{
    Py_INCREF(mk->cls);
    return (PyObject *)mk->cls;
}

static PyGetSetDef maker_getset[] = {
    {"cls", (getter)maker_get_cls, NULL, "the class whose instances this maker builds", NULL},
    {NULL},
};

static PyTypeObject MakerType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "simatch.msgs._positional.Maker",
    .tp_basicsize = sizeof(Maker),
    .tp_dealloc = (destructor)maker_dealloc,
    .tp_vectorcall_offset = offsetof(Maker, vectorcall),
    .tp_call = PyVectorcall_Call,
    .tp_repr = (reprfunc)maker_repr,
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_traverse = (traverseproc)maker_traverse,
    .tp_getset = maker_getset,
    .tp_doc = "Builds instances of one slotted message class from positional arguments (see the module).",
};

/* maker(cls, fields, defaults): fields a tuple of the slot names in constructor order, defaults a tuple of
 * the values of the last len(defaults) fields. */
static PyObject *
make(PyObject *module, PyObject *args)
{
    PyObject *cls, *fields, *defaults;
    if (!PyArg_ParseTuple(args, "O!O!O!:maker", &PyType_Type, &cls, &PyTuple_Type, &fields, &PyTuple_Type,
                          &defaults)) {
        return NULL;
    }
    PyTypeObject *type = (PyTypeObject *)cls;
    Py_ssize_t nfields = PyTuple_GET_SIZE(fields);
    Py_ssize_t ndefaults = PyTuple_GET_SIZE(defaults);
    if (ndefaults > nfields) {
        PyErr_SetString(PyExc_ValueError, "more defaults than fields");
        return NULL;
    }
    if (type->tp_new != PyBaseObject_Type.tp_new || type->tp_dictoffset != 0 || type->tp_alloc == NULL) {
        PyErr_Format(PyExc_TypeError, "%s is not a slotted class built by object's own __new__", type->tp_name);
        return NULL;
    }
    Py_ssize_t *offsets = PyMem_Malloc(sizeof(Py_ssize_t) * (nfields ? nfields : 1));
    if (offsets == NULL) {
        return PyErr_NoMemory();
    }
    for (Py_ssize_t i = 0; i < nfields; i++) {
        PyObject *name = PyTuple_GET_ITEM(fields, i);
        PyObject *descr = PyDict_GetItemWithError(type->tp_dict, name); /* borrowed */
        if (descr == NULL || Py_TYPE(descr) != &PyMemberDescr_Type) {
            PyMem_Free(offsets);
            if (!PyErr_Occurred()) {
                PyErr_Format(PyExc_TypeError, "%s.%S is not a slot of the class itself", type->tp_name, name);
            }
            return NULL;
        }
        PyMemberDef *member = ((PyMemberDescrObject *)descr)->d_member;
        if (member->type != T_OBJECT_EX || (member->flags & READONLY) || member->offset <= 0 ||
            member->offset + (Py_ssize_t)sizeof(PyObject *) > type->tp_basicsize) {
            PyMem_Free(offsets);
            PyErr_Format(PyExc_TypeError, "%s.%S is not a writable object slot", type->tp_name, name);
            return NULL;
        }
        offsets[i] = member->offset;
    }
    Maker *mk = PyObject_GC_New(Maker, &MakerType);
    if (mk == NULL) {
        PyMem_Free(offsets);
        return NULL;
    }
    Py_INCREF(cls);
    mk->cls = type;
    Py_INCREF(defaults);
    mk->defaults = defaults;
    mk->nfields = nfields;
    mk->nrequired = nfields - ndefaults;
    mk->offsets = offsets;
    mk->vectorcall = maker_vectorcall;
    PyObject_GC_Track(mk);
    return (PyObject *)mk;
}

static PyMethodDef methods[] = {
    {"maker", make, METH_VARARGS,
     "maker(cls, fields, defaults) -> a callable building cls instances from positional arguments"},
    {NULL},
};

/* what this build was made from (setup.py; see _cdr_accel.c) */
#ifndef SIMATCH_SOURCE_DIGEST
#define SIMATCH_SOURCE_DIGEST ""
#endif

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT, "simatch.msgs._positional",
    "Positional construction of slotted message classes in C (see simatch.msgs.positional).", -1, methods,
};

PyMODINIT_FUNC
PyInit__positional(void)
{
    if (PyType_Ready(&MakerType) < 0) {
        return NULL;
    }
    PyObject *m = PyModule_Create(&module_def);
    if (m != NULL && PyModule_AddStringConstant(m, "SOURCE_DIGEST", SIMATCH_SOURCE_DIGEST) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
