"""Studies over methods and plants: the comparison of methods (:mod:`.compare`) and robustness to the
plant's parameters (:mod:`.robustness`)."""
