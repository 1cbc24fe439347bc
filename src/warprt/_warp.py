"""Warp, imported with warprt's settings: every module that runs kernels imports it from here.

Warp's start-up banner and module-load lines are noise for a renderer's users.
"""

import warp as wp

wp.config.quiet = True
wp.config.log_level = wp.LOG_WARNING
