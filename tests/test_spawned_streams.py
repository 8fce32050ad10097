"""Streams spawned through one shared generator draw what ``trial.common.spawn`` draws."""

from __future__ import annotations

from contextlib import nullcontext

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from trackfuse.seeding import batch_streams, trial_streams
from trackfuse.spawned_streams import SharedStream, spawn_shared


def drawing(stream: SharedStream | np.random.Generator):
    """``with drawing(stream) as rng:`` for a shared stream or a generator alike."""
    return stream if isinstance(stream, SharedStream) else nullcontext(stream)


def _draws(stream) -> np.ndarray:
    """Uniforms, normals, exponentials and uniforms again, in one visit to the stream."""
    with drawing(stream) as rng:
        return np.concatenate([rng.random(3), rng.standard_normal(5),
                               rng.standard_exponential(2), rng.random(4)])


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**140), trials=st.lists(st.integers(0, 2**40), min_size=1,
                                                     max_size=4),
       children=st.integers(1, 4), point=st.integers(0, 5))
def test_shared_streams_draw_the_spawned_generators_numbers(seed, trials, children, point):
    shared = spawn_shared([trial_streams(seed, point, t) for t in trials], children)
    for trial, streams in zip(trials, shared, strict=True):
        spawned = trial_streams(seed, point, trial).common.spawn(children)
        assert len(streams) == children
        for ours, numpy_s in zip(streams, spawned, strict=True):
            np.testing.assert_array_equal(_draws(ours), _draws(numpy_s))


def test_streams_of_one_batch_drawn_in_turns_draw_their_own_numbers():
    shared = spawn_shared(batch_streams(7, 0, range(3)), 2)
    spawned = [s.common.spawn(2) for s in batch_streams(7, 0, range(3))]
    # visited in another order than made, each once: the shared generator carries nothing over
    for ours, theirs in reversed(list(zip(shared, spawned, strict=True))):
        for a, b in reversed(list(zip(ours, theirs, strict=True))):
            with a as rng:
                np.testing.assert_array_equal(rng.random(out=np.empty(2)), b.random(2))


def test_a_used_common_stream_is_refused():
    streams = batch_streams(1, 0, range(2))
    streams[1].common.random()
    with pytest.raises(ValueError, match="still unused"):
        spawn_shared(streams, 3)


def test_a_shared_stream_refuses_a_second_visit():
    [(once,)] = spawn_shared(batch_streams(3, 0, range(1)), 1)
    [numpy_s] = batch_streams(3, 0, range(1))[0].common.spawn(1)
    with once as rng:
        np.testing.assert_array_equal(rng.random(4), numpy_s.random(4))
    with pytest.raises(RuntimeError, match="visited once"), once:
        pass
