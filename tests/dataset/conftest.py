"""The batch tests' environment: Ray loopback-only and quiet, set before anything imports it, a stall
limit so that a hung worker fails its test rather than CI, and warprt's source importable in the
processes that multiprocessing and Ray start."""

import os

SRC = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "src")

os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")
os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
os.environ.setdefault("WARPRT_BATCH_STALL_TIMEOUT", "120")
os.environ.setdefault("WARPRT_RAY_READY_TIMEOUT", "120")
os.environ["PYTHONPATH"] = os.pathsep.join([SRC] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p])
