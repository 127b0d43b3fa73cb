"""HPIPM, the Riccati-based interior point for chains of stages, through the library CasADi's wheel ships.

A chain programme (an optimal-control quadratic programme) over stages ``k = 0 .. N``::

    minimise    sum_k  1/2 [u; x]^T [[R, S], [S^T, Q]] [u; x] + r^T u + q^T x
    subject to  x_{k+1} = A_k x_k + B_k u_k + b_k
                lbu <= u_k[idxbu] <= ubu,   lbx <= x_k[idxbx] <= ubx
                lg <= C_k x_k + D_k u_k <= ug          (a side of +-inf: no such bound)

HPIPM (Frison and Diehl, 2020, https://github.com/giaf/hpipm) factorises its Newton systems stage by stage with a
Riccati recursion: the work is linear in the number of stages, where a general sparse solver's grows faster and
HiGHS's simplex and interior point took seconds to minutes on the same programmes (docs/method.md, "The chain
programmes"). CasADi's wheels carry the library (``libhpipm``, with BLASFEO beside it) for their ``conic("hpipm")``
plugin; that plugin's set-up is quadratic in the stages (13.8 s for 3 200 stages, 274 s for 12 800, measured), so this
module calls the library's own C interface through :mod:`ctypes` (its ``d_ocp_qp_*`` functions, the interface
HPIPM's own Python package uses), stage by stage: nothing is compiled, and the set-up is linear too.

The solve stops on HPIPM's iteration limit, never on a clock: the same programme gives the same answer on a free and on
a busy machine. Its status, iterations and residuals are returned; :class:`ChainSolution.solved` says whether they
meet the tolerances asked for.
"""

from __future__ import annotations

import ctypes
import glob
import math
import os
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
from numpy.typing import NDArray

from ..errors import InversionError

__all__ = ["Stage", "Block", "ChainSolution", "solve_chain", "available", "STATUS"]

FloatArray = NDArray[np.float64]
#: HPIPM's exit status (``enum hpipm_status``).
STATUS = {0: "solved", 1: "iteration limit reached", 2: "minimum step length reached", 3: "NaN in the solution",
          4: "inconsistent equality constraints"}
#: HPIPM's modes (``enum hpipm_mode``): the robust one, relative formulation.
_ROBUST = 3

_LIB: list[Any] = []


def _library() -> Any:
    """``libhpipm`` from CasADi's package folder, its functions typed (loaded once)."""
    if _LIB:
        return _LIB[0]
    import casadi  # lazy: keeps `import inversion` fast

    folder = os.path.dirname(casadi.__file__)
    found = sorted(glob.glob(os.path.join(folder, "libhpipm.*")) + glob.glob(os.path.join(folder, "hpipm*.dll")))
    if not found:
        raise InversionError(f"HPIPM was not found beside CasADi ({folder}): the chain programmes need CasADi >= 3.6.7 "
                             "from its wheels, which carry it")
    for blasfeo in sorted(glob.glob(os.path.join(folder, "libblasfeo.*"))):  # where the loader does not look beside it
        try:
            ctypes.CDLL(blasfeo, mode=ctypes.RTLD_GLOBAL)
            break
        except OSError:
            continue
    # every call holds the GIL (PyDLL): the setters and getters take a microsecond, tens of thousands a programme, and a
    # call that let it go would wait for it back behind a busy thread (the automatic choice's family, solved beside a
    # limit: 0.73 s became 1.72 s); the solve alone lets it go (CDLL's call), for the seconds it runs
    lib = ctypes.PyDLL(found[0])
    size = ctypes.c_size_t
    vp, ip, dp = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    for name, restype, argtypes in (
        ("d_ocp_qp_dim_strsize", size, []), ("d_ocp_qp_dim_memsize", size, [ip]), ("d_ocp_qp_dim_create", None, [ip, vp, vp]),
        ("d_ocp_qp_strsize", size, []), ("d_ocp_qp_memsize", size, [vp]), ("d_ocp_qp_create", None, [vp, vp, vp]),
        ("d_ocp_qp_sol_strsize", size, []), ("d_ocp_qp_sol_memsize", size, [vp]), ("d_ocp_qp_sol_create", None, [vp, vp, vp]),
        ("d_ocp_qp_ipm_arg_strsize", size, []), ("d_ocp_qp_ipm_arg_memsize", size, [vp]),
        ("d_ocp_qp_ipm_arg_create", None, [vp, vp, vp]), ("d_ocp_qp_ipm_arg_set_default", None, [ip, vp]),
        ("d_ocp_qp_ipm_ws_strsize", size, []), ("d_ocp_qp_ipm_ws_memsize", size, [vp, vp]),
        ("d_ocp_qp_ipm_ws_create", None, [vp, vp, vp, vp]), ("d_ocp_qp_ipm_solve", None, [vp, vp, vp, vp]),
        ("d_ocp_qp_set_all_zero", None, [vp]),
    ):
        function = getattr(lib, name)
        function.restype, function.argtypes = restype, argtypes
    for name in ("nx", "nu", "nbx", "nbu", "ng", "ns"):
        getattr(lib, f"d_ocp_qp_dim_set_{name}").argtypes = [ip, ip, vp]
    for name in ("A", "B", "b", "Q", "S", "R", "q", "r", "lbx", "ubx", "lbu", "ubu", "C", "D", "lg", "ug", "lg_mask", "ug_mask",
                 "idxbx", "idxbu", "lbx_mask", "ubx_mask", "lbu_mask", "ubu_mask"):
        getattr(lib, f"d_ocp_qp_set_{name}").argtypes = [ip, vp, vp]
    for name in ("x", "u", "pi", "lam_lg", "lam_ug"):
        getattr(lib, f"d_ocp_qp_sol_get_{name}").argtypes = [ip, vp, vp]
    for name in ("iter_max",):
        getattr(lib, f"d_ocp_qp_ipm_arg_set_{name}").argtypes = [ctypes.POINTER(ip), vp]
    for name in ("tol_stat", "tol_eq", "tol_ineq", "tol_comp", "reg_prim", "mu0"):
        getattr(lib, f"d_ocp_qp_ipm_arg_set_{name}").argtypes = [ctypes.POINTER(dp), vp]
    for name in ("status", "iter"):
        getattr(lib, f"d_ocp_qp_ipm_get_{name}").argtypes = [vp, ctypes.POINTER(ip)]
    for name in ("max_res_stat", "max_res_eq", "max_res_ineq", "max_res_comp", "obj"):
        getattr(lib, f"d_ocp_qp_ipm_get_{name}").argtypes = [vp, ctypes.POINTER(dp)]
    released = ctypes.CDLL(found[0]).d_ocp_qp_ipm_solve
    released.restype, released.argtypes = None, [vp, vp, vp, vp]
    setattr(lib, "d_ocp_qp_ipm_solve", released)  # (the attribute ctypes would make, made here)
    _LIB.append(lib)
    return lib


def available() -> bool:
    """Whether HPIPM can be loaded (CasADi's wheel carries it)."""
    try:
        _library()
    except (InversionError, OSError, AttributeError):
        return False
    return True


@dataclass
class Stage:
    """One stage of a chain programme, as arrays.

    Its data as arrays (shapes from ``nx``, ``nu`` and the next stage's ``nx``). Every field may be shared between stages
    (the same array object): the library copies it in.

    Attributes
    ----------
    nx, nu : int
        The stage's states and inputs.
    A, B, b
        The dynamics to the next stage, ``(nx', nx)``, ``(nx', nu)``, ``(nx',)`` (``None`` on the last stage).
    Q, S, R, q, r
        The cost, ``(nx, nx)``, ``(nu, nx)``, ``(nu, nu)``, ``(nx,)``, ``(nu,)`` (``None``: zero).
    C, D, lg, ug
        The general constraints, ``(ng, nx)``, ``(ng, nu)``, ``(ng,)``, ``(ng,)``; an infinite side is no bound.
    idxbu, lbu, ubu, idxbx, lbx, ubx
        Bounds on some inputs and states (their indices); an infinite side is no bound.
    """

    nx: int
    nu: int
    A: FloatArray | None = None
    B: FloatArray | None = None
    b: FloatArray | None = None
    Q: FloatArray | None = None
    S: FloatArray | None = None
    R: FloatArray | None = None
    q: FloatArray | None = None
    r: FloatArray | None = None
    C: FloatArray | None = None
    D: FloatArray | None = None
    lg: FloatArray | None = None
    ug: FloatArray | None = None
    idxbu: NDArray[np.int32] | None = None
    lbu: FloatArray | None = None
    ubu: FloatArray | None = None
    idxbx: NDArray[np.int32] | None = None
    lbx: FloatArray | None = None
    ubx: FloatArray | None = None

    @property
    def ng(self) -> int:
        return 0 if self.lg is None else int(np.size(self.lg))

    @property
    def nbu(self) -> int:
        return 0 if self.idxbu is None else int(np.size(self.idxbu))

    @property
    def nbx(self) -> int:
        return 0 if self.idxbx is None else int(np.size(self.idxbx))


@dataclass(frozen=True)
class ChainSolution:
    """What HPIPM returned.

    Attributes
    ----------
    x, u : list of ndarray
        Each stage's states and inputs.
    status : int
        HPIPM's exit status (:data:`STATUS`).
    iterations : int
        Its interior-point iterations.
    residuals : dict
        The largest residual of stationarity, of the equalities, of the inequalities and of complementarity
        (``stat``, ``eq``, ``ineq``, ``comp``), and the objective (``obj``).
    tolerance : float
        The tolerance the residuals were asked to meet.
    """

    x: list[FloatArray]
    u: list[FloatArray]
    status: int
    iterations: int
    residuals: dict[str, float] = field(default_factory=dict)
    tolerance: float = 0.0

    @property
    def solved(self) -> bool:
        """HPIPM's status is success (every residual within the tolerance)."""
        return self.status == 0

    def within(self, tolerance: float) -> bool:
        """Whether every residual is within ``tolerance``.

        Stationarity, the equalities, the inequalities and complementarity.

        Parameters
        ----------
        tolerance : float
            The largest residual accepted.
        """
        r = self.residuals
        return all(math.isfinite(r.get(k, math.nan)) and r[k] <= tolerance for k in ("stat", "eq", "ineq", "comp"))

    @property
    def message(self) -> str:
        """The status and the residuals in words."""
        r = self.residuals
        return (f"HPIPM: {STATUS.get(self.status, f'status {self.status}')} after {self.iterations} iterations (residuals: "
                f"stationarity {r.get('stat', math.nan):.1e}, equalities {r.get('eq', math.nan):.1e}, inequalities "
                f"{r.get('ineq', math.nan):.1e}, complementarity {r.get('comp', math.nan):.1e}; asked {self.tolerance:.0e})")


def _buffer(size: int) -> Any:
    """Zeroed memory of ``size`` bytes (at least one)."""
    return ctypes.create_string_buffer(max(int(size), 1))


@dataclass
class Block:
    """Stages that share their matrices; the vectors that vary by row.

    ``count`` consecutive stages with the fields of ``stage``, except those named in ``rows``: an array of shape
    ``(count, n)`` whose ``k``-th row is the ``k``-th stage's (the bounds of the rows of a move: each stage its target).
    Set in bulk: the stages of a block cost a few library calls each, no Python arrays.

    Attributes
    ----------
    stage : Stage
        The shared fields.
    count : int
        The stages.
    rows : dict of str to ndarray
        The fields that vary, stage by stage.
    """

    stage: Stage
    count: int
    rows: dict[str, FloatArray] = field(default_factory=dict)


def solve_chain(stages: Sequence[Stage | Block], *, iterations: int = 200, tolerance: float = 1e-10,
                regularisation: float | None = None) -> ChainSolution:
    """Solve a chain programme by HPIPM's interior point.

    The programme of the module docstring, stage by stage.

    Parameters
    ----------
    stages : sequence of Stage or Block
        ``N + 1`` stages in all; the last has no inputs.
    iterations : int
        HPIPM's iteration limit (the only one: no clock).
    tolerance : float
        HPIPM's tolerances on the residuals of stationarity, the equalities, the inequalities and complementarity (of
        the programme as given: scale it).
    regularisation : float, optional
        HPIPM's regularisation of the Newton systems' primal block (a linear programme's Hessian is zero).

    Returns
    -------
    ChainSolution
        Whether or not it is solved: the caller judges :attr:`ChainSolution.solved`.
    """
    lib = _library()
    blocks = [b if isinstance(b, Block) else Block(b, 1) for b in stages]
    shapes = [(b.stage.nx, b.stage.nu, b.stage.nbx, b.stage.nbu, b.stage.ng) for b in blocks for _ in range(b.count)]
    N = len(shapes) - 1
    if N < 1 or shapes[-1][1] != 0:
        raise ValueError("a chain needs two stages at least, the last without inputs")
    memory: list[Any] = []  # every buffer HPIPM's structures point into, alive until the solution is read

    def create(kind: str, *args: Any) -> Any:
        struct = _buffer(getattr(lib, f"d_ocp_qp{kind}_strsize")())
        mem = _buffer(getattr(lib, f"d_ocp_qp{kind}_memsize")(*args))
        memory.extend([struct, mem])
        return struct, mem

    dim, dim_mem = create("_dim", N)
    lib.d_ocp_qp_dim_create(N, dim, dim_mem)
    setters = [getattr(lib, f"d_ocp_qp_dim_set_{name}") for name in ("nx", "nu", "nbx", "nbu", "ng", "ns")]
    for k, shape in enumerate(shapes):
        for setter, value in zip(setters, (*shape, 0)):
            setter(k, value, dim)
    qp, qp_mem = create("", dim)
    lib.d_ocp_qp_create(dim, qp, qp_mem)
    lib.d_ocp_qp_set_all_zero(qp)
    memory.append(_set_blocks(lib, qp, blocks, N))
    sol, sol_mem = create("_sol", dim)
    lib.d_ocp_qp_sol_create(dim, sol, sol_mem)
    arg, arg_mem = create("_ipm_arg", dim)
    lib.d_ocp_qp_ipm_arg_create(dim, arg, arg_mem)
    _set_arguments(lib, arg, iterations, tolerance, regularisation)
    ws, ws_mem = create("_ipm_ws", dim, arg)
    lib.d_ocp_qp_ipm_ws_create(dim, arg, ws, ws_mem)
    lib.d_ocp_qp_ipm_solve(qp, sol, arg, ws)
    return _read(lib, ws, sol, shapes, tolerance)


#: The bounds HPIPM takes as value and mask pairs: (lower, upper, their index field, the setters' names).
_BOUNDS = (("lg", "ug", None), ("lbu", "ubu", "idxbu"), ("lbx", "ubx", "idxbx"))


def _set_blocks(lib: Any, qp: Any, blocks: Sequence[Block], N: int) -> list[Any]:
    """Copy each stage's data into HPIPM's programme (the arrays it was given, converted, are returned: kept alive).

    A field shared by a block's stages is converted once; a field that varies is one contiguous array, each stage
    pointed at its row. An infinite side of a bound is no bound: its value 0, its mask 0.
    """
    keep: list[Any] = []

    def table(value: Any, count: int, dtype: Any = np.float64) -> tuple[int, int]:
        """The address of ``value`` (a stage's field, or ``count`` rows of one) and the bytes from one row to the next."""
        array = np.ascontiguousarray(np.asarray(value, dtype=dtype))
        keep.append(array)
        return int(array.ctypes.data), (int(array.strides[0]) if count > 1 and array.ndim > 1 else 0)

    k0 = 0
    for block in blocks:
        st, count, rows = block.stage, block.count, block.rows
        last = k0 + count - 1 == N  # the block holds the last stage: no dynamics there
        fields: list[tuple[Any, int, int, bool]] = []  # (setter, address, step from row to row, a dynamics field)
        for name in ("A", "B", "b", "Q", "S", "R", "q", "r", "C", "D"):
            dynamics = name in ("A", "B", "b")
            value = rows.get(name, getattr(st, name))
            if value is None:
                if dynamics and not (last and count == 1):
                    raise ValueError(f"stage {k0} has no {name}")
                continue
            if name in rows:
                address, step = table(value, count)
            else:  # a matrix is column-major for the library
                array = np.asfortranarray(np.asarray(value, dtype=np.float64))
                keep.append(array)
                address, step = int(array.ctypes.data), 0
            fields.append((getattr(lib, f"d_ocp_qp_set_{name}"), address, step, dynamics))
        for lower, upper, index in _BOUNDS:
            shared_lo, shared_hi = getattr(st, lower), getattr(st, upper)
            if shared_lo is None and lower not in rows:
                continue
            varying = lower in rows or upper in rows
            if varying:
                lo = np.asarray(rows[lower] if lower in rows else np.broadcast_to(shared_lo, (count, np.size(shared_lo))), dtype=float)
                hi = np.asarray(rows[upper] if upper in rows else np.broadcast_to(shared_hi, lo.shape), dtype=float)
            else:
                lo, hi = np.asarray(shared_lo, dtype=float), np.asarray(shared_hi, dtype=float)
            values = (np.where(np.isfinite(lo), lo, 0.0), np.where(np.isfinite(hi), hi, 0.0), np.isfinite(lo).astype(float),
                      np.isfinite(hi).astype(float))
            for name, value in zip((lower, upper, f"{lower}_mask", f"{upper}_mask"), values):
                fields.append((getattr(lib, f"d_ocp_qp_set_{name}"), *table(value, count if varying else 1), False))
            if index is not None:
                fields.append((getattr(lib, f"d_ocp_qp_set_{index}"), *table(getattr(st, index), 1, np.int32), False))
        for offset in range(count):
            k = k0 + offset
            for setter, address, step, dynamics in fields:
                if not (dynamics and k == N):
                    setter(k, address + offset * step, qp)
        k0 += count
    return keep


def _set_arguments(lib: Any, arg: Any, iterations: int, tolerance: float, regularisation: float | None) -> None:
    """HPIPM's robust mode, its iteration limit and tolerances."""
    lib.d_ocp_qp_ipm_arg_set_default(_ROBUST, arg)
    limit = ctypes.c_int(int(iterations))
    lib.d_ocp_qp_ipm_arg_set_iter_max(ctypes.byref(limit), arg)
    for name in ("tol_stat", "tol_eq", "tol_ineq", "tol_comp"):
        value = ctypes.c_double(tolerance)
        getattr(lib, f"d_ocp_qp_ipm_arg_set_{name}")(ctypes.byref(value), arg)
    if regularisation is not None:
        value = ctypes.c_double(regularisation)
        lib.d_ocp_qp_ipm_arg_set_reg_prim(ctypes.byref(value), arg)


def _read(lib: Any, ws: Any, sol: Any, shapes: Sequence[tuple[int, ...]], tolerance: float) -> ChainSolution:
    """HPIPM's status, iterations, residuals and each stage's solution."""
    status, count = ctypes.c_int(), ctypes.c_int()
    lib.d_ocp_qp_ipm_get_status(ws, ctypes.byref(status))
    lib.d_ocp_qp_ipm_get_iter(ws, ctypes.byref(count))
    residuals = {}
    for name in ("stat", "eq", "ineq", "comp", "obj"):
        value = ctypes.c_double()
        getattr(lib, "d_ocp_qp_ipm_get_obj" if name == "obj" else f"d_ocp_qp_ipm_get_max_res_{name}")(ws, ctypes.byref(value))
        residuals[name] = float(value.value)
    xs, us = [], []
    for k, (nx, nu, *_) in enumerate(shapes):
        x, u = np.zeros(nx), np.zeros(nu)
        if nx:
            lib.d_ocp_qp_sol_get_x(k, sol, x.ctypes.data)
        if nu:
            lib.d_ocp_qp_sol_get_u(k, sol, u.ctypes.data)
        xs.append(x)
        us.append(u)
    return ChainSolution(xs, us, int(status.value), int(count.value), residuals, tolerance)
