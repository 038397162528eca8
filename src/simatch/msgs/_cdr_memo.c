/* The encoder's memo (see simatch.msgs.cdr): this period's and the last one's, id(object) -> (object, phase,
 * bytes): a list met again at the same phase (offset modulo 8), or a message encoded on its own (phase 0, its
 * body) met again inside a sequence. Two forms: `encode` takes two dicts (id -> (object, phase, bytes)); the
 * message log holds two tables of its own (`MemoTable`: no Python object per entry, the bytes in one buffer per
 * period), so that remembering an entry makes no keys, tuples or bytes objects. NULL (both forms): no memo.
 */
#include "_cdr_accel.h"

PyObject *memo_now = NULL, *memo_old = NULL;
MemoTable *table_now = NULL, *table_old = NULL;

int memo_on(void) {
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
int memo_find(PyObject *obj, long phase, const char **p, Py_ssize_t *size) {
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
