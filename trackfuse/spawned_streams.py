"""The streams ``trial.common.spawn(children)`` of a batch of trials, drawn through one shared
generator instead of one ``Generator`` per stream (``docs/runner.md``, "Seeding").

Each child's PCG64 state is computed as numpy computes it (``SeedSequence`` entropy
assembly, hash mixing and ``generate_state``, then PCG64's seeding of its 128-bit state and
increment), for all trials at once; ``with stream as rng:`` sets the shared generator to the
child's state, once: each stream is visited once. The draws are bit for bit those of
``trial.common.spawn(children)`` (``tests/test_spawned_streams.py``), at a few microseconds
per trial instead of about seventy.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from trackfuse.seeding import COMMON_DOMAIN, TrialStreams

_POOL = 4  # SeedSequence's default pool size, 32-bit words
_INIT_A, _MULT_A, _INIT_B, _MULT_B = 0x43B0D7E5, 0x931E8875, 0x8B51F9DD, 0x58F38DED
_MIX_L, _MIX_R = 0xCA01F9DD, 0x4973F715
_MASK32, _MASK128 = (1 << 32) - 1, (1 << 128) - 1
_PCG_MULT = 0x2360ED051FC65DA44385DF649FCCF645  # PCG64's 128-bit LCG multiplier


class SharedStream:
    """One spawned stream, kept as its four 64-bit seed words until its one visit: ``with
    stream as rng:`` sets the generator it shares with other streams to the stream's PCG64
    state. Nothing is read back on leaving (that costs about a microsecond); a second visit
    raises."""

    __slots__ = ("_generator", "_seed_words", "_spent")

    def __init__(self, generator: np.random.Generator, seed_words: list[int]):
        self._generator, self._seed_words, self._spent = generator, seed_words, False

    def __enter__(self) -> np.random.Generator:
        if self._spent:
            raise RuntimeError("a shared stream is visited once")
        self._spent = True
        self._generator.bit_generator.state = _pcg64_state(self._seed_words)
        return self._generator

    def __exit__(self, *exc: object) -> None:
        return None


def spawn_shared(streams: Sequence[TrialStreams], children: int
                 ) -> list[tuple[SharedStream, ...]]:
    """For each trial, ``children`` streams equal to ``trial.common.spawn(children)`` of a
    common stream not yet used, each to be visited once; they share one generator, so use
    them from one thread."""
    if any("common" in vars(trial) for trial in streams):
        raise ValueError("spawn_shared needs trials whose common stream is still unused")
    generator = np.random.Generator(np.random.PCG64(0))
    words = _child_seed_words([(t.seed, t.trial) for t in streams], children)
    return [tuple(SharedStream(generator, child) for child in trial) for trial in words]


def _child_seed_words(keys: Sequence[tuple[int, int]], children: int
                      ) -> list[list[list[int]]]:
    """``generate_state(4, uint64)`` of each of
    ``SeedSequence(seed, spawn_key=(COMMON_DOMAIN, trial)).spawn(children)`` for each
    ``(seed, trial)`` of ``keys``."""
    runs = {seed: _run_entropy(seed) for seed in {seed for seed, _ in keys}}
    domain = _words(COMMON_DOMAIN)
    parents = [[*runs[seed], *domain, *_words(trial)] for seed, trial in keys]
    seeds: list[list[int]] = [[]] * (len(parents) * children)
    for width in {len(row) for row in parents}:  # a row's width depends on its ints' size
        chosen = [i for i, row in enumerate(parents) if len(row) == width]
        rows = np.repeat(np.array([parents[i] for i in chosen], dtype=np.uint32), children,
                         axis=0)  # each parent's children, then each child's number
        entropy = np.column_stack([rows, np.tile(np.arange(children, dtype=np.uint32),
                                                 len(chosen))])
        child_rows = (i * children + child for i in chosen for child in range(children))
        for i, words in zip(child_rows, _seed_words(_mixed_pool(entropy)).tolist(),
                            strict=True):
            seeds[i] = words
    return [seeds[i:i + children] for i in range(0, len(seeds), children)]


def _words(value: int) -> list[int]:
    """``value`` >= 0 as SeedSequence reads an int: 32-bit words, least significant first."""
    words = [value & _MASK32]
    while value := value >> 32:
        words.append(value & _MASK32)
    return words


def _run_entropy(seed: int) -> list[int]:
    """SeedSequence's words of ``seed`` before those of a spawn key: padded with zeros to the
    pool size (each key of the spawn key then adds its own words)."""
    run = _words(seed)
    return run + [0] * (_POOL - len(run))


def _hashmix(value: np.ndarray, hash_const: int) -> tuple[np.ndarray, int]:
    """One hash-mix step of (M,) uint32 words; returns them and the next hash constant."""
    value = value ^ np.uint32(hash_const)
    hash_const = (hash_const * _MULT_A) & _MASK32
    value = value * np.uint32(hash_const)
    return value ^ (value >> np.uint32(16)), hash_const


def _mix(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Combine two (M,) uint32 words."""
    result = np.uint32(_MIX_L) * x - np.uint32(_MIX_R) * y
    return result ^ (result >> np.uint32(16))


def _mixed_pool(entropy: np.ndarray) -> np.ndarray:
    """SeedSequence's pool ``(M, 4)`` uint32 of entropy rows ``(M, L)`` uint32, L >= 4."""
    hash_const, pool = _INIT_A, []
    for i in range(_POOL):
        word, hash_const = _hashmix(entropy[:, i], hash_const)
        pool.append(word)
    for src in range(_POOL):
        for dst in range(_POOL):
            if src != dst:
                word, hash_const = _hashmix(pool[src], hash_const)
                pool[dst] = _mix(pool[dst], word)
    for src in range(_POOL, entropy.shape[1]):
        for dst in range(_POOL):
            word, hash_const = _hashmix(entropy[:, src], hash_const)
            pool[dst] = _mix(pool[dst], word)
    return np.stack(pool, axis=1)


def _seed_words(pool: np.ndarray) -> np.ndarray:
    """``generate_state(4, uint64)`` ``(M, 4)`` uint64 of pools ``(M, 4)`` uint32."""
    hash_const, out = _INIT_B, []
    for i in range(8):
        value = pool[:, i % _POOL] ^ np.uint32(hash_const)
        hash_const = (hash_const * _MULT_B) & _MASK32
        value = value * np.uint32(hash_const)
        out.append(value ^ (value >> np.uint32(16)))
    words = np.stack(out, axis=1).astype(np.uint64)
    return words[:, 0::2] | (words[:, 1::2] << np.uint64(32))


def _pcg64_state(words: list[int]) -> dict[str, Any]:
    """``PCG64``'s state after seeding with ``generate_state(4, uint64)`` words: 128-bit
    initial state (words 0, 1) and stream (words 2, 3), high word first."""
    initstate, initseq = (words[0] << 64) | words[1], (words[2] << 64) | words[3]
    inc = ((initseq << 1) | 1) & _MASK128
    state = (((inc + initstate) * _PCG_MULT) + inc) & _MASK128
    return {"bit_generator": "PCG64", "state": {"state": state, "inc": inc},
            "has_uint32": 0, "uinteger": 0}
