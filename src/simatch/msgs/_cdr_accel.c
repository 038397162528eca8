/* CDR encoding of message objects in C: the hot path of `simatch.msgs.cdr` (see its docstring).
 *
 * A recording encodes some two thousand messages per simulated second on the thread that runs the
 * simulation; the generated Python encoders are at their floor there (bytecode per field), so this module
 * walks a message with a "program" that `simatch.msgs.cdr` compiles once per type from the type store:
 *
 *     program = ((kind, attribute name, argument), ...)
 *
 * kinds (K_* below): a primitive (argument unused), a string, a nested message (argument: its program),
 * a sequence or fixed array of primitives (argument: (element kind, length or -1)), of strings (argument:
 * length or -1) or of messages (argument: (program, length or -1)).
 *
 * Output: XCDR1 little endian with the 4-byte encapsulation header, byte for byte what rosbags writes
 * (checked type by type by tests/msgs/test_cdr.py). Anything this fast path does not take as it is (a
 * primitive sequence that is not a contiguous little-endian buffer of the wire's type, a wrong fixed
 * length, a value of the wrong type) makes it return None without an exception: the caller then uses the
 * pure-Python encoder, which converts what it can and raises the canonical error otherwise.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <string.h>

enum {
    K_BOOL = 1, K_I8, K_U8, K_I16, K_U16, K_I32, K_U32, K_I64, K_U64, K_F32, K_F64,
    K_STR = 20, K_MSG, K_PSEQ, K_SSEQ, K_MSEQ
};

typedef struct {
    char *p;
    Py_ssize_t n, cap;
} Buf;

static Buf buf = {NULL, 0, 0};     /* reused between calls: the GIL is held throughout */

/* numpy arrays without numpy's headers: the leading fields of numpy's array object, whose layout is part of
 * numpy's ABI (extensions built against old headers run with new numpy). `setup` hands over the ndarray
 * type and the dtype object of each kind, and checks this reading on a sample array before enabling it;
 * without it every array goes through the buffer protocol. */
typedef struct {
    PyObject_HEAD
    char *data;
    int nd;
    Py_ssize_t *dimensions;
    Py_ssize_t *strides;
    PyObject *base;
    PyObject *descr;
    int flags;
} ArrayHead;

#define C_CONTIGUOUS 0x0001
static PyTypeObject *ndarray = NULL;
static PyObject *dtypes[16];       /* by kind: the dtype object of contiguous arrays taken as they are */

#define FALLBACK 1                 /* not for the fast path: the caller uses the Python encoder */
#define FAILED -1                  /* a Python exception is set (memory) */

static int reserve(Py_ssize_t need) {
    if (buf.n + need <= buf.cap)
        return 0;
    Py_ssize_t cap = buf.cap ? buf.cap : 4096;
    while (cap < buf.n + need)
        cap *= 2;
    char *p = PyMem_Realloc(buf.p, cap);
    if (p == NULL) {
        PyErr_NoMemory();
        return FAILED;
    }
    buf.p = p;
    buf.cap = cap;
    return 0;
}

/* pad with zeros to a multiple of `a`, counted from the start of the body (after the 4-byte header) */
static int align(int a) {
    Py_ssize_t pad = (a - ((buf.n - 4) % a)) % a;
    if (pad) {
        if (reserve(pad) < 0)
            return FAILED;
        memset(buf.p + buf.n, 0, pad);
        buf.n += pad;
    }
    return 0;
}

static int put(const void *src, Py_ssize_t size) {
    if (reserve(size) < 0)
        return FAILED;
    memcpy(buf.p + buf.n, src, size);
    buf.n += size;
    return 0;
}

static int size_of(long kind) {
    switch (kind) {
    case K_BOOL: case K_I8: case K_U8: return 1;
    case K_I16: case K_U16: return 2;
    case K_I32: case K_U32: case K_F32: return 4;
    default: return 8;
    }
}

/* a primitive value; FALLBACK (exception cleared) if it is not one struct would pack the same way */
static int put_primitive(long kind, PyObject *v) {
    int size = size_of(kind);
    if (align(size) < 0)
        return FAILED;
    unsigned char out[8];
    if (kind == K_F64 || kind == K_F32) {
        double d = PyFloat_Check(v) ? PyFloat_AS_DOUBLE(v) : PyFloat_AsDouble(v);
        if (d == -1.0 && PyErr_Occurred())
            goto fallback;
        if (kind == K_F64)
            memcpy(out, &d, 8);
        else if (PyFloat_Pack4(d, (char *)out, 1) < 0)
            goto fallback;
        return put(out, size);
    }
    if (kind == K_BOOL) {
        int t = PyObject_IsTrue(v);
        if (t < 0)
            goto fallback;
        out[0] = (unsigned char)t;
        return put(out, 1);
    }
    if (!PyLong_Check(v)) {                /* a numpy integer: its __index__, as struct takes it */
        PyObject *i = PyNumber_Index(v);
        if (i == NULL)
            goto fallback;
        int r = put_primitive(kind, i);
        Py_DECREF(i);
        return r;
    }
    if (kind == K_U64) {
        unsigned long long u = PyLong_AsUnsignedLongLong(v);
        if (u == (unsigned long long)-1 && PyErr_Occurred())
            goto fallback;
        memcpy(out, &u, 8);
        return put(out, 8);
    }
    long long x = PyLong_AsLongLong(v);
    if (x == -1 && PyErr_Occurred())
        goto fallback;
    switch (kind) {
    case K_I8: if (x < -128 || x > 127) return FALLBACK; { signed char c = (signed char)x; memcpy(out, &c, 1); } break;
    case K_U8: if (x < 0 || x > 255) return FALLBACK; out[0] = (unsigned char)x; break;
    case K_I16: if (x < -32768 || x > 32767) return FALLBACK; { short s = (short)x; memcpy(out, &s, 2); } break;
    case K_U16: if (x < 0 || x > 65535) return FALLBACK; { unsigned short s = (unsigned short)x; memcpy(out, &s, 2); } break;
    case K_I32: if (x < INT32_MIN || x > INT32_MAX) return FALLBACK; { int i = (int)x; memcpy(out, &i, 4); } break;
    case K_U32: if (x < 0 || x > UINT32_MAX) return FALLBACK; { unsigned int i = (unsigned int)x; memcpy(out, &i, 4); } break;
    case K_I64: memcpy(out, &x, 8); break;
    default: return FALLBACK;
    }
    return put(out, size);
fallback:
    PyErr_Clear();
    return FALLBACK;
}

static int put_u32(Py_ssize_t n) {
    if (n > (Py_ssize_t)UINT32_MAX)
        return FALLBACK;
    if (align(4) < 0)
        return FAILED;
    unsigned int u = (unsigned int)n;
    return put(&u, 4);
}

static int put_string(PyObject *v) {
    if (!PyUnicode_Check(v))
        return FALLBACK;
    Py_ssize_t len;
    const char *s = PyUnicode_AsUTF8AndSize(v, &len);
    if (s == NULL) {
        PyErr_Clear();
        return FALLBACK;
    }
    int r = put_u32(len + 1);
    if (r)
        return r;
    if (reserve(len + 1) < 0)
        return FAILED;
    memcpy(buf.p + buf.n, s, len);
    buf.p[buf.n + len] = 0;
    buf.n += len + 1;
    return 0;
}

/* does a buffer's struct format describe the wire's element type (little endian or native)? */
static int format_fits(long kind, const char *fmt, Py_ssize_t itemsize) {
    if (fmt == NULL)
        return 0;
    if (*fmt == '<' || *fmt == '=' || *fmt == '@')
        fmt++;
    if (fmt[0] == 0 || fmt[1] != 0 || itemsize != size_of(kind))
        return 0;
    char c = fmt[0];
    switch (kind) {
    case K_F64: return c == 'd';
    case K_F32: return c == 'f';
    case K_BOOL: return c == '?';
    case K_I8: return c == 'b';
    case K_U8: return c == 'B';
    case K_I16: return c == 'h';
    case K_U16: return c == 'H';
    case K_I32: case K_I64: return c == 'i' || c == 'l' || c == 'q';
    case K_U32: case K_U64: return c == 'I' || c == 'L' || c == 'Q';
    default: return 0;
    }
}

static int encode_program(PyObject *program, PyObject *msg);
static int put_items(PyObject *v, Py_ssize_t fixed, PyObject *program, int align_first);

static int put_primitives(PyObject *v, PyObject *arg) {
    long kind = PyLong_AsLong(PyTuple_GET_ITEM(arg, 0));
    Py_ssize_t fixed = PyLong_AsSsize_t(PyTuple_GET_ITEM(arg, 1));
    if (Py_TYPE(v) == ndarray && kind < 16) {
        ArrayHead *a = (ArrayHead *)v;
        if (a->nd == 1 && a->descr == dtypes[kind] && (a->flags & C_CONTIGUOUS)) {
            Py_ssize_t n = a->dimensions[0];
            int r;
            if (fixed >= 0) {
                if (n != fixed)
                    return FALLBACK;
            } else if ((r = put_u32(n)) != 0) {
                return r;
            }
            if (n && (align(size_of(kind)) < 0 || put(a->data, n * size_of(kind)) < 0))
                return FAILED;
            return 0;
        }
    }
    Py_buffer view;
    if (PyObject_GetBuffer(v, &view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) {
        PyErr_Clear();
        return FALLBACK;                   /* a list, a strided view: the Python encoder converts it */
    }
    int r = FALLBACK;
    if (!format_fits(kind, view.format, view.itemsize))
        goto done;
    Py_ssize_t n = view.len / view.itemsize;
    if (fixed >= 0) {
        if (n != fixed)
            goto done;
    } else if ((r = put_u32(n)) != 0) {
        goto done;
    }
    if (n) {
        if ((r = align(size_of(kind))) < 0 || (r = put(view.buf, view.len)) < 0)
            goto done;
    }
    r = 0;
done:
    PyBuffer_Release(&view);
    return r;
}

/* The memo (see simatch.msgs.cdr): two dicts, this period's and the last one's, id(object) -> (object,
 * phase, bytes): a list met again at the same phase (offset modulo 8), or a message encoded on its own
 * (phase 0, its body) met again inside a sequence. NULL: no memo. */
static PyObject *memo_now = NULL, *memo_old = NULL;

static PyObject *memo_find(PyObject *obj, long phase) {
    PyObject *key = PyLong_FromVoidPtr(obj);
    if (key == NULL)
        return NULL;
    PyObject *hit = PyDict_GetItemWithError(memo_now, key);
    if (hit == NULL && !PyErr_Occurred() && memo_old != NULL)
        hit = PyDict_GetItemWithError(memo_old, key);
    Py_DECREF(key);
    if (hit == NULL || !PyTuple_Check(hit) || PyTuple_GET_SIZE(hit) != 3 || PyTuple_GET_ITEM(hit, 0) != obj
        || PyLong_AsLong(PyTuple_GET_ITEM(hit, 1)) != phase)
        return NULL;
    return PyTuple_GET_ITEM(hit, 2);            /* borrowed */
}

static int memo_keep(PyObject *obj, long phase, Py_ssize_t start) {
    PyObject *key = PyLong_FromVoidPtr(obj);
    PyObject *data = PyBytes_FromStringAndSize(buf.p + start, buf.n - start);
    PyObject *entry = (key && data) ? Py_BuildValue("(OlO)", obj, phase, data) : NULL;
    int r = entry ? PyDict_SetItem(memo_now, key, entry) : -1;
    Py_XDECREF(key);
    Py_XDECREF(data);
    Py_XDECREF(entry);
    return r < 0 ? FAILED : 0;
}

static long phase_now(void) {
    return (long)((buf.n - 4) & 7);
}

static int put_bytes_object(PyObject *data) {
    return put(PyBytes_AS_STRING(data), PyBytes_GET_SIZE(data));
}

/* a sequence (or fixed array) of strings (program NULL) or of messages (align: their first field's) */
static int put_items(PyObject *v, Py_ssize_t fixed, PyObject *program, int align_first) {
    long phase = phase_now();
    Py_ssize_t start = buf.n;
    if (memo_now != NULL) {
        PyObject *hit = memo_find(v, phase);
        if (hit != NULL)
            return put_bytes_object(hit);
        if (PyErr_Occurred())
            return FAILED;
    }
    PyObject *seq = PySequence_Fast(v, "");
    if (seq == NULL) {
        PyErr_Clear();
        return FALLBACK;
    }
    Py_ssize_t n = PySequence_Fast_GET_SIZE(seq);
    int r = 0;
    if (fixed >= 0 ? n != fixed : (r = put_u32(n)) != 0) {
        Py_DECREF(seq);
        return r ? r : FALLBACK;
    }
    PyObject **items = PySequence_Fast_ITEMS(seq);
    for (Py_ssize_t i = 0; i < n && r == 0; i++) {
        if (program == NULL) {
            r = put_string(items[i]);
            continue;
        }
        if (memo_now != NULL && align_first > 0) {     /* this message encoded on its own before? */
            Py_ssize_t pad = (align_first - ((buf.n - 4) % align_first)) % align_first;
            if (((buf.n - 4 + pad) & 7) == 0) {
                PyObject *hit = memo_find(items[i], 0);
                if (hit != NULL) {
                    if ((r = align(align_first)) == 0)
                        r = put_bytes_object(hit);
                    continue;
                }
                if (PyErr_Occurred()) {
                    r = FAILED;
                    break;
                }
            }
        }
        r = encode_program(program, items[i]);
    }
    Py_DECREF(seq);
    if (r == 0 && memo_now != NULL && n > 0)
        r = memo_keep(v, phase, start);
    return r;
}

static int encode_program(PyObject *program, PyObject *msg) {
    Py_ssize_t count = PyTuple_GET_SIZE(program);
    for (Py_ssize_t i = 0; i < count; i++) {
        PyObject *op = PyTuple_GET_ITEM(program, i);
        long kind = PyLong_AsLong(PyTuple_GET_ITEM(op, 0));
        PyObject *v = PyObject_GetAttr(msg, PyTuple_GET_ITEM(op, 1));
        if (v == NULL) {
            PyErr_Clear();
            return FALLBACK;
        }
        PyObject *arg = PyTuple_GET_ITEM(op, 2);
        int r;
        if (kind < K_STR)
            r = put_primitive(kind, v);
        else if (kind == K_STR)
            r = put_string(v);
        else if (kind == K_MSG)
            r = encode_program(arg, v);
        else if (kind == K_PSEQ)
            r = put_primitives(v, arg);
        else if (kind == K_SSEQ)
            r = put_items(v, PyLong_AsSsize_t(arg), NULL, 0);
        else
            r = put_items(v, PyLong_AsSsize_t(PyTuple_GET_ITEM(arg, 1)), PyTuple_GET_ITEM(arg, 0),
                          (int)PyLong_AsLong(PyTuple_GET_ITEM(arg, 2)));
        Py_DECREF(v);
        if (r)
            return r;
    }
    return 0;
}

/* encode(program, msg[, memo, keep, out]): memo = (this period's dict, the last one's dict) or None; keep:
 * remember this message's body (it may be met again inside a sequence); out: a bytearray to append the
 * bytes to (then the number of bytes is returned) instead of returning them as bytes */
static PyObject *encode(PyObject *self, PyObject *args) {
    PyObject *program, *msg, *memo = Py_None, *out = Py_None;
    int keep = 0;
    if (!PyArg_ParseTuple(args, "O!O|OpO", &PyTuple_Type, &program, &msg, &memo, &keep, &out))
        return NULL;
    if (out != Py_None && !PyByteArray_Check(out)) {
        PyErr_SetString(PyExc_TypeError, "out: a bytearray or None");
        return NULL;
    }
    memo_now = memo_old = NULL;
    if (memo != Py_None) {
        if (!PyTuple_Check(memo) || PyTuple_GET_SIZE(memo) != 2 || !PyDict_Check(PyTuple_GET_ITEM(memo, 0))
            || !PyDict_Check(PyTuple_GET_ITEM(memo, 1))) {
            PyErr_SetString(PyExc_TypeError, "memo: (dict, dict) or None");
            return NULL;
        }
        memo_now = PyTuple_GET_ITEM(memo, 0);
        memo_old = PyTuple_GET_ITEM(memo, 1);
    }
    buf.n = 0;
    if (reserve(4) < 0)
        return NULL;
    memcpy(buf.p, "\x00\x01\x00\x00", 4);
    buf.n = 4;
    int r = encode_program(program, msg);
    if (r == 0 && keep && memo_now != NULL)
        r = memo_keep(msg, 0, 4);
    memo_now = memo_old = NULL;
    if (r == FAILED)
        return NULL;
    if (r == FALLBACK)
        Py_RETURN_NONE;
    if (out == Py_None)
        return PyBytes_FromStringAndSize(buf.p, buf.n);
    Py_ssize_t at = PyByteArray_GET_SIZE(out);
    if (PyByteArray_Resize(out, at + buf.n) < 0)
        return NULL;
    memcpy(PyByteArray_AS_STRING(out) + at, buf.p, buf.n);
    return PyLong_FromSsize_t(buf.n);
}

/* setup(ndarray type, {kind: dtype}, sample float64 array) -> whether arrays are read directly */
static PyObject *setup(PyObject *self, PyObject *args) {
    PyObject *type, *kinds, *sample;
    if (!PyArg_ParseTuple(args, "O!O!O", &PyType_Type, &type, &PyDict_Type, &kinds, &sample))
        return NULL;
    if (Py_TYPE(sample) != (PyTypeObject *)type || ((PyTypeObject *)type)->tp_basicsize < (Py_ssize_t)sizeof(ArrayHead))
        Py_RETURN_FALSE;
    ArrayHead *a = (ArrayHead *)sample;
    /* the sample is np.arange(3.0): one dimension of 3, contiguous, values 0 1 2 */
    if (a->nd != 1 || a->dimensions[0] != 3 || !(a->flags & C_CONTIGUOUS) || ((double *)a->data)[2] != 2.0)
        Py_RETURN_FALSE;
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
    if (dtypes[K_F64] != a->descr)
        Py_RETURN_FALSE;
    Py_INCREF(type);
    Py_XSETREF(ndarray, (PyTypeObject *)type);
    Py_RETURN_TRUE;
}

static PyMethodDef methods[] = {
    {"encode", encode, METH_VARARGS, "encode(program, msg) -> CDR bytes with the header, or None: use Python"},
    {"setup", setup, METH_VARARGS, "setup(ndarray, {kind: dtype}, np.arange(3.0)) -> arrays read directly"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_cdr_accel", NULL, -1, methods};

PyMODINIT_FUNC PyInit__cdr_accel(void) {
    return PyModule_Create(&module);
}
