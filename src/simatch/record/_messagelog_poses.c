/* The message log's pose template (``log.poses``, ``log.pose_template``; see `Poses` in `_messagelog.h`): the
 * recorder's 3D scene drawn from the model states without a Python call per update, and `fill_poses`, which
 * writes the same poses into a template for the Python side.
 *
 * What this unit reads by offset: nothing (a message's `name` and `pose` by attribute and buffer protocol).
 */
#include "_messagelog.h"

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

int poses_after(Log *log, PyObject *msg) {
    Poses *ps = &log->poses;
    if (ps->fallback == NULL || log->step < 0 || log->step % ps->every != 0)
        return 0;
    int r = pose_record(log, msg);
    if (r != FALLBACK)
        return r;
    return called(PyObject_CallOneArg(ps->fallback, msg));
}
void poses_clear(Poses *ps) {
#define CLEAR_POSES(field) Py_CLEAR(ps->field);
    POSES_OBJECTS(CLEAR_POSES)
#undef CLEAR_POSES
    PyMem_Free(ps->slots);
    ps->slots = NULL;
    ps->nslots = 0;
}

PyObject *log_poses(Log *log, PyObject *args, PyObject *kwds) {
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

PyObject *log_pose_template(Log *log, PyObject *args, PyObject *kwds) {
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
/* fill_poses(template, slots, pose rows (a contiguous float32 or float64 buffer), grid, turn_grid) -> the
 * template with the poses written (as the log's pose template writes them: `write_poses`) */
PyObject *fill_poses(PyObject *self, PyObject *args) {
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
