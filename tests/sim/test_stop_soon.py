"""A signal during a run (Ctrl-C, SIGTERM) stops it at a step boundary, never inside a step.

A handler that raised wherever the signal landed could interrupt a node half-way through its step or a
compiled kernel's dispatch (seen once as a garbled ``SystemError`` from numba instead of a clean stop)."""

import os
import signal

import pytest

import simatch
from simatch import msgs
from simatch.bus import topics


def test_a_signal_in_the_middle_of_a_step_stops_the_run_at_the_next_step_boundary():
    with simatch.Simulation("msl_5v5", seed=0) as sim:
        chunk = round(0.1 / sim.dt)
        steps_seen = []

        def on_states(msg):  # runs inside a physics step
            steps_seen.append(int(msg.step))
            if msg.step == chunk + 3:
                os.kill(os.getpid(), signal.SIGINT)

        sim.bus.subscribe(topics.MODEL_STATES, msgs.ModelStates, on_states)
        with sim.stopping_on(signal.SIGINT, KeyboardInterrupt):
            with pytest.raises(KeyboardInterrupt):
                sim.run(seconds=5)
        # the step in which the signal came was finished, and so was the rest of its tenth of a second
        assert sim.simulator.step_index == 2 * chunk
        assert steps_seen[-1] == 2 * chunk - 1
        sim.run(seconds=0.1)  # the run can go on afterwards
        assert sim.simulator.step_index == 3 * chunk


def test_a_second_signal_raises_at_once_and_outside_a_run_the_signal_raises_as_usual():
    with simatch.Simulation("msl_5v5", seed=0) as sim:
        with sim.stopping_on(signal.SIGINT, KeyboardInterrupt):
            with pytest.raises(KeyboardInterrupt):
                os.kill(os.getpid(), signal.SIGINT)  # no run in progress

            def twice(msg):
                if msg.step in (5, 7):  # the impatient user presses twice
                    os.kill(os.getpid(), signal.SIGINT)

            sub = sim.bus.subscribe(topics.MODEL_STATES, msgs.ModelStates, twice)
            with pytest.raises(KeyboardInterrupt):
                sim.run(seconds=5)
            assert sim.simulator.step_index == 7  # raised inside step 7
            sub.close()
            before = sim.simulator.step_index
            sim.run(seconds=0.05)  # nothing left pending from the first signal
            assert sim.simulator.step_index == before + 10
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
