"""What the compiled (numba) kernels of every subsystem share: calling a kernel's compiled version directly.

numba's dispatcher types every argument at every call to pick the compiled version (some 150-250 machine
instructions per argument: a third of the cost of a per-step kernel's call in the simulator, more than the
arithmetic of a robot's per-tick kernel with thirty arguments). A call site whose arguments always have the
same types can skip it with `entry`. Shared by the simulator (`simatch.sim.kernels`) and the strategies
(`simatch.strategy.nubot`), which may not import each other."""

from __future__ import annotations

import numba


def entry(kernel, *sample):
    """``kernel``'s compiled function for the types of ``sample`` (its arguments at the calls to come), to call
    without numba's dispatcher.

    For call sites whose arguments always have the sample's types: arrays taken once as views of fixed memory
    (the engine's), arrays made by the caller with a fixed dtype (C-contiguous, writable), plain ints, floats
    and bools. The function returned takes the arguments as they are: it does not check an array's dtype or
    layout, so anything else must call the kernel. Nothing is run here (the version is compiled, or loaded
    from the cache); without numba's compiler (NUMBA_DISABLE_JIT) it is the kernel itself."""
    compile_for = getattr(kernel, "compile", None)
    if compile_for is None:
        return kernel
    return compile_for(tuple(numba.typeof(a) for a in sample))
