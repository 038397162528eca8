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
 * What this unit reads by offset, and who declares it:
 * - numpy's array and dtype objects: `simatch.msgs.cdr` declares the fields' offsets and checks them on an
 *   array; `setup` checks them against `ArrayHead` and `DescrHead` below.
 * - a message's fields: the slots of its class, found through the class's member descriptors (`slot_offset`,
 *   guarded by the class's version tag; the classes are made slotted by `simatch.msgs._with_slots`).
 */
#include "_cdr_accel.h"

static Buf scratch = {NULL, 0, 0, 0}; /* `encode`'s output, reused between calls: the GIL is held throughout */
Buf *out = &scratch;
Py_ssize_t body = 4;

/* numpy arrays without numpy's headers: the leading fields of numpy's array object, whose layout is part of
 * numpy's ABI (extensions built against old headers run with new numpy). The layout is declared, and checked
 * against numpy, by `simatch.msgs.cdr` (`NUMPY_ARRAY`, `NUMPY_DTYPE`); `setup` receives those offsets and
 * refuses to start if they are not those of the structs below. */
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

/* ... and the leading fields of a dtype, the same in numpy 1 and 2: an array made elsewhere (numba, a view of
 * a structured array) may have a dtype object of its own that equals the shared one */
typedef struct {
    PyObject_HEAD
    PyTypeObject *typeobj;         /* the scalar type: numpy.float64, ... */
    char kind, type, byteorder;
} DescrHead;

static int c_contiguous = 0;      /* numpy's flag of a C-contiguous array (`setup`) */
static PyTypeObject *ndarray = NULL;
static PyObject *dtypes[16];       /* by kind: the dtype object of contiguous arrays taken as they are */


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


static int size_of(long kind) {
    switch (kind) {
    case K_BOOL: case K_I8: case K_U8: return 1;
    case K_I16: case K_U16: return 2;
    case K_I32: case K_U32: case K_F32: return 4;
    default: return 8;
    }
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

/* The memo (see simatch.msgs.cdr): this period's and the last one's, id(object) -> (object, phase, bytes): a
 * list met again at the same phase (offset modulo 8), or a message encoded on its own (phase 0, its body) met
 * again inside a sequence. Two forms: `encode` takes two dicts (id -> (object, phase, bytes)); the message log
 * holds two tables of its own (`MemoTable`: no Python object per entry, the bytes in one buffer per period), so
 * that remembering an entry makes no keys, tuples or bytes objects. NULL (both forms): no memo. */

static PyObject *memo_now = NULL, *memo_old = NULL;
static MemoTable *table_now = NULL, *table_old = NULL;

static int memo_on(void) {
    return memo_now != NULL || table_now != NULL;
}

static Py_ssize_t table_slot(const MemoTable *t, PyObject *obj) {
    size_t h = (size_t)obj >> 4;
    h ^= h >> 9;
    Py_ssize_t mask = t->cap - 1, i = (Py_ssize_t)(h & (size_t)mask);
    while (t->entries[i].obj != NULL && t->entries[i].obj != obj)
        i = (i + 1) & mask;
    return i;
}

static const MemoEntry *table_find(const MemoTable *t, PyObject *obj) {
    if (t == NULL || t->cap == 0)
        return NULL;
    const MemoEntry *e = &t->entries[table_slot(t, obj)];
    return e->obj == obj ? e : NULL;
}

static int table_grow(MemoTable *t) {
    Py_ssize_t cap = t->cap ? t->cap * 2 : 64;
    MemoEntry *fresh = PyMem_Calloc(cap, sizeof(MemoEntry)), *old = t->entries;
    if (fresh == NULL) {
        PyErr_NoMemory();
        return FAILED;
    }
    Py_ssize_t old_cap = t->cap;
    t->entries = fresh;
    t->cap = cap;
    for (Py_ssize_t i = 0; i < old_cap; i++)
        if (old[i].obj != NULL)
            t->entries[table_slot(t, old[i].obj)] = old[i];
    PyMem_Free(old);
    return 0;
}

/* the entries' objects, for the garbage collector */
int table_traverse(const MemoTable *t, visitproc visit, void *arg) {
    for (Py_ssize_t i = 0; i < t->cap; i++)
        Py_VISIT(t->entries[i].obj);
    return 0;
}

/* empty the table (its memory is kept for the next period) */
void table_clear(MemoTable *t) {
    if (t->used) {
        for (Py_ssize_t i = 0; i < t->cap; i++) {
            PyObject *obj = t->entries[i].obj;
            t->entries[i].obj = NULL;
            Py_XDECREF(obj);
        }
    }
    t->used = 0;
    t->bytes.n = 0;
}

void table_free(MemoTable *t) {
    table_clear(t);
    PyMem_Free(t->entries);
    PyMem_Free(t->bytes.p);
    memset(t, 0, sizeof *t);
}

/* the bytes kept for `obj` at `phase` (1; *p and *size set), none (0), or an error (-1, its exception set) */
static int memo_find(PyObject *obj, long phase, const char **p, Py_ssize_t *size) {
    if (table_now != NULL) {
        const MemoTable *t = table_now;
        const MemoEntry *e = table_find(t, obj);
        if (e == NULL)
            e = table_find(t = table_old, obj);
        if (e == NULL || e->phase != phase)
            return 0;
        *p = t->bytes.p + e->at;
        *size = e->size;
        return 1;
    }
    PyObject *key = PyLong_FromVoidPtr(obj);
    if (key == NULL)
        return -1;
    PyObject *hit = PyDict_GetItemWithError(memo_now, key);
    if (hit == NULL && !PyErr_Occurred() && memo_old != NULL)
        hit = PyDict_GetItemWithError(memo_old, key);
    Py_DECREF(key);
    if (hit == NULL)
        return PyErr_Occurred() ? -1 : 0;
    if (!PyTuple_Check(hit) || PyTuple_GET_SIZE(hit) != 3 || PyTuple_GET_ITEM(hit, 0) != obj
        || PyLong_AsLong(PyTuple_GET_ITEM(hit, 1)) != phase || !PyBytes_Check(PyTuple_GET_ITEM(hit, 2))) {
        PyErr_Clear();
        return 0;
    }
    *p = PyBytes_AS_STRING(PyTuple_GET_ITEM(hit, 2));
    *size = PyBytes_GET_SIZE(PyTuple_GET_ITEM(hit, 2));
    return 1;
}

/* remember the bytes written since `start` as those of `obj` at `phase` */
int memo_keep(PyObject *obj, long phase, Py_ssize_t start) {
    if (table_now != NULL) {
        MemoTable *t = table_now;
        if ((t->used + 1) * 2 > t->cap && table_grow(t) < 0)
            return FAILED;
        Py_ssize_t size = out->n - start;
        if (t->bytes.n + size > t->bytes.cap) {         /* grow the period's bytes (`reserve` writes `out`) */
            Py_ssize_t cap = t->bytes.cap ? t->bytes.cap : 16384;
            while (cap < t->bytes.n + size)
                cap *= 2;
            char *q = PyMem_Realloc(t->bytes.p, cap);
            if (q == NULL) {
                PyErr_NoMemory();
                return FAILED;
            }
            t->bytes.p = q;
            t->bytes.cap = cap;
        }
        memcpy(t->bytes.p + t->bytes.n, out->p + start, size);
        MemoEntry *e = &t->entries[table_slot(t, obj)];
        if (e->obj == NULL) {
            e->obj = Py_NewRef(obj);
            t->used++;
        }
        e->phase = phase;
        e->at = t->bytes.n;
        e->size = size;
        t->bytes.n += size;
        return 0;
    }
    PyObject *key = PyLong_FromVoidPtr(obj);
    PyObject *data = PyBytes_FromStringAndSize(out->p + start, out->n - start);
    PyObject *at = PyLong_FromLong(phase);                 /* a small int: cached, no allocation */
    PyObject *entry = (key && data && at) ? PyTuple_Pack(3, obj, at, data) : NULL;
    Py_XDECREF(at);
    int r = entry ? PyDict_SetItem(memo_now, key, entry) : -1;
    Py_XDECREF(key);
    Py_XDECREF(data);
    Py_XDECREF(entry);
    return r < 0 ? FAILED : 0;
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

/* where instances of `tp` hold the attribute `name` (an offset > 0), or 0 if not in a slot that can be read there:
 * the generic attribute lookup finds it as a member descriptor of an object that raises AttributeError when
 * unset. The offset holds while `tp`'s version tag is the same. */
static Py_ssize_t slot_offset(PyTypeObject *tp, PyObject *name) {
    if (tp->tp_getattro != PyObject_GenericGetAttr)
        return 0;
    PyObject *d = _PyType_Lookup(tp, name);                    /* borrowed */
    if (d == NULL || !Py_IS_TYPE(d, &PyMemberDescr_Type))
        return 0;
    PyMemberDef *member = ((PyMemberDescrObject *)d)->d_member;
    if (member->type != T_OBJECT_EX || (member->flags & READ_RESTRICTED) || member->offset <= 0)
        return 0;
    return member->offset;
}

/* how instances of `tp` hold the program's fields: slotted if every field is in a slot (`slot_offset`) */
static void learn(Program *program, PyTypeObject *tp) {
    Py_XSETREF(program->type, (PyTypeObject *)Py_NewRef(tp));
    program->slotted = 0;
    for (Py_ssize_t i = 0; i < program->count; i++) {
        Op *op = &program->ops[i];
        if ((op->offset = slot_offset(tp, op->name)) == 0)
            goto done;
    }
    program->slotted = PyType_HasFeature(tp, Py_TPFLAGS_VALID_VERSION_TAG);
done:
    program->version = tp->tp_version_tag;                      /* the look-ups above assign one */
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

static void free_program(Program *program) {
    if (program == NULL)
        return;
    for (Py_ssize_t i = 0; i < program->count; i++) {
        Py_XDECREF(program->ops[i].name);
        free_program(program->ops[i].sub);
    }
    Py_XDECREF(program->type);
    PyMem_Free(program);
}

static int bad_program(void) {
    PyErr_SetString(PyExc_ValueError, "malformed encoder program");
    return -1;
}

/* one op of a program tuple: (kind, attribute, argument), see the top of this file */
static int compile_op(PyObject *item, Op *op, Program *(*compile)(PyObject *)) {
    if (!PyTuple_Check(item) || PyTuple_GET_SIZE(item) != 3 || !PyUnicode_Check(PyTuple_GET_ITEM(item, 1)))
        return bad_program();
    op->kind = (int)PyLong_AsLong(PyTuple_GET_ITEM(item, 0));
    op->name = Py_NewRef(PyTuple_GET_ITEM(item, 1));
    PyUnicode_InternInPlace(&op->name);
    PyObject *arg = PyTuple_GET_ITEM(item, 2);
    if (op->kind == -1 && PyErr_Occurred())
        return -1;
    if ((op->kind >= K_BOOL && op->kind <= K_F64) || op->kind == K_STR)
        return 0;
    if (op->kind == K_MSG)
        return (op->sub = compile(arg)) == NULL ? -1 : 0;
    if (op->kind == K_SSEQ) {
        op->fixed = PyLong_AsSsize_t(arg);
        return (op->fixed == -1 && PyErr_Occurred()) ? -1 : 0;
    }
    if ((op->kind != K_PSEQ && op->kind != K_MSEQ) || !PyTuple_Check(arg) || PyTuple_GET_SIZE(arg) < 2)
        return bad_program();
    op->fixed = PyLong_AsSsize_t(PyTuple_GET_ITEM(arg, 1));
    if (op->fixed == -1 && PyErr_Occurred())
        return -1;
    if (op->kind == K_PSEQ) {
        op->elem = (int)PyLong_AsLong(PyTuple_GET_ITEM(arg, 0));
        return (op->elem >= K_BOOL && op->elem <= K_F64) ? 0 : bad_program();
    }
    if (PyTuple_GET_SIZE(arg) != 3)
        return bad_program();
    op->elem = (int)PyLong_AsLong(PyTuple_GET_ITEM(arg, 2));
    if (op->elem != 1 && op->elem != 2 && op->elem != 4 && op->elem != 8)
        return bad_program();
    return (op->sub = compile(PyTuple_GET_ITEM(arg, 0))) == NULL ? -1 : 0;
}

/* the ops of a program tuple; `compile` compiles the programs of nested messages */
static Program *compile_ops(PyObject *ops, Program *(*compile)(PyObject *)) {
    if (!PyTuple_Check(ops)) {
        bad_program();
        return NULL;
    }
    Py_ssize_t count = PyTuple_GET_SIZE(ops);
    Program *p = PyMem_Calloc(1, sizeof(Program) + count * sizeof(Op));
    if (p == NULL) {
        PyErr_NoMemory();
        return NULL;
    }
    p->count = count;
    for (Py_ssize_t i = 0; i < count; i++) {
        if (compile_op(PyTuple_GET_ITEM(ops, i), &p->ops[i], compile) < 0) {
            free_program(p);
            return NULL;
        }
    }
    return p;
}

static Program *compile_tuple(PyObject *program) {
    return compile_ops(program, compile_tuple);
}

#define PROGRAM_CAPSULE "simatch.msgs._cdr_accel.program"

static void program_capsule_free(PyObject *capsule) {
    free_program(PyCapsule_GetPointer(capsule, PROGRAM_CAPSULE));
}

/* a compiled program (NULL: an exception is set) as the capsule Python holds */
static PyObject *capsule_of(Program *p) {
    if (p == NULL)
        return NULL;
    PyObject *capsule = PyCapsule_New(p, PROGRAM_CAPSULE, program_capsule_free);
    if (capsule == NULL)
        free_program(p);
    return capsule;
}

/* compile(program tuple) -> the compiled program (a capsule) that `encode` and `Log` take */
static PyObject *compile(PyObject *self, PyObject *program) {
    return capsule_of(compile_tuple(program));
}

Program *program_of(PyObject *capsule) {
    return PyCapsule_GetPointer(capsule, PROGRAM_CAPSULE);    /* NULL, with an exception, if it is not one */
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
static PyObject *encode(PyObject *self, PyObject *args) {
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

/* --- Decoding ------------------------------------------------------------------------------------------------
 *
 * `decode(compiled decoder program, payload)`: the message a little-endian CDR payload (header included) holds,
 * read as rosbags' own deserializer reads it (the tests and the fuzzing targets hold the two to the same message
 * and the same verdict on every input): primitive sequences become read-only numpy arrays viewing the payload,
 * a string must end with its NUL and be UTF-8, every length is checked against what is left before it is used,
 * and whatever does not fit raises `MessageError` (from `setup_decoding`), never anything else. The program is
 * the encoder's with each message's class: (class, ((kind, field, argument), ...)), a nested message's
 * argument being its own (class, ops).
 *
 * Messages are made as the classes' own __init__ makes them: a slotted class without __post_init__ (every
 * message class of simatch.msgs) is allocated and its slots filled directly; any other class is called with
 * the fields in order. */

static PyObject *message_error = NULL;     /* simatch.msgs.MessageError */

typedef struct {
    const unsigned char *p;        /* the body: after the 4-byte header (alignment counts from here) */
    Py_ssize_t n;                  /* its length */
    Py_ssize_t pos;
    PyObject *data;                /* the whole payload (bytes): the base of the arrays */
} In;

static PyObject *malformed(const char *fmt, ...) {
    va_list va;
    va_start(va, fmt);
    PyObject *text = PyUnicode_FromFormatV(fmt, va);
    va_end(va);
    if (text != NULL) {
        PyErr_SetObject(message_error, text);
        Py_DECREF(text);
    }
    return NULL;
}

/* the position of a field of `size` bytes at the current one (aligned), or -1 (MessageError) if it does not fit */
static Py_ssize_t take(In *in, int size) {
    Py_ssize_t at = in->pos + ((-in->pos) & (size - 1));
    if (at + size > in->n) {
        malformed("a field runs past the end (byte %zd)", at);
        return -1;
    }
    in->pos = at + size;
    return at;
}

static PyObject *read_primitive(In *in, int kind) {
    Py_ssize_t at = take(in, size_of(kind));
    if (at < 0)
        return NULL;
    const unsigned char *q = in->p + at;
    switch (kind) {
    case K_BOOL: return PyBool_FromLong(q[0] != 0);
    case K_I8: return PyLong_FromLong((signed char)q[0]);
    case K_U8: return PyLong_FromLong(q[0]);
    case K_I16: { int16_t v; memcpy(&v, q, 2); return PyLong_FromLong(v); }
    case K_U16: { uint16_t v; memcpy(&v, q, 2); return PyLong_FromLong(v); }
    case K_I32: { int32_t v; memcpy(&v, q, 4); return PyLong_FromLong(v); }
    case K_U32: { uint32_t v; memcpy(&v, q, 4); return PyLong_FromUnsignedLong(v); }
    case K_I64: { long long v; memcpy(&v, q, 8); return PyLong_FromLongLong(v); }
    case K_U64: { unsigned long long v; memcpy(&v, q, 8); return PyLong_FromUnsignedLongLong(v); }
    case K_F32: { float v; memcpy(&v, q, 4); return PyFloat_FromDouble(v); }
    default: { double v; memcpy(&v, q, 8); return PyFloat_FromDouble(v); }
    }
}

/* a u32 count (of elements, or of a string's bytes): its position, or -1 (MessageError) */
static Py_ssize_t read_count(In *in, Py_ssize_t *n) {
    Py_ssize_t at = take(in, 4);
    if (at >= 0) {
        uint32_t v;
        memcpy(&v, in->p + at, 4);
        *n = (Py_ssize_t)v;
    }
    return at;
}

static PyObject *read_string(In *in) {
    Py_ssize_t k, at = read_count(in, &k);
    if (at < 0)
        return NULL;
    if (k < 1 || at + 4 + k > in->n || in->p[at + 3 + k] != 0)
        return malformed("bad string at byte %zd", at);
    in->pos = at + 4 + k;
    PyObject *s = PyUnicode_DecodeUTF8((const char *)in->p + at + 4, k - 1, NULL);
    if (s == NULL) {
        PyErr_Clear();
        return malformed("a string at byte %zd is not UTF-8", at);
    }
    return s;
}

/* one empty read-only array per kind, shared by every empty sequence decoded (nothing in it to change) */
static PyObject *empty_arrays[16];

/* read-only numpy array of `n` elements viewing the payload (as rosbags makes it) */
static PyObject *read_array(In *in, const Op *op, Py_ssize_t n) {
    int size = size_of(op->elem);
    if (n)
        in->pos += (-in->pos) & (size - 1);
    if (in->pos > in->n || n > (in->n - in->pos) / size)
        return malformed("%U: %zd elements do not fit", op->name, n);
    if (n == 0 && empty_arrays[op->elem] != NULL)
        return Py_NewRef(empty_arrays[op->elem]);
    PyObject *shape = Py_BuildValue("(n)", n);
    PyObject *args = shape == NULL ? NULL : n ? Py_BuildValue("(OOOn)", shape, dtypes[op->elem], in->data, in->pos + 4)
                                              : Py_BuildValue("(OOy#)", shape, dtypes[op->elem], "", (Py_ssize_t)0);
    Py_XDECREF(shape);
    if (args == NULL)
        return NULL;
    PyObject *array = PyObject_Call((PyObject *)ndarray, args, NULL);
    Py_DECREF(args);
    in->pos += n * size;
    if (n == 0 && array != NULL)
        empty_arrays[op->elem] = Py_NewRef(array);      /* (over an empty bytes object, not the payload) */
    return array;
}

static PyObject *decode_message(In *in, const Program *program);

static PyObject *read_items(In *in, const Op *op, Py_ssize_t n) {
    if (op->sub == NULL ? n > (in->n - in->pos) / 5 : n > in->n - in->pos)
        return malformed(op->sub == NULL ? "%U: %zd strings do not fit" : "%U: %zd messages do not fit",
                         op->name, n);
    PyObject *list = PyList_New(n);
    if (list == NULL)
        return NULL;
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *item = op->sub == NULL ? read_string(in) : decode_message(in, op->sub);
        if (item == NULL) {
            Py_DECREF(list);
            return NULL;
        }
        PyList_SET_ITEM(list, i, item);
    }
    return list;
}

static PyObject *read_field(In *in, const Op *op) {
    if (op->kind < K_STR)
        return read_primitive(in, op->kind);
    if (op->kind == K_STR)
        return read_string(in);
    if (op->kind == K_MSG)
        return decode_message(in, op->sub);
    Py_ssize_t n = op->fixed;
    if (n < 0 && read_count(in, &n) < 0)
        return NULL;
    return op->kind == K_PSEQ ? read_array(in, op, n) : read_items(in, op, n);
}

static PyObject *decode_message(In *in, const Program *program) {
    PyTypeObject *cls = program->type;
    int direct = program->direct;
    /* the message itself (its slots filled below), or the arguments to call its class with */
    PyObject *made = direct ? cls->tp_alloc(cls, 0) : PyTuple_New(program->count);
    if (made == NULL)
        return NULL;
    for (Py_ssize_t i = 0; i < program->count; i++) {
        PyObject *v = read_field(in, &program->ops[i]);
        if (v == NULL) {
            Py_DECREF(made);
            return NULL;
        }
        if (direct)
            *(PyObject **)((char *)made + program->ops[i].offset) = v;
        else
            PyTuple_SET_ITEM(made, i, v);
    }
    if (direct)
        return made;
    PyObject *msg = PyObject_Call((PyObject *)cls, made, NULL);
    Py_DECREF(made);
    return msg;
}

/* (class, ops): the ops as the encoder compiles them, the class learnt as the encoder learns a message's */
static Program *compile_decoder_tuple(PyObject *pair) {
    if (!PyTuple_Check(pair) || PyTuple_GET_SIZE(pair) != 2 || !PyType_Check(PyTuple_GET_ITEM(pair, 0))) {
        PyErr_SetString(PyExc_ValueError, "malformed decoder program: (class, ops) expected");
        return NULL;
    }
    Program *p = compile_ops(PyTuple_GET_ITEM(pair, 1), compile_decoder_tuple);
    if (p == NULL)
        return NULL;
    PyTypeObject *cls = (PyTypeObject *)PyTuple_GET_ITEM(pair, 0);
    learn(p, cls);
    int post_init = PyObject_HasAttrString((PyObject *)cls, "__post_init__");
    p->direct = p->slotted && !post_init && cls->tp_new == PyBaseObject_Type.tp_new
                && cls->tp_alloc == PyType_GenericAlloc;
    return p;
}

/* compile_decoder((class, ops)) -> the compiled program `decode` takes */
static PyObject *compile_decoder(PyObject *self, PyObject *program) {
    return capsule_of(compile_decoder_tuple(program));
}

/* decode(compiled decoder program, payload: bytes) -> message; MessageError if the payload is not one */
static PyObject *decode(PyObject *self, PyObject *args) {
    PyObject *program, *data;
    if (!PyArg_ParseTuple(args, "OO!", &program, &PyBytes_Type, &data))
        return NULL;
    Program *compiled = program_of(program);
    if (compiled == NULL)
        return NULL;
    if (message_error == NULL || ndarray == NULL || compiled->type == NULL) {
        PyErr_SetString(PyExc_RuntimeError, "decoding is not set up (setup, setup_decoding, compile_decoder)");
        return NULL;
    }
    Py_ssize_t size = PyBytes_GET_SIZE(data);
    if (size < 4)
        return malformed("%zd bytes: no CDR header", size);
    In in = {(const unsigned char *)PyBytes_AS_STRING(data) + 4, size - 4, 0, data};
    PyObject *msg = decode_message(&in, compiled);
    if (msg != NULL && in.pos + 3 < in.n) {
        Py_DECREF(msg);
        return malformed("%zd bytes too many", in.n - in.pos);
    }
    return msg;
}

/* setup_decoding(MessageError): the exception `decode` raises (arrays need `setup` to have succeeded) */
static PyObject *setup_decoding(PyObject *self, PyObject *error) {
    if (!PyType_Check(error) || !PyType_IsSubtype((PyTypeObject *)error, (PyTypeObject *)PyExc_Exception)) {
        PyErr_SetString(PyExc_TypeError, "an exception class expected");
        return NULL;
    }
    Py_INCREF(error);
    Py_XSETREF(message_error, error);
    Py_RETURN_NONE;
}

/* --- Setup and the module ------------------------------------------------------------------------------------ */

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
