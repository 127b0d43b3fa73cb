"""CasADi functions of the SFLM model, C code generation and compilation.

SymPy derives (:mod:`modelgen.lagrange`), this module converts the result to CasADi SX
and builds one CasADi Function per role under one naming scheme, ``sflm_<role>``. Every
function takes the parameter vector ``p`` first (:mod:`modelgen.parameters`), so one
compiled library serves every geometry with the same number of modes. Linear algebra
the symbolic model leaves open (``M^-1 K`` ...) is done by CasADi (``solve``), not SymPy.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path
from typing import Any, Sequence

import casadi as ca

from .abi import BATCH_CHUNK, COMPILE_FLAGS, ROLES, symbol
from .errors import CodegenError
from .lagrange import SymbolicModel
from .parameters import parameter_names
from .sympy_casadi import SympyToCasadi

__all__ = [
    "build_functions",
    "function_signatures",
    "generate_sources",
    "compile_library",
    "source_header",
]

def build_functions(model: SymbolicModel) -> dict[str, ca.Function]:
    """CasADi Functions of every role in :data:`~modelgen.abi.ROLES`.

    CasADi Functions of every role in :data:`~modelgen.abi.ROLES` for a symbolic model.

    The SymPy matrices become SX kernels of ``p``: ``M, K, C, D, H`` of (P8), and ``W, W_paper``,
    the structure of the nonlinear models (stiffened, and the paper's (P4);
    :func:`modelgen.lagrange.derive`). The roles are MX graphs over these kernels -- the
    nonlinear right-hand sides and their Jacobians assembled from ``M, K, C, W`` as matrix
    products -- in which every ``M^-1`` is a linear solve by CasADi's QR (generated as a small
    runtime routine, so the code grows like ``n^2``, not ``n^3``).

    Parameters
    ----------
    model : SymbolicModel
        From :func:`modelgen.lagrange.derive`.

    Returns
    -------
    dict
        Role -> ``casadi.Function`` named ``sflm_<role>``.
    """
    n = model.n
    n1 = n + 1
    names = parameter_names(n)

    linear_kernel, structure_kernel = _kernels(model, names)

    # MX graphs of the roles
    p = ca.MX.sym("p", len(names))
    X = ca.MX.sym("X", 2 * n1)
    tau = ca.MX.sym("tau")
    yddot = ca.MX.sym("yddot")
    M, K, C, D, H = linear_kernel(p)
    MinvK, MinvC, MinvH = _qr_solve(M, K), _qr_solve(M, C), _qr_solve(M, H)
    A = ca.vertcat(ca.horzcat(ca.MX(n1, n1), ca.MX.eye(n1)), ca.horzcat(-MinvK, -MinvC))  # Eq. (10)
    B = ca.vertcat(ca.MX(n1, 1), MinvH)
    C_out = ca.horzcat(D, ca.MX(1, n1))
    CAB = ca.mtimes(D, MinvH)  # C_out A B = D M^-1 H, Eq. (11)
    CA2 = ca.mtimes(ca.horzcat(ca.MX(1, n1), D), A)  # C_out A^2 = [0, D] A

    AI, BI, T, Tinv = _normal_form(p, names, M, K, C, D)

    q, qd = X[:n1], X[n1:]
    tau_l = (yddot - ca.mtimes(CA2, X)) / CAB  # Eq. (12)
    linear_rhs = ca.mtimes(A, X) + B * tau  # Eq. (9a)
    W, W_paper = structure_kernel(p)
    nonlinear = {"nonlinear": _nonlinear(X, tau, M, K, C, H, W), "nonlinear_paper": _nonlinear(X, tau, M, K, C, H, W_paper)}
    energy = 0.5 * ca.mtimes([qd.T, M, qd]) + 0.5 * ca.mtimes([q.T, K, q])

    # batch form of Eq. (12): C_out A^2 and CAB once per chunk of samples
    X_batch = ca.MX.sym("X", 2 * n1, BATCH_CHUNK)
    yddot_batch = ca.MX.sym("yddot", 1, BATCH_CHUNK)
    tau_batch = (yddot_batch - ca.mtimes(CA2, X_batch)) / CAB

    outputs: dict[str, tuple[Any, ...]] = {
        "M": (M,),
        "K": (K,),
        "C": (C,),
        "D": (D,),
        "H": (H,),
        "A": (A,),
        "B": (B,),
        "C_out": (C_out,),
        "CAB": (CAB,),
        "CA2": (CA2,),
        "AI": (AI,),
        "BI": (BI,),
        "T": (T,),
        "Tinv": (Tinv,),
        "inverse_torque": (tau_l,),
        "inverse_torque_batch": (tau_batch,),
        "linear_rhs": (linear_rhs,),
        "nonlinear_rhs": nonlinear["nonlinear"][:1],
        "nonlinear_rhs_jacobian": nonlinear["nonlinear"][1:3],
        "nonlinear_paper_rhs": nonlinear["nonlinear_paper"][:1],
        "nonlinear_paper_rhs_jacobian": nonlinear["nonlinear_paper"][1:3],
        "nonlinear_energy": (nonlinear["nonlinear"][3],),
        "tip_output": (ca.mtimes(D, q), ca.mtimes(D, qd)),
        "energy": (energy,),
    }
    inputs = {"p": p, "X": X, "tau": tau, "yddot": yddot, "X_batch": X_batch, "yddot_batch": yddot_batch}
    functions = {}
    for role, (in_names, out_names) in ROLES.items():
        outs = [ca.densify(o) for o in outputs[role]]
        functions[role] = ca.Function(
            symbol(role),
            [inputs[i] for i in in_names],
            outs,
            [i.removesuffix("_batch") for i in in_names],
            list(out_names),
        )
    return functions


def _kernels(model: SymbolicModel, names: Sequence[str]) -> tuple[Any, Any]:
    """SX kernels from SymPy's matrices, functions of ``p``: the linear matrices ``M, K, C, D, H``, and the structure of
    the nonlinear terms ``W, W_paper`` (:func:`modelgen.lagrange.derive`)."""
    n = model.n
    n1 = n + 1
    p_sx = ca.SX.sym("p", len(names))
    X_sx = ca.SX.sym("X", 2 * n1)
    tau_sx = ca.SX.sym("tau")
    table: dict[Any, Any] = {model.params[name]: p_sx[i] for i, name in enumerate(names)}
    for k in range(n1):
        table[model.q[k]] = X_sx[k]
        table[model.qd[k]] = X_sx[n1 + k]
    table[model.tau] = tau_sx
    conv = SympyToCasadi(table)
    linear_kernel = ca.Function(
        "sflm_kernel_linear",
        [p_sx],
        [ca.densify(conv.matrix(m)) for m in (model.M, model.K, model.C, model.D, model.H)],
        ["p"],
        ["M", "K", "C", "D", "H"],
    )
    structure_kernel = ca.Function("sflm_kernel_structure", [p_sx], [ca.densify(conv.matrix(model.W)), ca.densify(conv.matrix(model.W_paper))],
                                   ["p"], ["W", "W_paper"])
    return linear_kernel, structure_kernel


def _normal_form(p: Any, names: Sequence[str], M: Any, K: Any, C: Any, D: Any) -> tuple[Any, Any, Any, Any]:
    """``AI, BI`` of the internal dynamics (Eq. (14)) and the transformation ``T`` to normal coordinates with its inverse."""
    n = M.shape[0] - 1
    n1 = n + 1
    # the output is measured where D does: y = x_out theta + phi(x_out) delta
    x_out = p[names.index("x_out")]
    phi_x = D[0, 1:].T
    m = M[1:, 0]
    Mbar = M[1:, 1:] - ca.mtimes(m, phi_x.T) / x_out  # Eq. (14)
    AI = ca.vertcat(
        ca.horzcat(ca.MX(n, n), ca.MX.eye(n)),
        ca.horzcat(-_qr_solve(Mbar, K[1:, 1:]), -_qr_solve(Mbar, C[1:, 1:])),
    )
    BI = ca.vertcat(ca.MX(n, 1), -_qr_solve(Mbar, m / x_out))
    T = ca.vertcat(
        ca.horzcat(D, ca.MX(1, n1)),
        ca.horzcat(ca.MX(1, n1), D),
        ca.horzcat(ca.MX(n, 1), ca.MX.eye(n), ca.MX(n, n1)),
        ca.horzcat(ca.MX(n, n1 + 1), ca.MX.eye(n)),
    )
    Tinv = ca.vertcat(
        ca.horzcat(1 / x_out, ca.MX(1, 1), -phi_x.T / x_out, ca.MX(1, n)),  # theta = (y - phi_x delta)/x_out
        ca.horzcat(ca.MX(n, 2), ca.MX.eye(n), ca.MX(n, n)),
        ca.horzcat(ca.MX(1, 1), 1 / x_out, ca.MX(1, n), -phi_x.T / x_out),
        ca.horzcat(ca.MX(n, 2 + n), ca.MX.eye(n)),
    )

    return AI, BI, T, Tinv


def _nonlinear(X: Any, tau: Any, M: Any, K: Any, C: Any, H: Any, W: Any) -> tuple[Any, Any, Any, Any]:
    """The right-hand side of the nonlinear model whose ``M_00`` grows by ``delta^T W delta`` (Eq. (4) in the closed form
    of :func:`modelgen.lagrange.derive`), its Jacobians w.r.t. ``X`` and ``tau``, and its energy ``T + V``.

    Built from the matrices as MX products, so the generated code grows like ``n^2`` data, not ``n^2`` expanded
    expressions (the SymPy entries of ``M(delta)`` and ``f`` are what the tests hold it to)."""
    n1 = X.shape[0] // 2
    n = n1 - 1
    q, qd = X[:n1], X[n1:]
    Wd = ca.mtimes(W, q[1:])
    s = ca.dot(q[1:], Wd)
    corner = ca.DM(ca.Sparsity.triplet(n1, n1, [0], [0]), 1.0)
    M_nl = M + s * corner
    f = ca.mtimes(K, q) + ca.mtimes(C, qd) + ca.vertcat(2 * qd[0] * ca.dot(Wd, qd[1:]), -qd[0] ** 2 * Wd)
    qdd = _qr_solve(M_nl, H * tau - f)  # Eq. (4)
    # d qdd / dX = -M^-1 (df/dX + d(M qdd)/dX |_qdd fixed),  d qdd / dtau = M^-1 H; only M_00 depends on X
    df_dX = ca.jacobian(f, X)
    dMv_dX = ca.vertcat(ca.horzcat(ca.MX(1, 1), 2 * qdd[0] * Wd.T, ca.MX(1, n1)), ca.MX(n, 2 * n1))
    rhs_dX = ca.vertcat(ca.horzcat(ca.MX(n1, n1), ca.MX.eye(n1)), -_qr_solve(M_nl, df_dX + dMv_dX))
    rhs_dtau = ca.vertcat(ca.MX(n1, 1), _qr_solve(M_nl, H))
    energy = 0.5 * ca.dot(qd, ca.mtimes(M_nl, qd)) + 0.5 * ca.dot(q, ca.mtimes(K, q))
    return ca.vertcat(qd, qdd), rhs_dX, rhs_dtau, energy


def _qr_solve(A: Any, b: Any) -> Any:
    """``A^-1 b`` by CasADi's sparse QR: a linear-solver node that code generation supports."""
    return ca.solve(A, b, "qr")


def function_signatures(functions: dict[str, ca.Function]) -> dict[str, dict[str, Any]]:
    """Manifest entries: role -> symbol, inputs and outputs in order.

    Parameters
    ----------
    functions : dict[str, ca.Function]
        The CasADi Functions by role.
    """
    out = {}
    for role, f in functions.items():
        out[role] = {
            "symbol": f.name(),
            "inputs": [[f.name_in(i), list(f.size_in(i))] for i in range(f.n_in())],
            "outputs": [[f.name_out(i), list(f.size_out(i))] for i in range(f.n_out())],
        }
    return out


def source_header(n: int, versions: dict[str, str]) -> str:
    """The comment heading every generated file.

    Parameters
    ----------
    n : int
        Number of assumed modes.
    versions : dict[str, str]
        Versions of the tools that generated the code, by name.
    """
    tools = ", ".join(f"{k} {v}" for k, v in sorted(versions.items()) if k in ("sflm", "sympy", "casadi"))
    return (
        "/* generated by sflm from the symbolic single-flexible-link model with "
        f"{n} assumed mode{'s' if n != 1 else ''}\n"
        " * (modelgen.lagrange -> modelgen.codegen; " + tools + ").\n"
        " * Every function takes the parameter vector p first; its entries are listed in manifest.json.\n"
        " * Do not edit by hand: regenerate with `sflm generate`. */\n"
    )


def generate_sources(functions: dict[str, ca.Function], folder: Path, basename: str, header: str) -> tuple[Path, Path]:
    """Write ``<basename>.c`` and ``.h`` into ``folder``.

    Write ``<basename>.c`` and ``<basename>.h`` into ``folder``, each headed by ``header``.

    Parameters
    ----------
    functions : dict[str, ca.Function]
        The CasADi Functions by role.
    folder : Path
        Where the files are written.
    basename : str
        The files' name without suffix.
    header : str
        The comment heading both files (:func:`source_header`).

    Returns
    -------
    (Path, Path)
        The C source and the header.
    """
    folder = Path(folder)
    cg = ca.CodeGenerator(f"{basename}.c", {"with_header": True})
    for role in ROLES:
        cg.add(functions[role])
    cg.generate(str(folder) + os.sep)
    paths = (folder / f"{basename}.c", folder / f"{basename}.h")
    for path in paths:
        path.write_text(header + path.read_text())
    return paths


def compile_library(source: Path, library: Path, command: str, flags: tuple[str, ...] = COMPILE_FLAGS) -> None:
    """Compile a generated source into a shared library.

    Parameters
    ----------
    source : Path
        The C source.
    library : Path
        The shared library to write.
    command : str
        The C compiler's command.
    flags : tuple[str, ...], optional
        The compiler's flags.

    Raises
    ------
    CodegenError
        With the compiler's first error lines when compilation fails.
    """
    cmd = [command, *flags, "-o", str(library), str(source), "-lm"]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    except (OSError, subprocess.SubprocessError) as exc:
        raise CodegenError(f"could not run the C compiler {command!r}: {exc}") from None
    if proc.returncode != 0:
        first = " | ".join(proc.stderr.strip().splitlines()[:3])
        raise CodegenError(f"compilation of {source.name} failed (exit {proc.returncode}): {first}")
