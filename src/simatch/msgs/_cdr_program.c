/* The codec's programs (see `_cdr_accel.c`): a program tuple compiled once into C structures (`compile`,
 * `compile_ops`), held by Python as a capsule; and how a message class holds its fields (`learn`), where the
 * encoder reads them and the decoder fills them.
 *
 * What this unit reads by offset: a class's member descriptors (`slot_offset`), guarded by its version tag.
 */
#include "_cdr_accel.h"

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
void learn(Program *program, PyTypeObject *tp) {
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
Program *compile_ops(PyObject *ops, Program *(*compile)(PyObject *)) {
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
PyObject *capsule_of(Program *p) {
    if (p == NULL)
        return NULL;
    PyObject *capsule = PyCapsule_New(p, PROGRAM_CAPSULE, program_capsule_free);
    if (capsule == NULL)
        free_program(p);
    return capsule;
}

/* compile(program tuple) -> the compiled program (a capsule) that `encode` and `Log` take */
PyObject *compile(PyObject *self, PyObject *program) {
    return capsule_of(compile_tuple(program));
}

Program *program_of(PyObject *capsule) {
    return PyCapsule_GetPointer(capsule, PROGRAM_CAPSULE);    /* NULL, with an exception, if it is not one */
}
