"""Only the optional C extensions of the messages; everything else is in pyproject.toml.

Both are optional: where they cannot be compiled (no C compiler), simatch uses its pure-Python encoders,
which write the same bytes, and builds messages by their classes (the same messages).
"""

from setuptools import Extension, setup

setup(
    ext_modules=[
        Extension("simatch.msgs._cdr_accel", ["src/simatch/msgs/_cdr_accel.c"], optional=True),
        Extension("simatch.msgs._positional", ["src/simatch/msgs/_positional.c"], optional=True),
    ]
)
