/* The CDR decoder of `simatch.msgs.cdr`.
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

#include "_cdr_accel.h"

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
PyObject *compile_decoder(PyObject *self, PyObject *program) {
    return capsule_of(compile_decoder_tuple(program));
}

/* decode(compiled decoder program, payload: bytes) -> message; MessageError if the payload is not one */
PyObject *decode(PyObject *self, PyObject *args) {
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
PyObject *setup_decoding(PyObject *self, PyObject *error) {
    if (!PyType_Check(error) || !PyType_IsSubtype((PyTypeObject *)error, (PyTypeObject *)PyExc_Exception)) {
        PyErr_SetString(PyExc_TypeError, "an exception class expected");
        return NULL;
    }
    Py_INCREF(error);
    Py_XSETREF(message_error, error);
    Py_RETURN_NONE;
}
