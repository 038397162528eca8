/* What the units of the recorder's message log share (`Log`, the bus callback behind
 * `simatch.record.messagelog`): `_messagelog.c` the log and its records, `_messagelog_poses.c` the pose
 * template, `_messagelog_chunks.c` the chunks the log hands over. They are compiled into the extension
 * `simatch.msgs._cdr_accel` with the CDR encoder they call (`simatch/msgs/_cdr_accel.h`).
 */
#ifndef SIMATCH_MESSAGELOG_H
#define SIMATCH_MESSAGELOG_H

#include "../msgs/_cdr_accel.h"

#pragma GCC visibility push(hidden)

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

/* the Python objects a Poses holds, in one list for the garbage collector's visit and clear */
#define POSES_OBJECTS(X) X(topic) X(fallback) X(names) X(template)

extern PyObject *name_name, *pose_name;   /* "name", "pose" (interned, `messagelog_add_types`) */

/* the log (`_messagelog.c`) */
int check_channel(long cid);
/* the record begun at `start` is written (r == 0): count it and write its header; else take it back */
int finish_record(Log *log, Py_ssize_t start, long cid, int r);
/* the result of a call whose value is not wanted: 0, or FAILED (its exception set) */
int called(PyObject *result);

/* the pose template (`_messagelog_poses.c`) */
int poses_after(Log *log, PyObject *msg);
void poses_clear(Poses *ps);
PyObject *log_poses(Log *log, PyObject *args, PyObject *kwds);
PyObject *log_pose_template(Log *log, PyObject *args, PyObject *kwds);
PyObject *fill_poses(PyObject *self, PyObject *args);

/* the chunks (`_messagelog_chunks.c`) */
extern PyTypeObject ChunkType;
PyObject *log_take(Log *log, PyObject *unused);
PyObject *log_into(Log *log, PyObject *arg);

#pragma GCC visibility pop

#endif
