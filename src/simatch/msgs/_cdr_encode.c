/* The CDR encoder of `simatch.msgs.cdr` (see `_cdr_accel.c` for the programs it walks and the wire): a message
 * walked field by field by its compiled program, each value written into `out` (`encode`'s scratch buffer, or
 * a message log's chunk); a list or message met again copied from the memo (`_cdr_memo.c`). Anything not taken
 * as it is returns FALLBACK: the caller uses the generated Python encoder.
 *
 * What this unit reads by offset: numpy's arrays (`ArrayHead`, `DescrHead`, checked by `setup`) and a message's
 * slots (at the offsets `learn` found, `_cdr_program.c`).
 */
#include "_cdr_accel.h"

static Buf scratch = {NULL, 0, 0, 0}; /* `encode`'s output, reused between calls: the GIL is held throughout */
Buf *out = &scratch;
Py_ssize_t body = 4;

int grow(Py_ssize_t need) {
    Py_ssize_t cap = out->cap ? out->cap : 4096;
    while (cap < out->n + need)
        cap *= 2;
    char *p = out->lent ? PyMem_Malloc(cap) : PyMem_Realloc(out->p, cap);
    if (p == NULL) {
        PyErr_NoMemory();
        return FAILED;
    }
    if (out->lent) {                                  /* the lent memory is full: go on in memory of our own */
        memcpy(p, out->p, out->n);
        out->lent = 0;
    }
    out->p = p;
    out->cap = cap;
    return 0;
}


/* `size` bytes at the next multiple of `size` (1, 2, 4 or 8) from the body's start: align and put in one */
static inline int put_aligned(const void *src, int size) {
    Py_ssize_t pad = (body - out->n) & (size - 1);
    if (out->n + pad + size > out->cap && reserve(pad + size) < 0)
        return FAILED;
    char *p = out->p + out->n;
    if (pad)
        memset(p, 0, pad);
    memcpy(p + pad, src, size);
    out->n += pad + size;
    return 0;
}

/* a primitive value; FALLBACK (exception cleared) if it is not one struct would pack the same way */
/* An integer of the given kind into b, as struct packs it; -1 (nothing written) if x is out of its range or
 * the kind is not an integer one. */
static inline int pack_int(long kind, long long x, unsigned char *b) {
    switch (kind) {
    case K_I8: if (x < -128 || x > 127) return -1; { signed char c = (signed char)x; memcpy(b, &c, 1); } return 0;
    case K_U8: if (x < 0 || x > 255) return -1; b[0] = (unsigned char)x; return 0;
    case K_I16: if (x < -32768 || x > 32767) return -1; { short h = (short)x; memcpy(b, &h, 2); } return 0;
    case K_U16: if (x < 0 || x > 65535) return -1; { unsigned short h = (unsigned short)x; memcpy(b, &h, 2); } return 0;
    case K_I32: if (x < INT32_MIN || x > INT32_MAX) return -1; { int i = (int)x; memcpy(b, &i, 4); } return 0;
    case K_U32: if (x < 0 || x > UINT32_MAX) return -1; { unsigned int i = (unsigned int)x; memcpy(b, &i, 4); } return 0;
    case K_I64: memcpy(b, &x, 8); return 0;
    case K_U64: if (x < 0) return -1; { unsigned long long u = (unsigned long long)x; memcpy(b, &u, 8); } return 0;
    default: return -1;
    }
}

#define NOT_FAST 2                 /* put_number: not one of the common cases (nothing written) */

/* The common cases of a primitive value (a message's numbers are Python floats, bools and small ints): each
 * is written straight into the buffer, with the bytes of the general path of `put_primitive`; NOT_FAST for
 * anything else. A float32 is the cast that PyFloat_Pack4 makes; NaN (whose bit pattern that function treats
 * with care) and overflow take the general path. Inline, and it runs no Python code, so that `encode_program`
 * can call it on the field it reads without taking a reference of its own. */
static inline int put_number(long kind, PyObject *v) {
    if (PyFloat_CheckExact(v)) {
        double d = PyFloat_AS_DOUBLE(v);
        if (kind == K_F64)
            return put_aligned(&d, 8);
        if (kind == K_F32 && !isnan(d)) {
            float f = (float)d;
            if (!isinf(f) || isinf(d))
                return put_aligned(&f, 4);
        }
    } else if (kind == K_BOOL && (v == Py_True || v == Py_False)) {
        unsigned char b = v == Py_True;
        return put_aligned(&b, 1);
    } else if (PyLong_CheckExact(v) && kind != K_BOOL && kind < K_F32) {
        long long x;
#if PY_VERSION_HEX >= 0x030C0000
        if (!PyUnstable_Long_IsCompact((PyLongObject *)v))
            return NOT_FAST;
        x = (long long)PyUnstable_Long_CompactValue((PyLongObject *)v);
#else
        Py_ssize_t digits = Py_SIZE(v);                /* an int of one digit (30 bits) at most */
        if (digits < -1 || digits > 1)
            return NOT_FAST;
        x = digits * (long long)((PyLongObject *)v)->ob_digit[0];
#endif
        unsigned char b[8];
        if (pack_int(kind, x, b) < 0)                  /* in range: written as struct packs it; else below */
            return NOT_FAST;
        return put_aligned(b, size_of(kind));
    }
    return NOT_FAST;
}

static int put_primitive(long kind, PyObject *v) {
    int fast = put_number(kind, v);
    if (fast != NOT_FAST)
        return fast;
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
    if (pack_int(kind, x, out) < 0)       /* (K_U64 was written above) */
        return FALLBACK;
    return put(out, size);
fallback:
    PyErr_Clear();
    return FALLBACK;
}

static inline int put_u32(Py_ssize_t n) {
    if (n > (Py_ssize_t)UINT32_MAX)
        return FALLBACK;
    unsigned int u = (unsigned int)n;
    return put_aligned(&u, 4);                         /* (align and put in one: every sequence's length) */
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
    memcpy(out->p + out->n, s, len);
    out->p[out->n + len] = 0;
    out->n += len + 1;
    return 0;
}

int format_fits(long kind, const char *fmt, Py_ssize_t itemsize) {
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


static int put_items(PyObject *v, Py_ssize_t fixed, Program *program, int align_first);

/* the dtype of the wire's element type (`ref`, from `setup`): that very object, or one of the same class with
 * the same scalar type and byte order (a machine-native one: this module only runs on little-endian ones) */
static int same_dtype(PyObject *descr, PyObject *ref) {
    if (descr == ref)
        return 1;
    if (ref == NULL || Py_TYPE(descr) != Py_TYPE(ref))
        return 0;
    const DescrHead *d = (const DescrHead *)descr, *r = (const DescrHead *)ref;
    return d->typeobj == r->typeobj && d->byteorder == r->byteorder && d->kind == r->kind && d->type == r->type;
}

static int put_primitives(PyObject *v, long kind, Py_ssize_t fixed) {
    if (Py_TYPE(v) == ndarray && kind < 16) {
        ArrayHead *a = (ArrayHead *)v;
        if (a->nd == 1 && (a->flags & c_contiguous) && same_dtype(a->descr, dtypes[kind])) {
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

static long phase_now(void) {
    return (long)((out->n - body) & 7);
}

/* a sequence (or fixed array) of strings (program NULL) or of messages (align: their first field's) */
static int put_items(PyObject *v, Py_ssize_t fixed, Program *program, int align_first) {
    long phase = phase_now();
    Py_ssize_t start = out->n;
    const char *kept;
    Py_ssize_t size;
    if (memo_on()) {
        int hit = memo_find(v, phase, &kept, &size);
        if (hit)
            return hit < 0 ? FAILED : put(kept, size);
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
        if (align_first > 0 && memo_on()) {            /* this message encoded on its own before? */
            Py_ssize_t pad = (body - out->n) & (align_first - 1);
            if (((out->n - body + pad) & 7) == 0) {
                int hit = memo_find(items[i], 0, &kept, &size);
                if (hit < 0) {
                    r = FAILED;
                    break;
                }
                if (hit) {
                    if ((r = align(align_first)) == 0)
                        r = put(kept, size);
                    continue;
                }
            }
        }
        r = encode_program(program, items[i]);
    }
    Py_DECREF(seq);
    if (r == 0 && n > 0 && memo_on())
        r = memo_keep(v, phase, start);
    return r;
}

int encode_program(Program *program, PyObject *msg) {
    PyTypeObject *tp = Py_TYPE(msg);
    if (tp != program->type || tp->tp_version_tag != program->version)
        learn(program, tp);
    int slotted = program->slotted;
    for (Py_ssize_t i = 0; i < program->count; i++) {
        const Op *op = &program->ops[i];
        PyObject *v;
        if (slotted) {
            v = *(PyObject **)((char *)msg + op->offset);
            if (v == NULL)                                     /* a field never set */
                return FALLBACK;
            if (op->kind < K_STR) {                            /* a number: the common cases without a reference */
                int r = put_number(op->kind, v);
                if (r != NOT_FAST) {
                    if (r)
                        return r;
                    continue;
                }
            }
            Py_INCREF(v);
        } else if ((v = PyObject_GetAttr(msg, op->name)) == NULL) {
            PyErr_Clear();
            return FALLBACK;
        }
        int r;
        if (op->kind < K_STR)
            r = put_primitive(op->kind, v);
        else if (op->kind == K_STR)
            r = put_string(v);
        else if (op->kind == K_MSG)
            r = encode_program(op->sub, v);
        else if (op->kind == K_PSEQ)
            r = put_primitives(v, op->elem, op->fixed);
        else if (op->kind == K_SSEQ)
            r = put_items(v, op->fixed, NULL, 0);
        else
            r = put_items(v, op->fixed, op->sub, op->elem);
        Py_DECREF(v);
        if (r)
            return r;
    }
    return 0;
}

State enter(Buf *to, Py_ssize_t at, PyObject *now, PyObject *old, MemoTable *tnow, MemoTable *told) {
    State saved = {out, body, memo_now, memo_old, table_now, table_old};
    out = to;
    body = at;
    memo_now = now;
    memo_old = old;
    table_now = tnow;
    table_old = told;
    return saved;
}

void leave(State saved) {
    out = saved.out;
    body = saved.body;
    memo_now = saved.memo_now;
    memo_old = saved.memo_old;
    table_now = saved.table_now;
    table_old = saved.table_old;
}

/* encode(program, msg[, memo, keep, out]): memo = (this period's dict, the last one's dict) or None; keep:
 * remember this message's body (it may be met again inside a sequence); out: a bytearray to append the
 * bytes to (then the number of bytes is returned) instead of returning them as bytes */
PyObject *encode(PyObject *self, PyObject *args) {
    PyObject *program, *msg, *memo = Py_None, *target = Py_None;
    int keep = 0;
    if (!PyArg_ParseTuple(args, "OO|OpO", &program, &msg, &memo, &keep, &target))
        return NULL;
    Program *compiled = program_of(program);
    if (compiled == NULL)
        return NULL;
    if (target != Py_None && !PyByteArray_Check(target)) {
        PyErr_SetString(PyExc_TypeError, "out: a bytearray or None");
        return NULL;
    }
    PyObject *now = NULL, *old = NULL;
    if (memo != Py_None) {
        if (!PyTuple_Check(memo) || PyTuple_GET_SIZE(memo) != 2 || !PyDict_Check(PyTuple_GET_ITEM(memo, 0))
            || !PyDict_Check(PyTuple_GET_ITEM(memo, 1))) {
            PyErr_SetString(PyExc_TypeError, "memo: (dict, dict) or None");
            return NULL;
        }
        now = PyTuple_GET_ITEM(memo, 0);
        old = PyTuple_GET_ITEM(memo, 1);
    }
    if (scratch.p == NULL && (scratch.p = PyMem_Malloc(4096)) != NULL)
        scratch.cap = 4096;
    if (scratch.p == NULL)
        return PyErr_NoMemory();
    Py_ssize_t mark = scratch.n;           /* not 0 if this call runs inside another one's field conversion */
    State saved = enter(&scratch, mark + 4, now, old, NULL, NULL);
    int r = put("\x00\x01\x00\x00", 4);
    if (r == 0)
        r = encode_program(compiled, msg);
    if (r == 0 && keep && memo_on())
        r = memo_keep(msg, 0, mark + 4);
    leave(saved);
    PyObject *result = NULL;
    if (r == FALLBACK)
        result = Py_NewRef(Py_None);
    else if (r == 0 && target == Py_None)
        result = PyBytes_FromStringAndSize(scratch.p + mark, scratch.n - mark);
    else if (r == 0) {
        Py_ssize_t at = PyByteArray_GET_SIZE(target), size = scratch.n - mark;
        if (PyByteArray_Resize(target, at + size) == 0) {
            memcpy(PyByteArray_AS_STRING(target) + at, scratch.p + mark, size);
            result = PyLong_FromSsize_t(size);
        }
    }
    scratch.n = mark;
    return result;
}
