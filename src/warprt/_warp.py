"""Warp, imported with warprt's settings, and its one-time start-up: every module that runs
kernels imports it from here.

Warp's start-up banner and module-load lines are noise for a renderer's users.
"""

import os
import sys
import tempfile

import warp as wp

wp.config.quiet = True
wp.config.log_level = wp.LOG_WARNING

_initialized = False


def init_warp():
    """Initialize Warp once. Its native layer warns on stderr when a machine has no CUDA driver,
    which is the normal case for this CPU renderer: that one line is dropped, anything else kept."""
    global _initialized
    if _initialized:
        return
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as captured:
        os.dup2(captured.fileno(), 2)
        try:
            wp.init()
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        captured.seek(0)
        for line in captured.read().decode(errors="replace").splitlines():
            if "Could not find or load the NVIDIA CUDA driver" not in line:
                print(line, file=sys.stderr)
    _initialized = True
