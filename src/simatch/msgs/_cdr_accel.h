/* What the units of the extension `simatch.msgs._cdr_accel` share: the CDR codec's (next to
 * `simatch.msgs.cdr`: `_cdr_accel.c` the module and numpy's layout, `_cdr_program.c` the compiled programs,
 * `_cdr_encode.c` the encoder, `_cdr_memo.c` its memo, `_cdr_decode.c` the decoder) and the recorder's message
 * log (`simatch/record/_messagelog*.c`), compiled into the same extension so that the log encodes each message
 * into its chunk buffer by a direct call of the encoder.
 *
 * The encoder writes into `out` (a growable buffer, or memory lent by the log), aligning each field to its
 * size counted from `body`, the offset where the current CDR body starts. A caller that encodes somewhere
 * else `enter`s with its buffer and memo, and `leave`s to restore what was there before (a field's
 * conversion may run Python code that encodes too).
 */
#ifndef SIMATCH_CDR_ACCEL_H
#define SIMATCH_CDR_ACCEL_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <string.h>
#include <structmember.h>

/* the symbols below are shared by the extension's units only */
#pragma GCC visibility push(hidden)

/* the kinds of a program's steps (the same numbers as `simatch.msgs.cdr`'s _KIND and _K_*) */
enum {
    K_BOOL = 1, K_I8, K_U8, K_I16, K_U16, K_I32, K_U32, K_I64, K_U64, K_F32, K_F64,
    K_STR = 20, K_MSG, K_PSEQ, K_SSEQ, K_MSEQ
};

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

extern int c_contiguous;           /* numpy's flag of a C-contiguous array (`setup`) */
extern PyTypeObject *ndarray;      /* numpy.ndarray (`setup`) */
extern PyObject *dtypes[16];       /* by kind: the dtype object of contiguous arrays taken as they are */

/* the size on the wire of a primitive of `kind` */
static inline int size_of(long kind) {
    switch (kind) {
    case K_BOOL: case K_I8: case K_U8: return 1;
    case K_I16: case K_U16: return 2;
    case K_I32: case K_U32: case K_F32: return 4;
    default: return 8;
    }
}

#define FALLBACK 1                 /* not for the fast path: the caller uses the Python encoder */
#define FAILED -1                  /* a Python exception is set (memory) */

typedef struct {
    char *p;
    Py_ssize_t n, cap;
    int lent;                      /* p is memory lent by another object (a message log's `into`): never
                                    * reallocated or freed here; growing past cap moves the bytes to memory
                                    * of the Buf's own */
} Buf;

extern Buf *out;                   /* where the encoder writes now */
extern Py_ssize_t body;            /* offset in `out` of the CDR body being written (alignment counts from it) */

int grow(Py_ssize_t need);

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

/* does a buffer's struct format describe the wire's element type `kind` (little endian or native)? */
int format_fits(long kind, const char *fmt, Py_ssize_t itemsize);

/* A program compiled once (`compile`): the steps of its tuple ((kind, attribute, argument), ...) as C values. */
typedef struct Program Program;
typedef struct {
    int kind;
    int elem;                      /* K_PSEQ: the element kind; K_MSEQ: the alignment of the first field */
    Py_ssize_t fixed;              /* sequences: the fixed length of an array, or -1 */
    PyObject *name;                /* the attribute (interned) */
    Program *sub;                  /* K_MSG, K_MSEQ: the nested message's program */
    Py_ssize_t offset;             /* where instances of the program's `type` hold this field (slotted) */
} Op;
/* Field reads: the message classes of simatch.msgs have __slots__ (`simatch.msgs._with_slots`), so an
 * instance holds each field at a fixed offset. A program learns the offsets from the class's member
 * descriptors (`slot_offset`) when it first meets the class, keeps the class's version tag (which changes
 * whenever the class is modified) and reads the fields there while the tag is the same. Any other class (a
 * dict-based one, a class with a property or __getattribute__ of its own) is read with PyObject_GetAttr. */
struct Program {
    Py_ssize_t count;
    PyTypeObject *type;            /* the class last met (a strong reference), or NULL */
    unsigned int version;          /* its version tag then */
    int slotted;                   /* read its instances' fields at `offset` */
    int direct;                    /* decoding: make instances of `type` by filling their slots */
    Op ops[];
};

/* the compiled program a capsule made by `compile` holds (NULL, an exception set, if it is not one) */
Program *program_of(PyObject *capsule);

/* a program tuple's ops compiled (`compile` compiles the programs of nested messages); NULL: an exception set */
Program *compile_ops(PyObject *ops, Program *(*compile)(PyObject *));

/* how instances of `tp` hold the program's fields (slotted, at which offsets), learnt for `tp` */
void learn(Program *program, PyTypeObject *tp);

/* a compiled program (NULL: an exception is set) as the capsule Python holds */
PyObject *capsule_of(Program *p);

/* encode `msg` into `out` by `program`: 0, FALLBACK (the caller takes back what was written) or FAILED */
int encode_program(Program *program, PyObject *msg);

/* The memo of a message log: two tables (this period's, the last one's), object -> (phase, bytes), so that
 * a list or a message met again is copied rather than encoded again (see simatch.msgs.cdr). */
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

/* the memo in use (`enter`): two dicts (`encode`) or two tables (a log); NULL: none */
extern PyObject *memo_now, *memo_old;
extern MemoTable *table_now, *table_old;

/* whether a memo is in use */
int memo_on(void);

/* the bytes kept for `obj` at `phase` (1; *p and *size set), none (0), or an error (-1, its exception set) */
int memo_find(PyObject *obj, long phase, const char **p, Py_ssize_t *size);

int table_traverse(const MemoTable *t, visitproc visit, void *arg);
void table_clear(MemoTable *t);
void table_free(MemoTable *t);

/* remember the bytes written to `out` since `start` as those of `obj` at `phase` */
int memo_keep(PyObject *obj, long phase, Py_ssize_t start);

/* The encoder's globals while one call runs: `enter` sets them and returns those it replaces, `leave`
 * restores them. `now`/`old`: the memo as two dicts (`encode`), `tnow`/`told` as two tables (a log); NULL: none. */
typedef struct {
    Buf *out;
    Py_ssize_t body;
    PyObject *memo_now, *memo_old;
    MemoTable *table_now, *table_old;
} State;

State enter(Buf *to, Py_ssize_t at, PyObject *now, PyObject *old, MemoTable *tnow, MemoTable *told);
void leave(State saved);

/* the module's functions, each in the unit of its layer */
PyObject *encode(PyObject *self, PyObject *args);
PyObject *compile(PyObject *self, PyObject *program);
PyObject *compile_decoder(PyObject *self, PyObject *program);
PyObject *decode(PyObject *self, PyObject *args);
PyObject *setup_decoding(PyObject *self, PyObject *error);

/* the message log's types added to the module (`_messagelog.c`): 0, or -1 with an exception set */
int messagelog_add_types(PyObject *module);

#pragma GCC visibility pop

#endif
