/* The recorder's message log in C: `Log`, the bus callback behind `simatch.record.messagelog` (whose
 * docstring describes its interface), compiled into the extension `simatch.msgs._cdr_accel` with the CDR
 * encoder it calls (simatch/msgs/_cdr_accel.c, shared through _cdr_accel.h).
 *
 * `Log(programs, fallback)` is called as ``log(topic, msg)`` and appends the message to one buffer as an MCAP
 * Message record: opcode 0x05, record length, channel id, sequence 0, log time and publish time = `log.now`
 * (u64 nanoseconds), then the message's CDR bytes, encoded in place by the topic's program. The whole path
 * (topic look-up, clock, record header, encoding, count) is one C call, so that recording a run adds no
 * Python frame and no object per message on the thread that runs the simulation.
 *
 * The pose template and the chunks are units of their own (`_messagelog.h`). What this unit reads by offset:
 * nothing of its own (messages are read by the encoder; the pose template's
 * `name` and `pose` by attribute and buffer protocol).
 */
#include "_messagelog.h"

static PyObject *step_name;        /* "step" (interned, `messagelog_add_types`) */
PyObject *name_name, *pose_name;

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

int check_channel(long cid) {
    if (cid < 0 || cid > 65535) {
        if (!PyErr_Occurred())
            PyErr_SetString(PyExc_ValueError, "channel id: 0 to 65535");
        return FAILED;
    }
    return 0;
}

/* the record begun at `start` is written (r == 0): count it and write its header; else take it back */
int finish_record(Log *log, Py_ssize_t start, long cid, int r) {
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

/* the result of a call whose value is not wanted: 0, or FAILED (its exception set) */
int called(PyObject *result) {
    Py_XDECREF(result);
    return result == NULL ? FAILED : 0;
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

/* the Python objects a Log holds, in one list for the garbage collector's visit and clear */
#define LOG_OBJECTS(X) X(channels) X(programs) X(fallback) X(on_chunk) X(ros_topic)

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

/* the slots of a callable object type that holds Python objects: its struct T, functions prefix_* */
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


static PyMethodDef messagelog_functions[] = {
    {"fill_poses", fill_poses, METH_VARARGS,
     "fill_poses(template, slots, pose rows, grid, turn_grid) -> the template with the poses written"},
    {NULL, NULL, 0, NULL},
};

int messagelog_add_types(PyObject *module) {
    if (PyType_Ready(&LogType) < 0 || PyType_Ready(&ChunkType) < 0 || PyType_Ready(&LogTopicType) < 0
        || (step_name = PyUnicode_InternFromString("step")) == NULL
        || (name_name = PyUnicode_InternFromString("name")) == NULL
        || (pose_name = PyUnicode_InternFromString("pose")) == NULL)
        return -1;
    if (PyModule_AddFunctions(module, messagelog_functions) < 0)
        return -1;
    return PyModule_AddObjectRef(module, "Log", (PyObject *)&LogType);
}
