"""The loaded model functions: compiled C behind ``casadi.external``, or in-process CasADi.

:class:`ModelFunctions` is what a :class:`~modelgen.model.Model` and the numeric layer
call. Single evaluations go through a reusable CasADi buffer (no conversion to ``DM``);
time series go through ``Function.map`` over chunks, in one call.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike, NDArray

from .abi import BATCH_CHUNK, ROLES, symbol
from .errors import CodegenError

__all__ = ["ModelFunctions", "FastCall", "load_external", "load_serialized"]

FloatArray = NDArray[np.float64]

#: Samples per mapped call in batch evaluation.
_MAP_BLOCK = 32768

_P_ONLY = tuple(role for role, (ins, _outs) in ROLES.items() if ins == ("p",))


def _bind_arg(buffer: Any, i: int, array: FloatArray) -> None:
    """Point input ``i`` of a CasADi function buffer at ``array`` (contiguous float64, kept alive by the caller)."""
    buffer.set_arg(i, array.data)


def _bind_res(buffer: Any, i: int, array: FloatArray) -> None:
    """Point output ``i`` of a CasADi function buffer at ``array``."""
    buffer.set_res(i, array.data)


class FastCall:
    """Repeated calls of one CasADi function with preallocated buffers.

    Parameters
    ----------
    function : casadi.Function
        Dense inputs and outputs.
    """

    def __init__(self, function: ca.Function):
        self.function = function
        self._inputs = [np.zeros(function.nnz_in(i)) for i in range(function.n_in())]
        self._outputs = [np.zeros(function.nnz_out(i)) for i in range(function.n_out())]
        self._shapes = [function.size_out(i) for i in range(function.n_out())]
        self._buffer, self._call = function.buffer()
        for i, a in enumerate(self._inputs):
            _bind_arg(self._buffer, i, a)
        for i, a in enumerate(self._outputs):
            _bind_res(self._buffer, i, a)

    def __call__(self, *args: ArrayLike | float) -> list[FloatArray]:
        """Evaluate; returns copies of the outputs, reshaped (column-major) to their sizes."""
        for dest, value in zip(self._inputs, args):
            dest[:] = np.ravel(value, order="F")
        self._call()
        return [out.reshape(shape, order="F").copy() for out, shape in zip(self._outputs, self._shapes)]


class ModelFunctions:
    """The generated functions of an ``n``-mode model.

    Parameters
    ----------
    n : int
        Number of assumed modes.
    functions : Mapping[str, casadi.Function]
        Role -> function (``sflm_<role>``), compiled (external) or in-process.
    compiled : bool
        Whether the functions run compiled C.
    manifest : dict
        The manifest of the cache entry they were loaded from.
    folder : Path, optional
        That cache entry.

    Attributes
    ----------
    cache_hit : bool
        Set by the cache: whether the entry existed already.
    """

    def __init__(
        self,
        n: int,
        functions: Mapping[str, ca.Function],
        compiled: bool,
        manifest: dict[str, Any],
        folder: Path | None = None,
    ):
        self.n = n
        self.functions = dict(functions)
        self.compiled = compiled
        self.manifest = manifest
        self.folder = folder
        self.cache_hit = False
        self._fast: dict[str, FastCall] = {}
        self._maps: dict[tuple[str, int], ca.Function] = {}

    def __repr__(self) -> str:
        kind = "compiled" if self.compiled else "in-process CasADi"
        return f"ModelFunctions(n={self.n}, {kind}, {self.folder})"

    def call(self, role: str, *args: ArrayLike | float) -> list[FloatArray]:
        """Evaluate one role once; outputs as 2-D arrays of their sizes.

        Parameters
        ----------
        role : str
            One of :data:`~modelgen.abi.ROLES`.
        """
        fast = self._fast.get(role)
        if fast is None:
            fast = self._fast[role] = FastCall(self.functions[role])
        return fast(*args)

    def matrices(self, p: ArrayLike) -> dict[str, FloatArray]:
        """Every role that depends on ``p`` only, evaluated at ``p``.

        Parameters
        ----------
        p : ArrayLike
            The parameter vector (order of :func:`~modelgen.parameters.parameter_names`).

        Returns
        -------
        dict
            ``M, K, C, A, AI, T, Tinv`` as 2-D arrays; ``D, H, B, C_out, CA2, BI`` as 1-D;
            ``CAB`` as a 0-d array.
        """
        out: dict[str, FloatArray] = {}
        for role in _P_ONLY:
            (value,) = self.call(role, p)
            if role in ("D", "H", "B", "C_out", "CA2", "BI"):
                value = value.reshape(-1)
            elif role == "CAB":
                value = value.reshape(())
            out[role] = value
        return out

    def inverse_torque(self, p: ArrayLike, X: ArrayLike, yddot: ArrayLike) -> FloatArray:
        """Eq. (12) over a time series, in batched compiled calls.

        Parameters
        ----------
        p : array_like
            Parameter vector.
        X : array_like, shape (N, 2(n+1))
            States, one row per sample.
        yddot : array_like, shape (N,)
            Output accelerations.

        Returns
        -------
        ndarray, shape (N,)
        """
        X = np.asarray(X, dtype=float)
        y = np.asarray(yddot, dtype=float).reshape(-1)
        N = y.size
        if X.shape != (N, 2 * (self.n + 1)):
            raise ValueError(f"X must have shape ({N}, {2 * (self.n + 1)}), got {X.shape}")
        chunks = -(-N // BATCH_CHUNK)
        padded = chunks * BATCH_CHUNK
        Xb = np.zeros((padded, X.shape[1]))
        Xb[:N] = X  # row-major (samples x states) is CasADi's column-major (states x samples)
        yb = np.zeros(padded)
        yb[:N] = y
        (tau,) = self._blocked("inverse_torque_batch", p, [Xb, yb], chunks, BATCH_CHUNK)
        return tau[:N]

    def map(self, role: str, p: ArrayLike, *columns: ArrayLike) -> list[FloatArray]:
        """Evaluate a role at ``N`` samples with ``Function.map``.

        Parameters
        ----------
        role : str
            A role whose first input is ``p``.
        p : array_like
            Parameter vector.
        *columns : array_like
            The other inputs, each of shape ``(N, size)`` (or ``(N,)`` for scalars).

        Returns
        -------
        list of ndarray
            Each output as ``(N, size)`` (matrices flattened column-major).
        """
        arrays = [np.ascontiguousarray(np.asarray(c, dtype=float).reshape(np.shape(c)[0], -1)) for c in columns]
        N = arrays[0].shape[0] if arrays else 1
        return [o.reshape(N, -1) for o in self._blocked(role, p, arrays, N, 1)]

    def _blocked(
        self, role: str, p: ArrayLike, arrays: list[FloatArray], calls: int, samples_per_call: int
    ) -> list[FloatArray]:
        """Run ``calls`` evaluations of a role over consecutive rows of ``arrays``.

        Uses ``Function.map`` over blocks of at most :data:`_MAP_BLOCK` samples (CasADi's
        set-up cost of a map grows with its length), one buffer call per block.
        """
        f = self.functions[role]
        p_arr = np.ascontiguousarray(p, dtype=float)
        rows = calls * samples_per_call
        outs = [np.zeros((rows, f.nnz_out(i) // samples_per_call)) for i in range(f.n_out())]
        per_block = max(1, _MAP_BLOCK // samples_per_call)
        for start in range(0, calls, per_block):
            count = min(per_block, calls - start)
            buf, call = self._mapped(role, count).buffer()
            lo, hi = start * samples_per_call, (start + count) * samples_per_call
            views = [a[lo:hi] for a in arrays]  # contiguous row blocks
            _bind_arg(buf, 0, p_arr)
            for i, v in enumerate(views, start=1):
                _bind_arg(buf, i, v)
            for i, o in enumerate(outs):
                _bind_res(buf, i, o[lo:hi])
            call()
        return [o.reshape(-1) if o.shape[1] == 1 else o for o in outs]

    def _mapped(self, role: str, count: int) -> ca.Function:
        """``Function.map`` of a role over ``count`` calls with ``p`` shared (kept for reuse)."""
        key = (role, count)
        fn = self._maps.get(key)
        if fn is None:
            if len(self._maps) > 32:
                self._maps.clear()
            f = self.functions[role]
            fn = self._maps[key] = f.map(f"{f.name()}_map{count}", "serial", count, [0], [])
        return fn


def load_external(library: Path, n: int, manifest: dict[str, Any], folder: Path) -> ModelFunctions:
    """Load every role from a compiled library (``casadi.external``).

    Parameters
    ----------
    library : Path
        The compiled shared library.
    n : int
        Number of assumed modes.
    manifest : dict[str, Any]
        The cache entry's manifest.
    folder : Path
        The cache entry's folder.

    Raises
    ------
    CodegenError
        If the library cannot be loaded or lacks a function.
    """
    functions = {}
    for role in ROLES:
        try:
            functions[role] = ca.external(symbol(role), str(library))
        except RuntimeError as exc:
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else "unknown error"
            raise CodegenError(f"cannot load {symbol(role)} from {library}: {first}") from None
    return ModelFunctions(n, functions, True, manifest, folder)


def load_serialized(path: Path, n: int, manifest: dict[str, Any], folder: Path | None) -> ModelFunctions:
    """Load the serialised in-process functions (no compiler).

    Parameters
    ----------
    path : Path
        The serialised functions' file.
    n : int
        Number of assumed modes.
    manifest : dict[str, Any]
        The cache entry's manifest.
    folder : Path | None
        The cache entry's folder, if any.
    """
    try:
        unpacked = ca.FileDeserializer(str(path)).unpack()
    except RuntimeError as exc:
        raise CodegenError(f"cannot read serialised functions {path}: {str(exc).strip()[:200]}") from None
    functions = {f.name().removeprefix("sflm_"): f for f in unpacked}
    missing = [r for r in ROLES if r not in functions]
    if missing:
        raise CodegenError(f"serialised functions {path} lack {', '.join(missing)}")
    return ModelFunctions(n, functions, False, manifest, folder)
