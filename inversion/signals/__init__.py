"""Signals in time: the desired trajectory (:mod:`.trajectory`) and piecewise Chebyshev series (:mod:`.chebyshev`)."""
