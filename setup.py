"""Only the optional C accelerator of the CDR encoder; everything else is in pyproject.toml.

The extension is optional: where it cannot be compiled (no C compiler), simatch uses its pure-Python
encoders, which write the same bytes.
"""

from setuptools import Extension, setup

setup(ext_modules=[Extension("simatch.msgs._cdr_accel", ["src/simatch/msgs/_cdr_accel.c"], optional=True)])
