"""Shared test set-up: scenes are built from dicts shaped like the TOML file."""

import os

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")
