/* The chunks of the message log: `take` hands the records held since the last take over, either as a `Chunk`
 * (the log's own buffer) or as a view of the memory lent by `into` (shared with the process that writes the
 * file).
 */
#include "_messagelog.h"

/* A chunk's records as `take` hands them over: the log's buffer itself, not a copy, so that the simulation
 * thread neither copies a chunk nor touches fresh pages for each one. Read through the buffer protocol (the
 * writer writes it to its pipe); when it is dropped, its memory becomes the spare buffer that the next `take`
 * gives the log, so the same pages serve every chunk. */
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

PyTypeObject ChunkType = {
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

PyObject *log_take(Log *log, PyObject *unused) {
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
PyObject *log_into(Log *log, PyObject *arg) {
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
