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
 * What this unit reads by offset: nothing of its own (messages are read by the encoder; the pose template's
 * `name` and `pose` by attribute and buffer protocol).
 */
#include "../msgs/_cdr_accel.h"

#define RECORD_HEAD 31             /* opcode u8, length u64, channel u16, sequence u32, log time u64, publish u64 */
#define CLOCK_STEP 1               /* add(..., clock=): the message's `step` sets the log time */
#define CLOCK_TICK 2               /* ... and opens a new memo period */

/* A pose template (``log.poses``): every `every` physics steps, a message on `topic` (model states: `name`, and
 * `pose` as rows of x y z qw qx qy qz) also yields a record on `channel`: a copy of `template` (a message
 * encoded once, header included) with a geometry_msgs/Pose (7 float64: position, then quaternion x y z w)
 * written at each slot's offset from its row, snapped to a grid: the recorder's 3D scene, drawn without a
 * Python call per update. Whatever this does not take as it is (no template yet, other names, a pose that is
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

static PyObject *step_name, *name_name, *pose_name; /* "step", "name", "pose" (interned, `messagelog_add_types`) */

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

/* A geometry_msgs/Pose at each slot's offset in `at` (a copy of the template), from the rows of x y z qw qx qy qz
 * in `rows` (float32 if `f32`, else float64): the position snapped to the grid, the height the slot's (or the
 * row's, snapped, if NaN), the orientation the row's turn about z snapped (or none). */
static void write_poses(char *at, const PoseSlot *slots, Py_ssize_t nslots, const void *rows, int f32, double grid,
                        double turn_grid) {
    for (Py_ssize_t i = 0; i < nslots; i++) {
        const PoseSlot *slot = &slots[i];
        double p[7], v[7];
        for (int j = 0; j < 7; j++)
            p[j] = f32 ? (double)((const float *)rows)[slot->row * 7 + j] : ((const double *)rows)[slot->row * 7 + j];
        v[0] = snap(p[0], grid);
        v[1] = snap(p[1], grid);
        v[2] = isnan(slot->z) ? snap(p[2], grid) : slot->z;
        v[3] = v[4] = 0.0;
        v[5] = slot->turn ? snap(p[6], turn_grid) : 0.0;
        v[6] = slot->turn ? snap(p[3], turn_grid) : 1.0;
        memcpy(at + slot->offset, v, sizeof v);
    }
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
        write_poses(at, ps->slots, ps->nslots, view.buf, f32, ps->grid, ps->turn_grid);
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

/* the slots of a pose template of `size` bytes, each (offset, row, z, turn); NULL (ValueError) if one is not inside
 * the template */
static PoseSlot *parse_slots(PyObject *slots, Py_ssize_t size, Py_ssize_t *count) {
    PyObject *seq = PySequence_Fast(slots, "pose_template: slots must be a sequence");
    if (seq == NULL)
        return NULL;
    Py_ssize_t n = PySequence_Fast_GET_SIZE(seq);
    PoseSlot *parsed = PyMem_Calloc(n ? n : 1, sizeof(PoseSlot));
    if (parsed == NULL) {
        Py_DECREF(seq);
        PyErr_NoMemory();
        return NULL;
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
    *count = n;
    return parsed;
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
    Py_ssize_t n;
    PoseSlot *parsed = parse_slots(slots, PyBytes_GET_SIZE(template), &n);
    if (parsed == NULL)
        return NULL;
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


/* fill_poses(template, slots, pose rows (a contiguous float32 or float64 buffer), grid, turn_grid) -> the
 * template with the poses written (as the log's pose template writes them: `write_poses`) */
static PyObject *fill_poses(PyObject *self, PyObject *args) {
    PyObject *template, *slots, *pose;
    Py_buffer view;
    double grid, turn_grid;
    if (!PyArg_ParseTuple(args, "SOOdd", &template, &slots, &pose, &grid, &turn_grid)
        || PyObject_GetBuffer(pose, &view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0)
        return NULL;
    Py_ssize_t n = 0, size = PyBytes_GET_SIZE(template);
    PoseSlot *parsed = parse_slots(slots, size, &n);
    PyObject *result = NULL;
    int f32 = format_fits(K_F32, view.format, view.itemsize), f64 = format_fits(K_F64, view.format, view.itemsize);
    Py_ssize_t values = view.itemsize ? view.len / view.itemsize : 0, rows = values / 7, needed = 0;
    for (Py_ssize_t i = 0; parsed != NULL && i < n; i++)
        needed = parsed[i].row + 1 > needed ? parsed[i].row + 1 : needed;
    if (parsed == NULL)
        goto done;
    if (!(f32 || f64) || values % 7 != 0)
        PyErr_SetString(PyExc_ValueError, "fill_poses: poses as rows of 7 float32 or float64");
    else if (rows < needed)
        PyErr_Format(PyExc_ValueError, "%zd poses where the template shows %zd models", rows, needed);
    else if ((result = PyBytes_FromStringAndSize(PyBytes_AS_STRING(template), size)) != NULL)
        write_poses(PyBytes_AS_STRING(result), parsed, n, view.buf, f32, grid, turn_grid);
done:
    PyMem_Free(parsed);
    PyBuffer_Release(&view);
    return result;
}

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
