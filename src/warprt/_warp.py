"""Warp, imported with warprt's settings, and its one-time start-up: every module that runs
kernels imports it from here.

Warp's start-up banner and module-load lines are noise for a renderer's users.
"""

import atexit
import os
import shutil
import tempfile

import warp as wp

from .diagnostics import emit, native_stderr

wp.config.quiet = True
wp.config.log_level = wp.LOG_WARNING

_initialized = False


def init_warp():
    """Initialize Warp once. Its native layer warns on stderr when a machine has no CUDA driver,
    which is the normal case for this CPU renderer: that one line is dropped, anything else becomes
    a warning line."""
    global _initialized
    if _initialized:
        return
    _ensure_kernel_cache()
    with native_stderr() as native:
        wp.init()
    for line in native.text.splitlines():
        if line.strip() and "Could not find or load the NVIDIA CUDA driver" not in line:
            emit(f"Warp: {line.strip()}")
    _initialized = True


def warp_started() -> bool:
    """Whether this process has started Warp's runtime (init_warp, or a wp.init() of its own): such a
    process must not fork workers. Where Warp's internals have moved and it cannot tell, it says yes."""
    if _initialized:
        return True
    try:
        from warp._src import context
    except ImportError:
        return True
    return getattr(context, "runtime", True) is not None


def kernel_cache_dir() -> str:
    """Where Warp will cache compiled kernels: warp.config.kernel_cache_dir if set, else
    WARP_CACHE_PATH, else the user's cache folder (~/.cache/warp/<version> on Linux)."""
    if wp.config.kernel_cache_dir:
        return wp.config.kernel_cache_dir
    if os.environ.get("WARP_CACHE_PATH"):
        return os.path.realpath(os.environ["WARP_CACHE_PATH"])
    try:
        from warp._src.thirdparty import appdirs
    except ImportError:  # Warp before 1.10
        from warp.thirdparty import appdirs
    return appdirs.user_cache_dir(appname="warp", appauthor="NVIDIA", version=wp.config.version)


_fallback_cache = None


def _ensure_kernel_cache():
    """Read-only containers and CI sandboxes have no writable home, and Warp would fail on its first
    kernel. There the kernels are cached in a fresh private temporary folder, compiled again each run
    and removed at exit (a fixed shared folder would let another user plant compiled code)."""
    global _fallback_cache
    where = kernel_cache_dir()
    try:
        os.makedirs(where, exist_ok=True)
        # Permission bits do not tell (root ignores them; a read-only mount does not show in them).
        fd, probe = tempfile.mkstemp(prefix=".warprt-probe-", dir=where)
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        _fallback_cache = tempfile.mkdtemp(prefix="warprt-kernels-")
        wp.config.kernel_cache_dir = _fallback_cache
        atexit.register(remove_fallback_cache)
        emit(f"Warp's kernel cache {where} is not writable ({e.strerror or e}); caching kernels in "
             f"{_fallback_cache} for this run (set WARP_CACHE_PATH to a writable folder to keep them)")


def remove_fallback_cache():
    """Remove the temporary kernel cache, if this process made one (the command line calls this:
    it exits without running atexit handlers)."""
    global _fallback_cache
    if _fallback_cache is not None:
        shutil.rmtree(_fallback_cache, ignore_errors=True)
        _fallback_cache = None
