"""The other methods a result is compared with or falls back to: polynomial redefinition, stable
inversion, the optimal-control feedforward and input shaping."""
