"""The stability suite's artifact starts empty each session, so it holds this run's figures only."""

import pytest

from stability.probes import ARTIFACT


@pytest.fixture(scope="session", autouse=True)
def fresh_artifact():
    ARTIFACT.unlink(missing_ok=True)
    yield
