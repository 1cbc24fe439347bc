"""The quick loop: `pytest -m "not slow"` runs the cheap cases of each property, `make test` every case.
A property checked over many scenes or seeds keeps its cheapest ones quick and marks the rest slow."""

from __future__ import annotations

import pytest

slow = pytest.mark.slow
# Cases of a property that make test already checks on others of its kind, each minutes long: run by
# `make test-exhaustive` (their measured errors in the cases' comments), not by make test or CI, whose time they
# would take past its budget.
exhaustive = pytest.mark.exhaustive


def quick_cases(values, quick, ids=None) -> list:
    """Parameters for pytest.mark.parametrize: each of ``values`` (with its id from ``ids``), marked slow
    unless it, or its id, is in ``quick``."""
    ids = list(ids) if ids is not None else [None] * len(values)
    return [pytest.param(v, id=i, marks=() if (i in quick if i is not None else v in quick) else slow)
            for v, i in zip(values, ids)]
