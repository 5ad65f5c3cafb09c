import os

import jax

# The command's persistent compilation cache stays out of the tests (tests/test_cli.py
# checks it with its own folder).
os.environ.setdefault("MAGDESIGN_NO_CACHE", "1")
jax.config.update("jax_enable_x64", True)
