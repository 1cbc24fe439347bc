"""Every test here runs twice: with traced and with hybrid first hits (tests/conftest.py)."""

import pytest


@pytest.fixture(autouse=True)
def _both_primaries(both_primaries):
    """Every test here runs with traced and with hybrid first hits (tests/conftest.py)."""
