"""Root test configuration: the compiled-model cache used by tests and notebooks.

Set before any test or notebook kernel starts, so that they share one cache (entries are
keyed by a content hash, so a stale entry is never used). ``SFLM_CACHE_DIR`` from the
environment wins.
"""

from __future__ import annotations

import os
from pathlib import Path

os.environ.setdefault("SFLM_CACHE_DIR", str(Path(__file__).parent / ".pytest_cache" / "sflm-models"))


def pytest_addoption(parser) -> None:  # type: ignore[no-untyped-def]
    parser.addoption(
        "--update-golden",
        action="store_true",
        help="rewrite the committed generated sources under generated/ instead of comparing",
    )
