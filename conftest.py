"""Root test configuration: the compiled-model cache and the thread pools of tests and notebooks.

Set before any test or notebook kernel starts, so that they share one cache (entries are
keyed by a content hash, so a stale entry is never used). ``SFLM_CACHE_DIR`` from the
environment wins.
"""

from __future__ import annotations

import os
from pathlib import Path

os.environ.setdefault("SFLM_CACHE_DIR", str(Path(__file__).parent / ".pytest_cache" / "sflm-models"))

# One BLAS thread for the tests, their subprocesses and notebook kernels: the products are
# small and the machines have two cores, where pools of threads spin (measured: the suite
# 326 s with the default pools, 85 s with one thread).
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")


def pytest_configure(config) -> None:  # type: ignore[no-untyped-def]
    """Hold the pools already loaded (NumPy's, imported by a plugin) to one thread as well."""
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)


def pytest_addoption(parser) -> None:  # type: ignore[no-untyped-def]
    parser.addoption(
        "--update-golden",
        action="store_true",
        help="rewrite the committed generated sources under generated/ instead of comparing",
    )
    parser.addoption(
        "--update-references",
        action="store_true",
        help="rewrite tests/data/reference-runs/ (today's outputs of the reference commands) instead of comparing",
    )
