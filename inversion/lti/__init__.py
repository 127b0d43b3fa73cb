"""Linear time-invariant dynamics: the link's normal form (:mod:`.system`), a generic system's (:mod:`.linear_system`),
the internal and zero dynamics, exponentials, exact discretisation and the causal limit of a move."""
