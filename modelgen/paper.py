"""Numbers reported in the paper, for side-by-side comparison (never used in computations).

Source: "Piece-wise causal inversion by output redefinition for a flexible link
manipulator", Trans. CSME 33(2), 2009 (``shared/paper``), sections 7 and 8.
"""

from __future__ import annotations

from typing import Any

__all__ = ["PAPER", "TRUNCATION_NOTE"]

PAPER: dict[str, dict[str, Any]] = {
    "paper-sim": {
        "where": "section 7, Table 1 (2 modes)",
        "zeros": [61.25, -61.25, 54.34j, -54.34j],
        "n_unstable": 3,
    },
    "paper-exp": {
        "where": "section 8 (1 mode)",
        "zeros": [212.0, -212.0],
        "n_unstable": 1,
        "second_frequency_hz": 54.0,
        "steady_tip_error_pd_m": 0.010,
        "steady_tip_error_two_stage_m": 0.001,
    },
}

TRUNCATION_NOTE = (
    "The paper's mode shapes come from a reference not at hand and its zeros differ from "
    "ours by a few percent; assumed-mode truncation moves zeros too (see --convergence): "
    "the structure (which zeros are real, which imaginary, how many unstable) is what "
    "must agree."
)
