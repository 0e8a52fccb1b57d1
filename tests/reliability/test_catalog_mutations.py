"""Every value of real catalog files, mutated: the loader refuses each mutation with a SpecError naming the
file (or loads it), never another exception. Covers the task files' objects, parts, open shapes, links and
key rows, and a hand file's fingers, actuators, tactile and real_model blocks: each is checked by the
schema layer (sim/schema) before anything is built from it."""

from __future__ import annotations

import copy
import itertools
from pathlib import Path

import pytest
import yaml

from sim.embodiment.description import read_hand_file
from sim.errors import SpecError
from sim.registry import catalog_path, load_yaml
from sim.tasks import parse_task

WRONG = ("x", {"zz": 1}, [], -1e9)      # a word, a mapping, an empty list, a huge negative number
UNKNOWN_KEY = "zz_unknown"


def _places(node, path=()):
    """(path, node) of every mapping, list and leaf below ``node``."""
    yield path, node
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, child in items:
        yield from _places(child, (*path, key))


def _set(raw, path, value):
    out = copy.deepcopy(raw)
    parent = out
    for key in path[:-1]:
        parent = parent[key]
    parent[path[-1]] = value
    return out


def _mutations(raw, skip=()):
    """(what, mutated file) for an unknown key in every mapping and each wrong value at every place."""
    for path, node in _places(raw):
        if any(path[:len(s)] == s for s in skip):
            continue
        if isinstance(node, dict):
            yield f"{path} + {UNKNOWN_KEY}", _set(raw, (*path, UNKNOWN_KEY), 1) if path else {**raw, UNKNOWN_KEY: 1}
        if path:
            for value in WRONG:
                if value != node:
                    yield f"{path} = {value!r}", _set(raw, path, value)


def _check(load, raw, path: Path, skip=(), every: int = 1) -> tuple[int, int]:
    """Refused and accepted counts over every ``every``-th mutation (a fixed subset of a large file)."""
    refused = accepted = 0
    for what, mutated in itertools.islice(_mutations(raw, skip), 0, None, every):
        path.write_text(yaml.safe_dump(mutated, sort_keys=False))
        try:
            load(path)
        except SpecError as err:
            assert str(path) in str(err), f"{what}: the error does not name the file: {err}"
            refused += 1
        except Exception as err:    # noqa: BLE001 -- the point of the test
            pytest.fail(f"{what}: {type(err).__name__} instead of a SpecError: {err}")
        else:
            assert not what.endswith(UNKNOWN_KEY), f"{what}: an unknown key was accepted"
            accepted += 1
    return refused, accepted


@pytest.mark.parametrize("task", ["trash_disposal", "bimanual_piano_melody"])
def test_every_mutation_of_a_task_file_is_refused_or_loads(tmp_path, task):
    """The metrics block is the evaluator's (its own compiler and tests); the demo plan is mutated elsewhere."""
    raw = load_yaml(catalog_path("tasks", task))
    refused, accepted = _check(lambda p: parse_task(load_yaml(p), p), raw, tmp_path / f"{task}.yaml",
                               skip=(("metrics",), ("demo_plan",)))
    assert refused > 3 * accepted


def test_mutations_of_a_hand_file_are_refused_or_load(tmp_path):
    """The Shadow hand file (3,669 mutations; every 11th, for CI's time)."""
    raw = load_yaml(catalog_path("hands", "shadow"))
    refused, accepted = _check(read_hand_file, raw, tmp_path / "shadow.yaml", every=11)
    assert refused > 3 * accepted
