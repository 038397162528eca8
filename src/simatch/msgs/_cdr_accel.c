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
 * length or -1) or of messages (argument: (program, length or -1, alignment of its first field)).
 * `compile` turns such a tuple into C structures once (no tuple unpacking or int conversion per field).
 *
 * The same programs, with each message's class, decode payloads (`decode`, below). The module also holds
 * the recorder's message log (`Log`, below), which frames and encodes each message it is given straight into
 * the recording's chunk buffer.
 *
 * Output: XCDR1 little endian with the 4-byte encapsulation header, byte for byte what rosbags writes
 * (checked type by type by tests/msgs/test_cdr.py). Anything this fast path does not take as it is (a
 * primitive sequence that is not a contiguous little-endian buffer of the wire's type, a wrong fixed
 * length, a value of the wrong type) makes it return None without an exception: the caller then uses the
 * pure-Python encoder, which converts what it can and raises the canonical error otherwise.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <string.h>
#include <structmember.h>

enum {
    K_BOOL = 1, K_I8, K_U8, K_I16, K_U16, K_I32, K_U32, K_I64, K_U64, K_F32, K_F64,
    K_STR = 20, K_MSG, K_PSEQ, K_SSEQ, K_MSEQ
};

typedef struct {
    char *p;
    Py_ssize_t n, cap;
    int lent;                      /* p is memory lent by another object (a message log's `into`): never
                                    * reallocated or freed here; growing past cap moves the bytes to memory
                                    * of the Buf's own */
} Buf;

static Buf scratch = {NULL, 0, 0, 0}; /* `encode`'s output, reused between calls: the GIL is held throughout */
static Buf *out = &scratch;         /* where the encoder writes now: `scratch` or a message log's buffer */
static Py_ssize_t body = 4;         /* offset in `out` of the CDR body being written (alignment counts from it) */

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

/* ... and the leading fields of a dtype, the same in numpy 1 and 2: an array made elsewhere (numba, a view of
 * a structured array) may have a dtype object of its own that equals the shared one */
typedef struct {
    PyObject_HEAD
    PyTypeObject *typeobj;         /* the scalar type: numpy.float64, ... */
    char kind, type, byteorder;
} DescrHead;

#define C_CONTIGUOUS 0x0001
static PyTypeObject *ndarray = NULL;
static PyObject *dtypes[16];       /* by kind: the dtype object of contiguous arrays taken as they are */

#define FALLBACK 1                 /* not for the fast path: the caller uses the Python encoder */
#define FAILED -1                  /* a Python exception is set (memory) */

static int grow(Py_ssize_t need) {
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

/* room for `need` more bytes in `out` (the test inline: it is made for every field and record) */
static inline int reserve(Py_ssize_t need) {
    return out->n + need <= out->cap ? 0 : grow(need);
}

/* pad with zeros to a multiple of `a`, counted from the start of the body (after the 4-byte header) */
static inline int align(int a) {
    Py_ssize_t pad = (body - out->n) & (a - 1);       /* a is 1, 2, 4 or 8 */
    if (pad) {
        if (reserve(pad) < 0)
            return FAILED;
        memset(out->p + out->n, 0, pad);
        out->n += pad;
    }
    return 0;
}

static inline int put(const void *src, Py_ssize_t size) {
    if (reserve(size) < 0)
        return FAILED;
    memcpy(out->p + out->n, src, size);
    out->n += size;
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
 * with care) and overflow take the general path. Inline, and it runs no Python code: `encode_program` calls it
 * on the field it reads, without a reference of its own (some 100,000 numbers per simulated second of a
 * recorded match: the call and the reference count were a third of their cost). */
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

/* A program compiled once (`compile`): the same steps as its tuple, as C values. */
typedef struct Program Program;
typedef struct {
    int kind;
    int elem;                      /* K_PSEQ: the element kind; K_MSEQ: the alignment of the first field */
    Py_ssize_t fixed;              /* sequences: the fixed length of an array, or -1 */
    PyObject *name;                /* the attribute (interned) */
    Program *sub;                  /* K_MSG, K_MSEQ: the nested message's program */
    Py_ssize_t offset;             /* where instances of the program's `type` hold this field (slotted) */
} Op;
/* Field reads: the message classes of simatch.msgs have __slots__, so an instance holds each field at a fixed
 * offset. A program learns the offsets from the first message's class (its `type`, kept with the class's
 * version tag, which changes whenever the class is modified) and then reads fields there directly: looking
 * each name up, as PyObject_GetAttr does, was the larger part of encoding a message. Any other class (a
 * dict-based one, a class with a property or __getattribute__ of its own) is read with PyObject_GetAttr. */
struct Program {
    Py_ssize_t count;
    PyTypeObject *type;            /* the class last met (a strong reference), or NULL */
    unsigned int version;          /* its version tag then */
    int slotted;                   /* read its instances' fields at `offset` */
    int direct;                    /* decoding: make instances of `type` by filling their slots (see below) */
    Op ops[];
};

static int encode_program(Program *program, PyObject *msg);
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
        if (a->nd == 1 && (a->flags & C_CONTIGUOUS) && same_dtype(a->descr, dtypes[kind])) {
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
 * holds two tables of its own (`MemoTable`: no Python object per entry, the bytes in one buffer per period),
 * because the dicts' keys, tuples and bytes, made and dropped for a few hundred entries per simulated second,
 * cost more than the encoding they saved. NULL (both forms): no memo. */
typedef struct {
    PyObject *obj;                 /* a strong reference: while it is held, no other object has its id */
    long phase;
    Py_ssize_t at, size;           /* its bytes in the table's `bytes` */
} MemoEntry;

typedef struct {
    MemoEntry *entries;            /* open addressing (linear probing), `cap` a power of two; obj NULL: free */
    Py_ssize_t cap, used;
    Buf bytes;
} MemoTable;

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
static int table_traverse(const MemoTable *t, visitproc visit, void *arg) {
    for (Py_ssize_t i = 0; i < t->cap; i++)
        Py_VISIT(t->entries[i].obj);
    return 0;
}

/* empty the table (its memory is kept for the next period) */
static void table_clear(MemoTable *t) {
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

static void table_free(MemoTable *t) {
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
static int memo_keep(PyObject *obj, long phase, Py_ssize_t start) {
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

static int encode_program(Program *program, PyObject *msg) {
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

static Program *program_of(PyObject *capsule) {
    return PyCapsule_GetPointer(capsule, PROGRAM_CAPSULE);    /* NULL, with an exception, if it is not one */
}

/* The encoder's globals while one call runs (saved and restored: a field's __float__ may run Python code that
 * encodes too). */
typedef struct {
    Buf *out;
    Py_ssize_t body;
    PyObject *memo_now, *memo_old;
    MemoTable *table_now, *table_old;
} State;

static State enter(Buf *to, Py_ssize_t at, PyObject *now, PyObject *old, MemoTable *tnow, MemoTable *told) {
    State saved = {out, body, memo_now, memo_old, table_now, table_old};
    out = to;
    body = at;
    memo_now = now;
    memo_old = old;
    table_now = tnow;
    table_old = told;
    return saved;
}

static void leave(State saved) {
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
 * read as the generated Python decoders of `simatch.msgs.cdr` read it (they stay the reference, and what runs
 * where this module is not built): primitive sequences become read-only numpy arrays viewing the payload, a
 * string must end with its NUL and be UTF-8, every length is checked against what is left before it is used,
 * and whatever does not fit raises `MessageError` (from `setup_decoding`), never anything else. The program is
 * the encoder's with each message's class: (class, ((kind, field, argument), ...)), a nested message's
 * argument being its own (class, ops). A process of a distributed run decodes the perception, its team's
 * picture and the coach's command at every control tick, on its critical path.
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

/* read-only numpy array of `n` elements viewing the payload, as the Python decoder makes it */
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

/* --- The recorder's message log -----------------------------------------------------------------------------
 *
 * `Log(programs, fallback)` is a bus callback, ``log(topic, msg)``, that appends each message to one buffer as
 * an MCAP Message record: opcode 0x05, record length, channel id, sequence 0, log time and publish time =
 * `log.now` (u64 nanoseconds), then the message's CDR bytes, encoded in place by the programs above. A
 * recording spends most of its time here, some two thousand times per simulated second, so the whole path
 * (topic look-up, clock, record header, encoding, count) is one C call with no Python frame and no object per
 * message. `simatch.record.messagelog.MessageLog` is the same thing in Python, byte for byte; its docstring
 * describes the interface. */

#define RECORD_HEAD 31             /* opcode u8, length u64, channel u16, sequence u32, log time u64, publish u64 */
#define CLOCK_STEP 1               /* add(..., clock=): the message's `step` sets the log time */
#define CLOCK_TICK 2               /* ... and opens a new memo period */

/* A pose template (``log.poses``): every `every` physics steps, a message on `topic` (model states: `name`, and
 * `pose` as rows of x y z qw qx qy qz) also yields a record on `channel`: a copy of `template` (a message
 * encoded once, header included) with a geometry_msgs/Pose (7 float64: position, then quaternion x y z w)
 * written at each slot's offset from its row, snapped to a grid. The recorder's 3D scene is made so: a
 * Python callback and a field-by-field update for each of them cost more than a millisecond per
 * simulated second. Whatever this does not take as it is (no template yet, other names, a pose that is
 * not a contiguous float buffer of enough rows) goes to `fallback(msg)`, which may set a new template. */
typedef struct {
    Py_ssize_t offset;             /* of the Pose in the template */
    Py_ssize_t row;                /* of the model in `pose` */
    double z;                      /* the height drawn, or NaN: the row's (snapped) */
    int turn;                      /* the orientation: the row's turn about z (snapped), else none */
} PoseSlot;

typedef struct {
    PyObject *topic, *fallback;    /* NULL: no pose template */
    long channel;
    long long every;
    PyObject *names, *template;    /* NULL until `pose_template` */
    PoseSlot *slots;
    Py_ssize_t nslots;
    double grid, turn_grid;        /* steps per metre, per unit of a quaternion */
} Poses;

typedef struct {
    PyObject_HEAD
    vectorcallfunc vectorcall;
    Buf buf;
    Py_buffer target;              /* `into`: memory lent for this chunk's records (target.obj NULL: none) */
    PyObject *channels;            /* topic -> Channel (in a capsule) */
    unsigned long generation;      /* changes whenever `channels` does (a `for_topic` callable finds it again) */
    PyObject *programs, *fallback, *on_chunk;
    MemoTable memo[2];             /* the memo's tables: this period's is memo[current] */
    int current;
    long long now, first, last;    /* log time; of the first and last message since the last take (-1: none) */
    long long step_ns, chunk_ns, next_chunk;
    long long step;                /* the physics step of the last clock message (-1: none usable) */
    Py_ssize_t *counts, ncounts;   /* messages since the last take, by channel id */
    Poses poses;
    PyObject *ros_topic;           /* `ros_clock`: after each message on it, ROS 2's clock (NULL: none) */
    long ros_channel;
} Log;

typedef struct {
    long id;
    int keep;                      /* remember each message's body in the memo */
    int clock;                     /* CLOCK_* flags */
    int poses;                     /* the topic of the pose template */
    int ros_clock;                 /* the topic of `ros_clock` */
    Program *program;
    PyObject *owner;               /* the program's capsule */
} Channel;

static PyObject *step_name = NULL, *name_name = NULL, *pose_name = NULL; /* "step", "name", "pose" */

static void channel_free(PyObject *capsule) {
    Channel *ch = PyCapsule_GetPointer(capsule, NULL);
    if (ch != NULL) {
        Py_XDECREF(ch->owner);
        PyMem_Free(ch);
    }
}

static void put_le(char *p, unsigned long long v, int size) {
    for (int i = 0; i < size; i++, v >>= 8)
        p[i] = (char)(v & 0xff);
}

static int count_message(Log *log, long cid) {
    if (cid >= log->ncounts) {
        Py_ssize_t n = cid + 64;
        Py_ssize_t *c = PyMem_Realloc(log->counts, n * sizeof(Py_ssize_t));
        if (c == NULL) {
            PyErr_NoMemory();
            return FAILED;
        }
        memset(c + log->ncounts, 0, (n - log->ncounts) * sizeof(Py_ssize_t));
        log->counts = c;
        log->ncounts = n;
    }
    log->counts[cid]++;
    if (log->first < 0)
        log->first = log->now;
    log->last = log->now;
    return 0;
}

static void put_head(Log *log, Py_ssize_t start, long cid) {
    char *p = log->buf.p + start;
    p[0] = 0x05;
    put_le(p + 1, (unsigned long long)(log->buf.n - start - 9), 8);
    put_le(p + 9, (unsigned long long)cid, 2);
    put_le(p + 11, 0, 4);
    put_le(p + 15, (unsigned long long)log->now, 8);
    put_le(p + 23, (unsigned long long)log->now, 8);
}

static int check_channel(long cid) {
    if (cid < 0 || cid > 65535) {
        if (!PyErr_Occurred())
            PyErr_SetString(PyExc_ValueError, "channel id: 0 to 65535");
        return FAILED;
    }
    return 0;
}

/* the record begun at `start` is written (r == 0): count it and write its header; else take it back */
static int finish_record(Log *log, Py_ssize_t start, long cid, int r) {
    if (r == 0)
        r = count_message(log, cid);
    if (r != 0) {
        log->buf.n = start;
        return r;
    }
    put_head(log, start, cid);
    return 0;
}

/* encode msg as one record; FALLBACK (nothing appended) if the C encoder does not take it */
static int log_message(Log *log, const Channel *ch, PyObject *msg) {
    Py_ssize_t start = log->buf.n;
    State saved = enter(&log->buf, start + RECORD_HEAD + 4, NULL, NULL, &log->memo[log->current],
                        &log->memo[!log->current]);
    int r = reserve(RECORD_HEAD + 4);
    if (r == 0) {
        memcpy(out->p + start + RECORD_HEAD, "\x00\x01\x00\x00", 4);
        out->n = start + RECORD_HEAD + 4;
        r = encode_program(ch->program, msg);
    }
    if (r == 0 && ch->keep)
        r = memo_keep(msg, 0, start + RECORD_HEAD + 4);
    leave(saved);
    return finish_record(log, start, ch->id, r);
}

static int forget(Log *log) {
    log->current = !log->current;                   /* this period's table becomes the last one's */
    table_clear(&log->memo[log->current]);          /* (Python code may run as its objects go) */
    return 0;
}

/* the run is at physics step `step`: messages from now on carry its time; a chunk may end first */
static int advance(Log *log, long long step) {
    if (log->step_ns <= 0 || step > LLONG_MAX / log->step_ns)      /* no timing, or an absurd step: ignored */
        return 0;
    long long now = step * log->step_ns;
    if (now == log->now)
        return 0;
    log->now = now;
    if (log->on_chunk == NULL || log->chunk_ns <= 0 || now < log->next_chunk)
        return 0;
    log->next_chunk = (now / log->chunk_ns + 1) * log->chunk_ns;
    PyObject *r = PyObject_CallNoArgs(log->on_chunk);
    Py_XDECREF(r);
    return r == NULL ? FAILED : 0;
}

/* a clock message: its step (if it has a usable one) sets the time */
static int clock_message(Log *log, const Channel *ch, PyObject *msg) {
    PyObject *v = PyObject_GetAttr(msg, step_name);
    long long step = -1;
    if (v != NULL) {
        PyObject *i = PyNumber_Index(v);      /* an int, or a numpy integer */
        Py_DECREF(v);
        if (i != NULL) {
            step = PyLong_AsLongLong(i);
            Py_DECREF(i);
        }
    }
    log->step = step;
    if (step < 0)
        PyErr_Clear();
    else if (advance(log, step) < 0)
        return FAILED;
    return (ch->clock & CLOCK_TICK) ? forget(log) : 0;
}

static double snap(double v, double grid) {
    return nearbyint(v * grid) / grid;          /* to nearest, ties to even: as numpy's round */
}

/* the pose template's record for a model-states message (see Poses); FALLBACK: for `poses.fallback` */
static int pose_record(Log *log, PyObject *msg) {
    Poses *ps = &log->poses;
    if (ps->template == NULL)
        return FALLBACK;
    PyObject *names = PyObject_GetAttr(msg, name_name);
    int same = names == NULL ? -1 : PyObject_RichCompareBool(names, ps->names, Py_EQ);
    Py_XDECREF(names);
    if (same <= 0) {
        PyErr_Clear();
        return FALLBACK;
    }
    PyObject *pose = PyObject_GetAttr(msg, pose_name);
    Py_buffer view;
    if (pose == NULL || PyObject_GetBuffer(pose, &view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) {
        Py_XDECREF(pose);
        PyErr_Clear();
        return FALLBACK;
    }
    Py_DECREF(pose);
    int f32 = format_fits(K_F32, view.format, view.itemsize), f64 = format_fits(K_F64, view.format, view.itemsize);
    Py_ssize_t values = view.itemsize ? view.len / view.itemsize : 0, rows = values / 7;
    int r = (f32 || f64) && values % 7 == 0 ? 0 : FALLBACK;
    for (Py_ssize_t i = 0; i < ps->nslots && r == 0; i++)
        if (ps->slots[i].row >= rows)
            r = FALLBACK;
    Py_ssize_t start = log->buf.n, size = PyBytes_GET_SIZE(ps->template);
    State saved = enter(&log->buf, 0, NULL, NULL, NULL, NULL);
    if (r == 0 && (r = reserve(RECORD_HEAD + size)) == 0) {
        char *at = out->p + start + RECORD_HEAD;
        memcpy(at, PyBytes_AS_STRING(ps->template), size);
        for (Py_ssize_t i = 0; i < ps->nslots; i++) {
            const PoseSlot *slot = &ps->slots[i];
            double p[7], v[7];
            for (int j = 0; j < 7; j++)
                p[j] = f32 ? (double)((const float *)view.buf)[slot->row * 7 + j]
                           : ((const double *)view.buf)[slot->row * 7 + j];
            v[0] = snap(p[0], ps->grid);
            v[1] = snap(p[1], ps->grid);
            v[2] = isnan(slot->z) ? snap(p[2], ps->grid) : slot->z;
            v[3] = v[4] = 0.0;
            v[5] = slot->turn ? snap(p[6], ps->turn_grid) : 0.0;
            v[6] = slot->turn ? snap(p[3], ps->turn_grid) : 1.0;
            memcpy(at + slot->offset, v, sizeof v);
        }
        out->n = start + RECORD_HEAD + size;
    }
    leave(saved);
    PyBuffer_Release(&view);
    return finish_record(log, start, ps->channel, r);
}

/* after a message on the pose template's topic was logged */
/* the result of a call whose value is not wanted: 0, or FAILED (its exception set) */
static int called(PyObject *result) {
    Py_XDECREF(result);
    return result == NULL ? FAILED : 0;
}

static int poses_after(Log *log, PyObject *msg) {
    Poses *ps = &log->poses;
    if (ps->fallback == NULL || log->step < 0 || log->step % ps->every != 0)
        return 0;
    int r = pose_record(log, msg);
    if (r != FALLBACK)
        return r;
    return called(PyObject_CallOneArg(ps->fallback, msg));
}

/* ROS 2's clock (rosgraph_msgs/msg/Clock: builtin_interfaces/Time, int32 sec and uint32 nanosec) at the log
 * time, on `ros_channel` (what `simatch.record.layout.ros_clock` encodes; a time beyond int32 seconds is not
 * written, by either log) */
static int ros_clock_record(Log *log) {
    long long sec = log->now / 1000000000LL, nsec = log->now % 1000000000LL;
    if (nsec < 0) {                                /* floored, as Python's divmod */
        sec -= 1;
        nsec += 1000000000LL;
    }
    if (sec < INT32_MIN || sec > INT32_MAX)
        return 0;
    Py_ssize_t start = log->buf.n;
    State saved = enter(&log->buf, 0, NULL, NULL, NULL, NULL);
    int r = reserve(RECORD_HEAD + 12);
    if (r == 0) {
        char *p = out->p + start + RECORD_HEAD;
        memcpy(p, "\x00\x01\x00\x00", 4);
        put_le(p + 4, (unsigned long long)(sec & 0xffffffffLL), 4);
        put_le(p + 8, (unsigned long long)nsec, 4);
        out->n = start + RECORD_HEAD + 12;
    }
    leave(saved);
    return finish_record(log, start, log->ros_channel, r);
}

/* ros_clock(topic, channel_id): after each message on topic, a record of ROS 2's clock at the log time */
static PyObject *log_ros_clock(Log *log, PyObject *args) {
    PyObject *topic, *key, *value;
    long cid;
    if (!PyArg_ParseTuple(args, "Ul", &topic, &cid) || check_channel(cid) < 0)
        return NULL;
    Py_XSETREF(log->ros_topic, Py_NewRef(topic));
    log->ros_channel = cid;
    Py_ssize_t pos = 0;
    while (PyDict_Next(log->channels, &pos, &key, &value)) {      /* a channel added before */
        Channel *ch = PyCapsule_GetPointer(value, NULL);
        if (ch == NULL)
            return NULL;
        ch->ros_clock = PyUnicode_Compare(key, topic) == 0;
    }
    Py_RETURN_NONE;
}

/* ``log(topic, msg)`` where `entry` is the topic's channel (a capsule), or NULL for a topic not added */
static PyObject *deliver(Log *log, PyObject *topic, PyObject *entry, PyObject *msg) {
    PyObject *args[2] = {topic, msg};
    if (entry == NULL)             /* a topic not added: the fallback's */
        return PyObject_Vectorcall(log->fallback, args, 2, NULL);
    Py_INCREF(entry);              /* on_chunk and the fallbacks run Python: keep the channel alive meanwhile */
    const Channel *ch = PyCapsule_GetPointer(entry, NULL);
    int r = ch->clock ? clock_message(log, ch, msg) : 0;
    if (r == 0)
        r = log_message(log, ch, msg);
    if (r == FALLBACK)             /* the fallback encodes it, or says what is wrong; its poses follow all the same */
        r = called(PyObject_Vectorcall(log->fallback, args, 2, NULL));
    if (r == 0 && ch->poses)
        r = poses_after(log, msg);
    if (r == 0 && ch->ros_clock)
        r = ros_clock_record(log);
    Py_DECREF(entry);
    if (r != 0)
        return NULL;
    Py_RETURN_NONE;
}

static PyObject *log_vectorcall(PyObject *self, PyObject *const *args, size_t nargsf, PyObject *kwnames) {
    Log *log = (Log *)self;
    if (PyVectorcall_NARGS(nargsf) != 2 || (kwnames != NULL && PyTuple_GET_SIZE(kwnames))) {
        PyErr_SetString(PyExc_TypeError, "log(topic, msg)");
        return NULL;
    }
    PyObject *entry = PyDict_GetItemWithError(log->channels, args[0]);
    if (entry == NULL && PyErr_Occurred())
        return NULL;
    return deliver(log, args[0], entry, args[1]);
}

/* `log.for_topic(topic)`: the log's callback for the messages of one topic, ``f(msg)`` = ``log(topic, msg)``. The
 * in-process bus calls such a callable, when a wildcard subscriber offers one, instead of a partial of the
 * subscriber (`simatch.bus.inproc`): no partial's call and no look-up of the topic per message, the channel is
 * found once (and again after the log's channels change). */
typedef struct {
    PyObject_HEAD
    vectorcallfunc vectorcall;
    Log *log;
    PyObject *topic;
    PyObject *entry;               /* the topic's channel as of `generation`, or NULL (none yet: looked up again) */
    unsigned long generation;
} LogTopic;

static PyObject *log_topic_vectorcall(PyObject *self, PyObject *const *args, size_t nargsf, PyObject *kwnames) {
    LogTopic *lt = (LogTopic *)self;
    if (PyVectorcall_NARGS(nargsf) != 1 || (kwnames != NULL && PyTuple_GET_SIZE(kwnames))) {
        PyErr_SetString(PyExc_TypeError, "for_topic(topic)(msg)");
        return NULL;
    }
    Log *log = lt->log;
    if (log == NULL) {             /* (cleared by the garbage collector) */
        PyErr_SetString(PyExc_ValueError, "the log of this callable is gone");
        return NULL;
    }
    if (lt->entry == NULL || lt->generation != log->generation) {
        PyObject *entry = PyDict_GetItemWithError(log->channels, lt->topic);
        if (entry == NULL && PyErr_Occurred())
            return NULL;
        Py_XSETREF(lt->entry, Py_XNewRef(entry));
        lt->generation = log->generation;
    }
    return deliver(log, lt->topic, lt->entry, args[0]);
}

static int log_topic_traverse(LogTopic *self, visitproc visit, void *arg) {
    Py_VISIT(self->log);
    Py_VISIT(self->topic);
    Py_VISIT(self->entry);
    return 0;
}

static int log_topic_clear(LogTopic *self) {
    Py_CLEAR(self->log);
    Py_CLEAR(self->topic);
    Py_CLEAR(self->entry);
    return 0;
}

static void log_topic_dealloc(LogTopic *self) {
    PyObject_GC_UnTrack(self);
    log_topic_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyTypeObject LogTopicType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "simatch.msgs._cdr_accel.LogTopic",
    .tp_doc = "log.for_topic(topic): f(msg) logs msg as log(topic, msg) does",
    .tp_basicsize = sizeof(LogTopic),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_dealloc = (destructor)log_topic_dealloc,
    .tp_traverse = (traverseproc)log_topic_traverse,
    .tp_clear = (inquiry)log_topic_clear,
    .tp_call = PyVectorcall_Call,
    .tp_vectorcall_offset = offsetof(LogTopic, vectorcall),
};

static PyObject *log_for_topic(Log *log, PyObject *topic) {
    if (!PyUnicode_Check(topic)) {
        PyErr_SetString(PyExc_TypeError, "for_topic(topic): a str");
        return NULL;
    }
    LogTopic *lt = PyObject_GC_New(LogTopic, &LogTopicType);
    if (lt == NULL)
        return NULL;
    lt->vectorcall = log_topic_vectorcall;
    lt->log = (Log *)Py_NewRef((PyObject *)log);
    lt->topic = Py_NewRef(topic);
    lt->entry = NULL;
    lt->generation = 0;
    PyObject_GC_Track(lt);
    return (PyObject *)lt;
}

static PyObject *log_add(Log *log, PyObject *args, PyObject *kwds) {
    PyObject *topic, *typename;
    long cid;
    int clock = 0;
    static char *kwlist[] = {"topic", "channel_id", "typename", "clock", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "UlO|i", kwlist, &topic, &cid, &typename, &clock)
        || check_channel(cid) < 0)
        return NULL;
    PyObject *found = PyObject_CallOneArg(log->programs, typename);
    if (found == NULL)
        return NULL;
    if (!PyTuple_Check(found) || PyTuple_GET_SIZE(found) != 2) {
        Py_DECREF(found);
        PyErr_SetString(PyExc_TypeError, "programs(typename) must return (compiled program, keep)");
        return NULL;
    }
    Program *program = program_of(PyTuple_GET_ITEM(found, 0));
    int keep = program == NULL ? -1 : PyObject_IsTrue(PyTuple_GET_ITEM(found, 1));
    Channel *ch = keep < 0 ? NULL : PyMem_Malloc(sizeof(Channel));
    if (ch == NULL) {
        Py_DECREF(found);
        return keep < 0 ? NULL : PyErr_NoMemory();
    }
    int poses = log->poses.topic != NULL && PyUnicode_Compare(topic, log->poses.topic) == 0;
    int ros = log->ros_topic != NULL && PyUnicode_Compare(topic, log->ros_topic) == 0;
    *ch = (Channel){cid, keep, clock & (CLOCK_STEP | CLOCK_TICK), poses, ros, program,
                    Py_NewRef(PyTuple_GET_ITEM(found, 0))};
    Py_DECREF(found);
    PyObject *entry = PyCapsule_New(ch, NULL, channel_free);
    if (entry == NULL) {
        Py_DECREF(ch->owner);
        PyMem_Free(ch);
        return NULL;
    }
    int r = PyDict_SetItem(log->channels, topic, entry);
    Py_DECREF(entry);
    if (r < 0)
        return NULL;
    log->generation++;
    Py_RETURN_NONE;
}

static PyObject *log_timing(Log *log, PyObject *args, PyObject *kwds) {
    long long step_ns, chunk_ns;
    PyObject *on_chunk;
    static char *kwlist[] = {"step_ns", "chunk_ns", "on_chunk", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "LLO", kwlist, &step_ns, &chunk_ns, &on_chunk))
        return NULL;
    if (step_ns <= 0 || chunk_ns <= 0 || !PyCallable_Check(on_chunk)) {
        PyErr_SetString(PyExc_ValueError, "timing(step_ns > 0, chunk_ns > 0, on_chunk callable)");
        return NULL;
    }
    log->step_ns = step_ns;
    log->chunk_ns = chunk_ns;
    log->next_chunk = (log->now / chunk_ns + 1) * chunk_ns;
    Py_XSETREF(log->on_chunk, Py_NewRef(on_chunk));
    Py_RETURN_NONE;
}

/* the Python objects a Log holds, in one list each for the garbage collector's visit and clear */
#define LOG_OBJECTS(X) X(channels) X(programs) X(fallback) X(on_chunk) X(ros_topic)
#define POSES_OBJECTS(X) X(topic) X(fallback) X(names) X(template)

static void poses_clear(Poses *ps) {
#define CLEAR_POSES(field) Py_CLEAR(ps->field);
    POSES_OBJECTS(CLEAR_POSES)
#undef CLEAR_POSES
    PyMem_Free(ps->slots);
    ps->slots = NULL;
    ps->nslots = 0;
}

static PyObject *log_poses(Log *log, PyObject *args, PyObject *kwds) {
    PyObject *topic, *fallback;
    long cid;
    long long every;
    static char *kwlist[] = {"topic", "channel_id", "every", "fallback", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "UlLO", kwlist, &topic, &cid, &every, &fallback)
        || check_channel(cid) < 0)
        return NULL;
    if (every <= 0 || !PyCallable_Check(fallback)) {
        PyErr_SetString(PyExc_ValueError, "poses(topic, channel_id, every > 0, fallback callable)");
        return NULL;
    }
    poses_clear(&log->poses);
    log->poses = (Poses){Py_NewRef(topic), Py_NewRef(fallback), cid, every, NULL, NULL, NULL, 0, 0.0, 0.0};
    PyObject *key, *value;
    Py_ssize_t pos = 0;
    while (PyDict_Next(log->channels, &pos, &key, &value)) {
        Channel *ch = PyCapsule_GetPointer(value, NULL);
        if (ch == NULL)
            return NULL;
        ch->poses = PyUnicode_Compare(key, topic) == 0;
    }
    Py_RETURN_NONE;
}

static PyObject *log_pose_template(Log *log, PyObject *args, PyObject *kwds) {
    PyObject *names, *template, *slots;
    double grid, turn_grid;
    static char *kwlist[] = {"names", "template", "slots", "grid", "turn_grid", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "OSOdd", kwlist, &names, &template, &slots, &grid, &turn_grid))
        return NULL;
    if (log->poses.fallback == NULL) {
        PyErr_SetString(PyExc_ValueError, "pose_template: call poses() first");
        return NULL;
    }
    if (!(grid > 0.0) || !(turn_grid > 0.0)) {
        PyErr_SetString(PyExc_ValueError, "pose_template: grids must be positive");
        return NULL;
    }
    PyObject *seq = PySequence_Fast(slots, "pose_template: slots must be a sequence");
    if (seq == NULL)
        return NULL;
    Py_ssize_t n = PySequence_Fast_GET_SIZE(seq), size = PyBytes_GET_SIZE(template);
    PoseSlot *parsed = PyMem_Calloc(n ? n : 1, sizeof(PoseSlot));
    if (parsed == NULL) {
        Py_DECREF(seq);
        return PyErr_NoMemory();
    }
    for (Py_ssize_t i = 0; i < n; i++) {
        PoseSlot *slot = &parsed[i];
        if (!PyArg_ParseTuple(PySequence_Fast_GET_ITEM(seq, i), "nndp;slot: (offset, row, z, turn)",
                              &slot->offset, &slot->row, &slot->z, &slot->turn)
            || slot->offset < 4 || slot->offset + 7 * (Py_ssize_t)sizeof(double) > size || slot->row < 0) {
            if (!PyErr_Occurred())
                PyErr_SetString(PyExc_ValueError, "pose_template: a slot outside the template");
            PyMem_Free(parsed);
            Py_DECREF(seq);
            return NULL;
        }
    }
    Py_DECREF(seq);
    Poses *ps = &log->poses;
    Py_XSETREF(ps->names, Py_NewRef(names));
    Py_XSETREF(ps->template, Py_NewRef(template));
    PyMem_Free(ps->slots);
    ps->slots = parsed;
    ps->nslots = n;
    ps->grid = grid;
    ps->turn_grid = turn_grid;
    Py_RETURN_NONE;
}

static PyObject *log_record(Log *log, PyObject *args) {
    long cid;
    Py_buffer data;
    if (!PyArg_ParseTuple(args, "ly*", &cid, &data))
        return NULL;
    Py_ssize_t start = log->buf.n;
    State saved = enter(&log->buf, 0, NULL, NULL, NULL, NULL);
    int r = check_channel(cid);
    if (r == 0 && (r = reserve(RECORD_HEAD)) == 0) {
        out->n += RECORD_HEAD;
        r = put(data.buf, data.len);
    }
    leave(saved);
    PyBuffer_Release(&data);
    if (finish_record(log, start, cid, r) != 0)
        return NULL;
    Py_RETURN_NONE;
}

static PyObject *log_append(Log *log, PyObject *args) {
    Py_buffer data;
    if (!PyArg_ParseTuple(args, "y*", &data))
        return NULL;
    State saved = enter(&log->buf, 0, NULL, NULL, NULL, NULL);
    int r = put(data.buf, data.len);
    leave(saved);
    PyBuffer_Release(&data);
    if (r != 0)
        return NULL;
    Py_RETURN_NONE;
}

/* A chunk's records as `take` hands them over: the log's buffer itself, not a copy (a chunk of a match is some
 * 400 kB; copying it into a bytes object, whose fresh pages the system maps anew each time, cost the simulation
 * thread some 0.3 ms per chunk). Read through the buffer protocol (the writer writes it to its pipe); when it
 * is dropped, its memory becomes the spare buffer that the next `take` gives the log, so the same pages serve
 * every chunk. */
typedef struct {
    PyObject_HEAD
    Buf buf;
    Py_ssize_t exports;
} Chunk;

static Buf spare = {NULL, 0, 0, 0};     /* a dropped chunk's memory, for the log's next buffer (the GIL is held) */

static int chunk_getbuffer(Chunk *self, Py_buffer *view, int flags) {
    int r = PyBuffer_FillInfo(view, (PyObject *)self, self->buf.p ? self->buf.p : "", self->buf.n, 1, flags);
    if (r == 0)
        self->exports++;
    return r;
}

static void chunk_releasebuffer(Chunk *self, Py_buffer *view) {
    self->exports--;
}

static Py_ssize_t chunk_length(Chunk *self) {
    return self->buf.n;
}

/* `buf`, which holds no more records, as the spare buffer (the larger one is kept) */
static void keep_spare(Buf buf) {
    if (buf.lent)
        return;
    if (spare.cap < buf.cap) {
        PyMem_Free(spare.p);
        spare = buf;
        spare.n = 0;
    } else {
        PyMem_Free(buf.p);
    }
}

static void chunk_dealloc(Chunk *self) {
    keep_spare(self->buf);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *chunk_bytes(Chunk *self, PyObject *unused) {
    return PyBytes_FromStringAndSize(self->buf.p ? self->buf.p : "", self->buf.n);
}

static PyBufferProcs chunk_as_buffer = {(getbufferproc)chunk_getbuffer, (releasebufferproc)chunk_releasebuffer};
static PySequenceMethods chunk_as_sequence = {.sq_length = (lenfunc)chunk_length};
static PyMethodDef chunk_methods[] = {
    {"__bytes__", (PyCFunction)chunk_bytes, METH_NOARGS, "the records as bytes (a copy)"},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject ChunkType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "simatch.msgs._cdr_accel.Chunk",
    .tp_basicsize = sizeof(Chunk),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "the records of one chunk, as Log.take hands them over (a read-only buffer; bytes(chunk) copies)",
    .tp_dealloc = (destructor)chunk_dealloc,
    .tp_as_buffer = &chunk_as_buffer,
    .tp_as_sequence = &chunk_as_sequence,
    .tp_methods = chunk_methods,
};

static PyObject *log_take(Log *log, PyObject *unused) {
    PyObject *counts = PyDict_New();
    if (counts == NULL)
        return NULL;
    for (Py_ssize_t cid = 0; cid < log->ncounts; cid++) {
        if (!log->counts[cid])
            continue;
        PyObject *k = PyLong_FromSsize_t(cid), *v = PyLong_FromSsize_t(log->counts[cid]);
        int r = (k && v) ? PyDict_SetItem(counts, k, v) : -1;
        Py_XDECREF(k);
        Py_XDECREF(v);
        if (r < 0) {
            Py_DECREF(counts);
            return NULL;
        }
    }
    PyObject *result = NULL;
    if (log->buf.lent) {               /* the records are in the memory lent by `into`: a view of them */
        PyObject *whole = PyMemoryView_FromObject(log->target.obj);
        PyObject *data = whole ? PySequence_GetSlice(whole, 0, log->buf.n) : NULL;
        Py_XDECREF(whole);
        if (data != NULL)
            result = Py_BuildValue("(NNLL)", data, counts, log->first, log->last);
        if (result == NULL) {
            Py_DECREF(counts);
            return NULL;
        }
        PyBuffer_Release(&log->target);   /* the log writes no more into it: the memory is the taker's now */
        log->buf = spare;                 /* until the next `into` */
        spare = (Buf){NULL, 0, 0, 0};
    } else {
        Chunk *data = PyObject_New(Chunk, &ChunkType);
        if (data != NULL) {
            data->buf = log->buf;          /* the buffer itself; the log goes on in the spare one */
            data->exports = 0;
            log->buf = spare;
            spare = (Buf){NULL, 0, 0, 0};
            result = Py_BuildValue("(NNLL)", (PyObject *)data, counts, log->first, log->last);
        }
        if (result == NULL) {
            Py_XDECREF(data);
            Py_DECREF(counts);
            return NULL;
        }
    }
    log->buf.n = 0;
    log->first = log->last = -1;
    if (log->ncounts)
        memset(log->counts, 0, log->ncounts * sizeof(Py_ssize_t));
    return result;
}

/* stop writing into the memory lent by `into`: the records held there move to memory of the log's own */
static int leave_target(Log *log) {
    if (log->target.obj == NULL)
        return 0;
    if (log->buf.lent) {
        Buf own = spare;
        if (own.cap < log->buf.n) {
            char *p = PyMem_Realloc(own.p, log->buf.n);
            if (p == NULL) {
                PyErr_NoMemory();
                return FAILED;
            }
            own.p = p;
            own.cap = log->buf.n;
        }
        spare = (Buf){NULL, 0, 0, 0};
        if (log->buf.n)
            memcpy(own.p, log->buf.p, log->buf.n);
        own.n = log->buf.n;
        log->buf = own;
    }
    PyBuffer_Release(&log->target);
    return 0;
}

/* into(buffer or None): write the records from now on into `buffer` (a writable buffer: memory shared with the
 * process that writes the file), as long as they fit; those held since the last take move there (if they
 * fit). `take` then hands them over as a memoryview of `buffer`, and the log writes no more into it until it
 * is given again. None: back to memory of the log's own. */
static PyObject *log_into(Log *log, PyObject *arg) {
    Py_buffer view = {0};
    if (arg != Py_None && PyObject_GetBuffer(arg, &view, PyBUF_WRITABLE) < 0)
        return NULL;
    if (leave_target(log) < 0) {
        if (view.obj != NULL)
            PyBuffer_Release(&view);
        return NULL;
    }
    if (view.obj == NULL)
        Py_RETURN_NONE;
    if (log->buf.n > view.len) {      /* what is held does not fit: it stays where it is */
        PyBuffer_Release(&view);
        Py_RETURN_NONE;
    }
    if (log->buf.n)
        memcpy(view.buf, log->buf.p, log->buf.n);
    Py_ssize_t n = log->buf.n;
    keep_spare(log->buf);
    log->buf = (Buf){view.buf, n, view.len, 1};
    log->target = view;
    Py_RETURN_NONE;
}

static PyObject *log_forget(Log *log, PyObject *unused) {
    if (forget(log) < 0)
        return NULL;
    Py_RETURN_NONE;
}

static PyObject *log_size(Log *log, void *closure) {
    return PyLong_FromSsize_t(log->buf.n);
}

/* the garbage collector's visit and clear of the objects a `self` holds (listed by an X macro: LOG_OBJECTS) */
#define VISIT_MEMBER(field) Py_VISIT(self->field);
#define CLEAR_MEMBER(field) Py_CLEAR(self->field);

static int log_traverse(Log *self, visitproc visit, void *arg) {
#define VISIT_POSES(field) Py_VISIT(self->poses.field);
    LOG_OBJECTS(VISIT_MEMBER)
    POSES_OBJECTS(VISIT_POSES)
    Py_VISIT(self->target.obj);
#undef VISIT_POSES
    for (int i = 0; i < 2; i++) {
        int r = table_traverse(&self->memo[i], visit, arg);
        if (r)
            return r;
    }
    return 0;
}

static int log_clear(Log *self) {
    LOG_OBJECTS(CLEAR_MEMBER)
    poses_clear(&self->poses);
    if (self->target.obj != NULL) {   /* the records held in the lent memory are dropped with it */
        if (self->buf.lent)
            self->buf = (Buf){NULL, 0, 0, 0};
        PyBuffer_Release(&self->target);
    }
    table_clear(&self->memo[0]);
    table_clear(&self->memo[1]);
    return 0;
}

static void log_dealloc(Log *log) {
    PyObject_GC_UnTrack(log);
    log_clear(log);
    table_free(&log->memo[0]);
    table_free(&log->memo[1]);
    if (!log->buf.lent)
        PyMem_Free(log->buf.p);
    PyMem_Free(log->counts);
    Py_TYPE(log)->tp_free((PyObject *)log);
}

static PyObject *log_new(PyTypeObject *type, PyObject *args, PyObject *kwds) {
    PyObject *programs, *fallback;
    static char *kwlist[] = {"programs", "fallback", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "OO", kwlist, &programs, &fallback))
        return NULL;
    if (!PyCallable_Check(programs) || !PyCallable_Check(fallback)) {
        PyErr_SetString(PyExc_TypeError, "Log(programs, fallback): two callables");
        return NULL;
    }
    Log *log = (Log *)type->tp_alloc(type, 0);
    if (log == NULL)
        return NULL;
    log->vectorcall = log_vectorcall;
    log->first = log->last = log->step = -1;
    log->channels = PyDict_New();
    log->programs = Py_NewRef(programs);
    log->fallback = Py_NewRef(fallback);
    if (log->channels == NULL) {
        Py_DECREF(log);
        return NULL;
    }
    return (PyObject *)log;
}

static PyMethodDef log_methods[] = {
    {"add", (PyCFunction)(void (*)(void))log_add, METH_VARARGS | METH_KEYWORDS,
     "add(topic, channel_id, typename, clock=0): record topic on that channel"},
    {"timing", (PyCFunction)(void (*)(void))log_timing, METH_VARARGS | METH_KEYWORDS,
     "timing(step_ns, chunk_ns, on_chunk): how clock messages set the time and end chunks"},
    {"ros_clock", (PyCFunction)log_ros_clock, METH_VARARGS,
     "ros_clock(topic, channel_id): after each message on topic, ROS 2's clock at the log time on that channel"},
    {"poses", (PyCFunction)(void (*)(void))log_poses, METH_VARARGS | METH_KEYWORDS,
     "poses(topic, channel_id, every, fallback): a pose template's record every `every` steps of topic"},
    {"pose_template", (PyCFunction)(void (*)(void))log_pose_template, METH_VARARGS | METH_KEYWORDS,
     "pose_template(names, template, slots, grid, turn_grid): the template for model states of these names"},
    {"record", (PyCFunction)log_record, METH_VARARGS, "record(channel_id, data): an encoded message, at `now`"},
    {"append", (PyCFunction)log_append, METH_VARARGS, "append(data): raw records"},
    {"take", (PyCFunction)log_take, METH_NOARGS,
     "take() -> (chunk, {channel_id: messages}, first time, last time) since the last take; chunk: a buffer"},
    {"for_topic", (PyCFunction)log_for_topic, METH_O,
     "for_topic(topic) -> f: f(msg) logs msg as log(topic, msg) does (the in-process bus calls it)"},
    {"into", (PyCFunction)log_into, METH_O,
     "into(buffer or None): write the next records into buffer (writable) while they fit; take hands a view of it"},
    {"forget", (PyCFunction)log_forget, METH_NOARGS, "forget(): start a new memo period"},
    {NULL, NULL, 0, NULL},
};

static PyMemberDef log_members[] = {
    {"now", T_LONGLONG, offsetof(Log, now), 0, "log time of the next messages [ns]"},
    {NULL, 0, 0, 0, NULL},
};

static PyGetSetDef log_getset[] = {
    {"size", (getter)log_size, NULL, "bytes held since the last take", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

/* the slots of a callable object type that holds Python objects (Log, Tap): its struct T, functions prefix_* */
#define CALLABLE_TYPE(T, prefix)                                                                           \
    .tp_basicsize = sizeof(T), .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL, \
    .tp_new = prefix##_new, .tp_dealloc = (destructor)prefix##_dealloc,                                        \
    .tp_traverse = (traverseproc)prefix##_traverse, .tp_clear = (inquiry)prefix##_clear,                        \
    .tp_call = PyVectorcall_Call, .tp_vectorcall_offset = offsetof(T, vectorcall)

static PyTypeObject LogType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "simatch.msgs._cdr_accel.Log",
    .tp_doc = "Log(programs, fallback): MCAP message records of bus messages, encoded to CDR in C",
    CALLABLE_TYPE(Log, log),
    .tp_methods = log_methods,
    .tp_members = log_members,
    .tp_getset = log_getset,
};

/* ------------------------------------------------------------------------------------------------------------
 * The world's input taps (`simatch.sim.inputs`): the logging twins of the simulator's velocity and action
 * commands, which a match calls hundreds of times per simulated second while a recorder listens. A Python
 * twin cost a frame (and a tuple of its arguments) per call; a tap is one C call that appends the command to
 * the input log's lists, as `InputLog.vel`/`InputLog.action` do, and calls the simulator's method. Any other
 * call (keywords, another count of arguments, a robot index that is not a small int, a call made while the
 * log is busy) goes to `general`, the Python twin that logs it as a call. */

#define TAP_VEL 1
#define TAP_ACTION 2

typedef struct {
    PyObject_HEAD
    vectorcallfunc vectorcall;
    int form;                      /* TAP_VEL or TAP_ACTION */
    PyObject *original, *general, *log, *kind, *robot, *values, *code; /* code: the kind's int */
    PyTypeObject *log_type;        /* the log's class when it holds `busy` in a slot (at `busy_at`), else NULL */
    unsigned int log_version;      /* ... and its version tag then (the slot is read while it is the same) */
    Py_ssize_t busy_at;
} Tap;

static PyObject *busy_name;       /* (below, with the taps' other constants) */

/* the log's `busy` mark: read in its slot (as `encode_program` reads a message's fields), else by name */
static int tap_busy(Tap *tap) {
    PyTypeObject *tp = Py_TYPE(tap->log);
    if (tp == tap->log_type && tp->tp_version_tag == tap->log_version) {
        PyObject *busy = *(PyObject **)((char *)tap->log + tap->busy_at);
        if (busy == Py_False)
            return 0;
        if (busy == Py_True)
            return 1;
    }
    PyObject *busy = PyObject_GetAttr(tap->log, busy_name);
    if (busy == NULL)
        return -1;
    int b = PyObject_IsTrue(busy);
    Py_DECREF(busy);
    return b;
}

static PyObject *busy_name = NULL, *zero = NULL, *one = NULL, *nan_value = NULL;

static int tap_append(Tap *tap, PyObject *index, PyObject *const *numbers, int n) {
    if (PyList_Append(tap->kind, tap->code) < 0 || PyList_Append(tap->robot, index) < 0)
        return FAILED;
    for (int k = 0; k < n; k++)
        if (PyList_Append(tap->values, numbers[k]) < 0)
            return FAILED;
    return 0;
}

static PyObject *tap_vectorcall(PyObject *self, PyObject *const *args, size_t nargsf, PyObject *kwnames) {
    Tap *tap = (Tap *)self;
    Py_ssize_t nargs = PyVectorcall_NARGS(nargsf);
    int compact = (kwnames == NULL || PyTuple_GET_SIZE(kwnames) == 0)
                  && (tap->form == TAP_VEL ? nargs == 4 : (nargs >= 2 && nargs <= 5)) && PyLong_CheckExact(args[0]);
    if (compact) {
        int overflow = 0;
        long i = PyLong_AsLongAndOverflow(args[0], &overflow);
        compact = !overflow && i >= 0 && i < 32768;
    }
    if (compact) {
        int b = tap_busy(tap);
        if (b < 0)
            return NULL;
        compact = !b;
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

#define TAP_OBJECTS(X) X(original) X(general) X(log) X(kind) X(robot) X(values) X(code)

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

static PyObject *tap_new(PyTypeObject *type, PyObject *args, PyObject *kwds) {
    static char *kwlist[] = {"form", "original", "general", "log", "kind", "robot", "values", "code", NULL};
    const char *form;
    PyObject *original, *general, *log, *kind, *robot, *values, *code;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "sOOOO!O!O!O", kwlist, &form, &original, &general, &log,
                                     &PyList_Type, &kind, &PyList_Type, &robot, &PyList_Type, &values, &code))
        return NULL;
    int f = strcmp(form, "vel") == 0 ? TAP_VEL : strcmp(form, "action") == 0 ? TAP_ACTION : 0;
    if (!f || !PyCallable_Check(original) || !PyCallable_Check(general)) {
        PyErr_SetString(PyExc_ValueError, "Tap(form: \"vel\" or \"action\", original, general, log, lists, code)");
        return NULL;
    }
    Tap *tap = (Tap *)type->tp_alloc(type, 0);
    if (tap == NULL)
        return NULL;
    tap->vectorcall = tap_vectorcall;
    tap->form = f;
    tap->original = Py_NewRef(original);
    tap->general = Py_NewRef(general);
    tap->log = Py_NewRef(log);
    tap->kind = Py_NewRef(kind);
    tap->robot = Py_NewRef(robot);
    tap->values = Py_NewRef(values);
    tap->code = Py_NewRef(code);
    PyTypeObject *lt = Py_TYPE(log);                /* does the log hold `busy` in a slot? (InputLog does) */
    Py_ssize_t busy_at = slot_offset(lt, busy_name);
    if (busy_at > 0 && PyType_HasFeature(lt, Py_TPFLAGS_VALID_VERSION_TAG)) {
        tap->log_type = lt;
        tap->log_version = lt->tp_version_tag;
        tap->busy_at = busy_at;
    }
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
    .tp_name = "simatch.msgs._cdr_accel.Tap",
    .tp_doc = "Tap(form, original, general, log, kind, robot, values, code): a world input's logging twin in C",
    CALLABLE_TYPE(Tap, tap),
    .tp_getset = tap_getset,
};

/* pack(list, code) -> bytearray | None: the list's numbers as one machine array ("d": float64 from exact floats,
 * exact ints (correctly rounded, as float() rounds them) and bools; "B": uint8 and "h": int16 from exact ints
 * in range), or None if an item is anything else (the caller converts those lists itself). The world inputs'
 * message takes its arrays so (`simatch.sim.inputs`): the array module's constructor parses each item's
 * format, some hundred instructions per number. */
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
    const DescrHead *d = (const DescrHead *)a->descr;
    if (dtypes[K_F64] != a->descr || d->kind != 'f' || d->type != 'd')
        Py_RETURN_FALSE;
    Py_INCREF(type);
    Py_XSETREF(ndarray, (PyTypeObject *)type);
    Py_RETURN_TRUE;
}

static PyMethodDef methods[] = {
    {"encode", encode, METH_VARARGS, "encode(compiled program, msg) -> CDR bytes with the header, or None: use Python"},
    {"setup", setup, METH_VARARGS, "setup(ndarray, {kind: dtype}, np.arange(3.0)) -> arrays read directly"},
    {"pack", pack, METH_VARARGS, "pack(list, 'd'|'B'|'h') -> the numbers as a bytearray, or None: convert them yourself"},
    {"compile", compile, METH_O, "compile(program tuple) -> the compiled program that encode and Log take"},
    {"compile_decoder", compile_decoder, METH_O, "compile_decoder((class, ops)) -> the program decode takes"},
    {"decode", decode, METH_VARARGS, "decode(compiled decoder program, payload bytes) -> message, or MessageError"},
    {"setup_decoding", setup_decoding, METH_O, "setup_decoding(MessageError): the error decode raises"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_cdr_accel", NULL, -1, methods};

/* what this build was made from (setup.py: the first 16 hex digits of this file's SHA-256), so that a test can
 * tell an extension left from an older source (an optional extension that fails to compile leaves the last one) */
#ifndef SIMATCH_SOURCE_DIGEST
#define SIMATCH_SOURCE_DIGEST ""
#endif

PyMODINIT_FUNC PyInit__cdr_accel(void) {
    if (PyType_Ready(&LogType) < 0 || PyType_Ready(&ChunkType) < 0 || PyType_Ready(&TapType) < 0
        || PyType_Ready(&LogTopicType) < 0
        || (busy_name = PyUnicode_InternFromString("busy")) == NULL || (zero = PyFloat_FromDouble(0.0)) == NULL
        || (one = PyFloat_FromDouble(1.0)) == NULL || (nan_value = PyFloat_FromDouble(Py_NAN)) == NULL
        || (step_name = PyUnicode_InternFromString("step")) == NULL
        || (name_name = PyUnicode_InternFromString("name")) == NULL
        || (pose_name = PyUnicode_InternFromString("pose")) == NULL)
        return NULL;
    PyObject *m = PyModule_Create(&module);
    if (m == NULL)
        return NULL;
    if (PyModule_AddObjectRef(m, "Log", (PyObject *)&LogType) < 0
        || PyModule_AddObjectRef(m, "Tap", (PyObject *)&TapType) < 0
        || PyModule_AddStringConstant(m, "SOURCE_DIGEST", SIMATCH_SOURCE_DIGEST) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
