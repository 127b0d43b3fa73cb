"""inversion: piece-wise causal inversion by output redefinition (the numeric layer).

Consumes a loaded :class:`modelgen.Model` (compiled functions) and never imports SymPy.
"""

from __future__ import annotations

__all__: list[str] = []
