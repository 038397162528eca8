/* The CDR codec in C: the encoder and decoder behind `simatch.msgs.cdr` (see its docstring).
 *
 * `simatch.msgs.cdr` compiles, once per message type, a "program" from the type store:
 *
 *     program = ((kind, attribute name, argument), ...)
 *
 * kinds (K_* in _cdr_accel.h): a primitive (argument unused), a string, a nested message (argument: its
 * program), a sequence or fixed array of primitives (argument: (element kind, length or -1)), of strings
 * (argument: length or -1) or of messages (argument: (program, length or -1, alignment of its first field)).
 * `compile` turns such a tuple into C structures once; `encode` walks a message with it. The same programs,
 * with each message's class, decode payloads (`decode`). The recorder's message log (`Log`,
 * simatch/record/_messagelog.c) is compiled into this extension and encodes with the same functions.
 *
 * Output: XCDR1 little endian with the 4-byte encapsulation header, byte for byte what rosbags writes
 * (checked type by type by tests/msgs/test_cdr.py). Anything the encoder does not take as it is (a primitive
 * sequence that is not a contiguous little-endian buffer of the wire's type, a wrong fixed length, a value of
 * the wrong type) makes it return None without an exception: the caller then uses the generated Python
 * encoder, which converts what it can and raises the canonical error otherwise.
 *
 * This unit is the module: its functions, and the numpy layout the encoder and the decoder read arrays by. The
 * layers are units of their own (`_cdr_accel.h` names them). What they read by offset, and who declares it:
 * - numpy's array and dtype objects: `simatch.msgs.cdr` declares the fields' offsets and checks them on an
 *   array; `setup` checks them against `ArrayHead` and `DescrHead` (`_cdr_accel.h`).
 * - a message's fields: the slots of its class, found through the class's member descriptors (`slot_offset`,
 *   `_cdr_program.c`, guarded by the class's version tag; the classes are made slotted by
 *   `simatch.msgs._with_slots`).
 */
#include "_cdr_accel.h"

int c_contiguous = 0;
PyTypeObject *ndarray = NULL;
PyObject *dtypes[16];

/* `declared` ({field: offset}, from simatch.msgs.cdr) names the `n` fields of numpy's `what` at `offsets` */
static int check_offsets(PyObject *declared, const char *what, const char *const *names, const Py_ssize_t *offsets,
                         int n) {
    if (!PyDict_Check(declared) || PyDict_GET_SIZE(declared) != n) {
        PyErr_Format(PyExc_ImportError, "simatch.msgs._cdr_accel: the %s layout declared by simatch.msgs.cdr "
                                        "does not name the %d fields this extension reads", what, n);
        return -1;
    }
    for (int i = 0; i < n; i++) {
        PyObject *v = PyDict_GetItemString(declared, names[i]);      /* borrowed */
        Py_ssize_t at = v == NULL ? -1 : PyLong_AsSsize_t(v);
        if (at == -1 && PyErr_Occurred())
            return -1;
        if (at != offsets[i]) {
            PyErr_Format(PyExc_ImportError, "simatch.msgs._cdr_accel reads the %s field %s at byte %zd, and "
                                            "simatch.msgs.cdr declares it at %zd: rebuild the extension "
                                            "(pip install -e .) or mend the declaration", what, names[i],
                         offsets[i], at);
            return -1;
        }
    }
    return 0;
}

/* setup(ndarray type, {kind: dtype}, {field: offset} of the array, {field: offset} of the dtype, C-contiguous
 * flag): the arrays the encoder reads directly and the decoder makes. The offsets are those that
 * `simatch.msgs.cdr` declares and has checked on an array; they must be those of `ArrayHead` and `DescrHead`. */
static PyObject *setup(PyObject *self, PyObject *args) {
    PyObject *type, *kinds, *array_layout, *dtype_layout;
    int contiguous;
    if (!PyArg_ParseTuple(args, "O!O!OOi", &PyType_Type, &type, &PyDict_Type, &kinds, &array_layout, &dtype_layout,
                          &contiguous))
        return NULL;
    static const char *const array_names[] = {"data", "nd", "dimensions", "strides", "base", "descr", "flags"};
    static const Py_ssize_t array_offsets[] = {
        offsetof(ArrayHead, data), offsetof(ArrayHead, nd), offsetof(ArrayHead, dimensions),
        offsetof(ArrayHead, strides), offsetof(ArrayHead, base), offsetof(ArrayHead, descr),
        offsetof(ArrayHead, flags)};
    static const char *const dtype_names[] = {"typeobj", "kind", "type", "byteorder"};
    static const Py_ssize_t dtype_offsets[] = {offsetof(DescrHead, typeobj), offsetof(DescrHead, kind),
                                               offsetof(DescrHead, type), offsetof(DescrHead, byteorder)};
    if (check_offsets(array_layout, "array", array_names, array_offsets, 7) < 0
        || check_offsets(dtype_layout, "dtype", dtype_names, dtype_offsets, 4) < 0)
        return NULL;
    if (((PyTypeObject *)type)->tp_basicsize < (Py_ssize_t)sizeof(ArrayHead)) {
        PyErr_SetString(PyExc_ImportError, "simatch.msgs._cdr_accel: numpy's array object is smaller than the "
                                           "fields declared by simatch.msgs.cdr");
        return NULL;
    }
    PyObject *key, *value;
    Py_ssize_t pos = 0;
    while (PyDict_Next(kinds, &pos, &key, &value)) {
        long k = PyLong_AsLong(key);
        if (k < 0 || k >= 16) {
            PyErr_SetString(PyExc_ValueError, "kind out of range");
            return NULL;
        }
        Py_INCREF(value);
        Py_XSETREF(dtypes[k], value);
    }
    c_contiguous = contiguous;
    Py_INCREF(type);
    Py_XSETREF(ndarray, (PyTypeObject *)type);
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"encode", encode, METH_VARARGS, "encode(compiled program, msg) -> CDR bytes with the header, or None: use Python"},
    {"setup", setup, METH_VARARGS,
     "setup(ndarray, {kind: dtype}, array layout, dtype layout, C-contiguous flag): numpy as simatch.msgs.cdr declares"},
    {"compile", compile, METH_O, "compile(program tuple) -> the compiled program that encode and Log take"},
    {"compile_decoder", compile_decoder, METH_O, "compile_decoder((class, ops)) -> the program decode takes"},
    {"decode", decode, METH_VARARGS, "decode(compiled decoder program, payload bytes) -> message, or MessageError"},
    {"setup_decoding", setup_decoding, METH_O, "setup_decoding(MessageError): the error decode raises"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_cdr_accel", NULL, -1, methods};

/* what this build was made from (setup.py: the first 16 hex digits of the SHA-256 of its sources), so that a test
 * can tell an extension left from older sources */
#ifndef SIMATCH_SOURCE_DIGEST
#define SIMATCH_SOURCE_DIGEST ""
#endif

PyMODINIT_FUNC PyInit__cdr_accel(void) {
    PyObject *m = PyModule_Create(&module);
    if (m == NULL)
        return NULL;
    if (messagelog_add_types(m) < 0 || PyModule_AddStringConstant(m, "SOURCE_DIGEST", SIMATCH_SOURCE_DIGEST) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
