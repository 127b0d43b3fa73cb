"""Symbolic derivation of the SFLM equations with SymPy (Eqs. (3)-(8)).

The energies of docs/method.md section 1 are written once, with the deflection expanded in
assumed modes ``w(x, t) = sum_j phi_j(x) delta_j(t)`` (Eq. (3)) and the shapes kept as
undefined functions. Integrals along the link are then reduced to the named mode
constants of :mod:`modelgen.parameters` (``int x phi_j = S_j`` ...), and Lagrange's
equations ``d/dt dL/dqdot - dL/dq + dR/dqdot = H tau`` are formed by SymPy
differentiation (:func:`lagrange_derivation`). Rayleigh damping (Eq. (7)) enters through the
dissipation function ``R = b_h thetadot^2 / 2 + (2 zeta / omega_1) EI/2 int (wdot'')^2 dx + qdot^T Dm qdot / 2``,
which gives ``C = (2 zeta / omega_1) K_B + diag(b_h, 0..0) + Dm`` (``Dm``: modal damping's matrix, zero for Rayleigh
damping).

The nonlinear model (P4) uses the full kinetic energy, and by default the link's axial
foreshortening too (geometric stiffening, docs/method.md section 1a; the paper's (P4) without
it stays as ``M_nl_paper``, ``f_nl_paper``); the linear model (P6)/(P8) keeps only the part of
the Lagrangian that is quadratic in ``(q, qdot)`` jointly (the ``(w thetadot)^2`` and
stiffening terms are of fourth order and drop out).

Those energies are quadratic forms whose only state-dependent coefficient is
``M_00(delta) = J + delta^T W delta``, so their Lagrange equations have a closed form;
:func:`derive`, which the code generator uses, writes it down entry by entry from the modal
parameters (0.02 s for 2 modes, 0.5 s for 12, where the symbolic differentiation takes 2 s
and 44 s), and the tests hold it to :func:`lagrange_derivation` term by term.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import sympy as sp

from .errors import ModelError
from .parameters import parameter_names

__all__ = ["SymbolicModel", "derive", "lagrange_derivation", "reduce_link_integrals"]


@dataclass(frozen=True)
class SymbolicModel:
    """The SFLM equations for ``n`` modes, as SymPy objects.

    Attributes
    ----------
    n : int
        Number of assumed modes.
    params : dict[str, sympy.Symbol]
        The symbols of the parameter vector ``p`` (order of ``parameter_names(n)``).
    q, qd, qdd : list[sympy.Symbol]
        Generalised coordinates ``[theta, delta_1..delta_n]`` and their rates, as plain
        symbols (the dynamic symbols substituted).
    tau : sympy.Symbol
        Base torque.
    energies : dict[str, sympy.Expr]
        ``T`` (nonlinear, stiffened), ``T_paper`` (P4's), ``T_lin``, ``V`` and ``R`` in terms of ``q, qd``.
    lagrange_nonlinear, lagrange_linear : sympy.Matrix
        The residuals ``d/dt dL/dqdot - dL/dq + dR/dqdot - H tau`` of the stiffened nonlinear
        model and of (P8).
    M_nl : sympy.Matrix
        ``M(delta)`` of the nonlinear model with geometric stiffening (docs/method.md section
        1a): (P4) with the link's axial foreshortening.
    f_nl : sympy.Matrix
        Everything in it but ``M(delta) qddot`` and ``H tau``:
        ``C_cc qdot + C qdot + K_B q``.
    M_nl_paper, f_nl_paper : sympy.Matrix
        The same of the paper's (P4), without the foreshortening (its centrifugal softening
        ``(w thetadot)^2`` unbalanced).
    M, C, K : sympy.Matrix
        Constant mass, damping and stiffness matrices of (P8).
    D : sympy.Matrix
        Output row ``[x_out, phi_1(x_out) .. phi_n(x_out)]`` of ``y = D q`` (the tip, ``x_out = L``,
        by default; :func:`modelgen.parameters.parameter_names`).
    H : sympy.Matrix
        Input column ``[1, 0..0]^T``.
    W, W_paper : sympy.Matrix
        The structure of the nonlinear terms: ``M_00(delta) = M_00 + delta^T W delta`` (``n x n``,
        symmetric), of the stiffened model and of the paper's; every nonlinear term of (P4)
        follows from it (:func:`derive`).
    """

    n: int
    params: dict[str, sp.Symbol]
    q: list[sp.Symbol]
    qd: list[sp.Symbol]
    qdd: list[sp.Symbol]
    tau: sp.Symbol
    energies: dict[str, sp.Expr]
    lagrange_nonlinear: sp.Matrix
    lagrange_linear: sp.Matrix
    M_nl: sp.Matrix
    f_nl: sp.Matrix
    M_nl_paper: sp.Matrix
    f_nl_paper: sp.Matrix
    M: sp.Matrix
    C: sp.Matrix
    K: sp.Matrix
    D: sp.Matrix
    H: sp.Matrix
    W: sp.Matrix
    W_paper: sp.Matrix


def reduce_link_integrals(
    expr: sp.Expr, x: sp.Symbol, phi: list[sp.FunctionClass], params: dict[str, sp.Symbol]
) -> sp.Expr:
    """Replace integrals over ``x in [0, L]`` by the mode constants.

    Each integrand is expanded; the factor of each term that depends on ``x`` must be one
    of ``1, x, x^2`` (integrated exactly), ``x phi_j`` (``S_j``), ``phi_i phi_j``
    (``N_i_j``) or ``phi_i'' phi_j''`` (``G_i_j``).

    Parameters
    ----------
    expr : sp.Expr
        The expression holding the integrals.
    x : sp.Symbol
        The coordinate along the link.
    phi : list[sp.FunctionClass]
        The mode-shape functions.
    params : dict[str, sp.Symbol]
        The named symbols (``L``, the mode constants).

    Raises
    ------
    ModelError
        For any other ``x``-dependence (a term the model does not know how to integrate).
    """
    L = params["L"]
    index = {f: j for j, f in enumerate(phi, start=1)}

    def sym_pair(prefix: str, i: int, j: int) -> sp.Symbol:
        a, b = sorted((i, j))
        return params[f"{prefix}_{a}_{b}"]

    def integrate_factor(xpart: sp.Expr) -> sp.Expr:
        powers = sp.Mul.make_args(xpart)
        xpow = 0
        shapes: list[int] = []
        curvatures: list[int] = []
        for factor in powers:
            base, exp = factor.as_base_exp()
            if not exp.is_Integer or exp < 0:
                raise ModelError(f"cannot integrate the link factor {xpart}")
            k = int(exp)
            if base == x:
                xpow += k
            elif isinstance(base, sp.Derivative) and base.expr.func in index and base.variables == (x, x):
                curvatures += [index[base.expr.func]] * k
            elif base.func in index and base.args == (x,):
                shapes += [index[base.func]] * k
            else:
                raise ModelError(f"cannot integrate the link factor {xpart}")
        if not shapes and not curvatures:
            return L ** (xpow + 1) / (xpow + 1)
        if xpow == 1 and len(shapes) == 1 and not curvatures:
            return params[f"S_{shapes[0]}"]
        if xpow == 0 and len(shapes) == 2 and not curvatures:
            return sym_pair("N", *shapes)
        if xpow == 0 and not shapes and len(curvatures) == 2:
            return sym_pair("G", *curvatures)
        raise ModelError(f"cannot integrate the link factor {xpart}")

    def reduce_one(integral: sp.Integral) -> sp.Expr:
        (var, lower, upper), = integral.limits
        if var != x or lower != 0 or upper != L:
            raise ModelError(f"unexpected integral {integral}")
        total = sp.S.Zero
        for term in sp.Add.make_args(sp.expand(integral.function)):
            coeff, xpart = term.as_independent(x, as_Add=False)
            total += coeff * integrate_factor(xpart)
        return total

    return expr.replace(lambda e: isinstance(e, sp.Integral), reduce_one)


@lru_cache(maxsize=8)
def derive(n: int) -> SymbolicModel:
    """The nonlinear (P4) and linear (P8) SFLM equations for ``n`` assumed modes, assembled from their structure.

    The kinetic energy is ``T = qdot^T M(delta) qdot / 2`` with every entry of ``M`` constant but
    ``M_00(delta) = J + delta^T W delta``; ``V = delta^T EI G delta / 2`` and ``R`` are quadratic too.
    Lagrange's equations of such energies are, in closed form (docs/method.md section 1a)::

        M(delta) qddot + K q + C qdot + [2 thetadot delta^T W deltadot; -thetadot^2 W delta] = H tau,

    with ``W = rho N + m_t phiL phiL^T`` for the paper's (P4) and ``W - rho P / 2 - m_t L Q`` with the
    geometric stiffening. So the matrices are written down entry by entry from the modal
    parameters, which takes milliseconds where differentiating the Lagrangian symbolically
    (:func:`lagrange_derivation`, the reference the tests hold this one to for ``n = 1..3``)
    takes a minute at twelve modes.

    Parameters
    ----------
    n : int
        Number of assumed modes (>= 1).

    Returns
    -------
    SymbolicModel
        The same equations as :func:`lagrange_derivation` (equal after expansion).

    Examples
    --------
    >>> model = derive(1)
    >>> model.M[0, 0]
    I_h + I_t + L**3*rho/3 + L**2*m_t
    """
    if n < 1:
        raise ModelError(f"number of modes must be >= 1, got {n}")
    P = {name: sp.Symbol(name, real=True) for name in parameter_names(n)}
    L, EI, rho, m_t, I_t = P["L"], P["EI"], P["rho"], P["m_t"], P["I_t"]
    tau = sp.Symbol("tau", real=True)
    q, qd, qdd = _state_symbols(n)

    def pair(prefix: str, i: int, j: int) -> sp.Symbol:
        return P[f"{prefix}_{min(i, j)}_{max(i, j)}"]

    modes = range(1, n + 1)
    phiL, dphiL = [P[f"phiL_{j}"] for j in modes], [P[f"dphiL_{j}"] for j in modes]
    M = sp.zeros(n + 1)
    M[0, 0] = P["I_h"] + rho * L**3 / 3 + m_t * L**2 + I_t
    for j in modes:
        M[0, j] = M[j, 0] = rho * P[f"S_{j}"] + m_t * L * phiL[j - 1] + I_t * dphiL[j - 1]
        for i in modes:
            M[i, j] = rho * pair("N", i, j) + m_t * phiL[i - 1] * phiL[j - 1] + I_t * dphiL[i - 1] * dphiL[j - 1]
    K = sp.zeros(n + 1)
    C = sp.zeros(n + 1)
    C[0, 0] = P["b_h"]
    for i in modes:
        for j in modes:
            K[i, j] = EI * pair("G", i, j)
            C[i, j] = 2 * P["zeta"] / P["omega_1"] * EI * pair("G", i, j)
    for i in range(n + 1):  # modal damping's matrix (zero for Rayleigh damping)
        for j in range(n + 1):
            C[i, j] += pair("Dm", i, j)
    H = sp.Matrix([1] + [0] * n)
    D = sp.Matrix([[P["x_out"]] + [P[f"phiX_{j}"] for j in modes]])  # y = x_out theta + w(x_out)
    W_paper = sp.Matrix(n, n, lambda i, j: rho * pair("N", i + 1, j + 1) + m_t * phiL[i] * phiL[j])
    W = sp.Matrix(n, n, lambda i, j: W_paper[i, j] - rho * pair("P", i + 1, j + 1) / 2 - m_t * L * pair("Q", i + 1, j + 1))
    delta, deltadot = q[1:], qd[1:]

    def times(A: sp.Matrix, v: list[sp.Symbol]) -> sp.Matrix:  # SymPy's matrix product is slow on symbols: sums instead
        return sp.Matrix([sp.Add(*(A[i, j] * v[j] for j in range(len(v)))) for i in range(A.rows)])

    def form(a: list[sp.Symbol], A: sp.Matrix, b: list[sp.Symbol]) -> sp.Expr:
        return sp.Add(*(a[i] * A[i, j] * b[j] for i in range(len(a)) for j in range(len(b))))

    linear_forces = times(K, q) + times(C, qd)

    def nonlinear(W: sp.Matrix) -> tuple[sp.Matrix, sp.Matrix, sp.Expr]:
        """``M(delta)``, ``f(q, qdot)`` and the kinetic energy of the model whose ``M_00`` grows by ``delta^T W delta``."""
        M_nl = M.copy()
        M_nl[0, 0] = M[0, 0] + form(delta, W, delta)
        gyroscopic = sp.Matrix([2 * qd[0] * form(delta, W, deltadot)]).col_join(-qd[0] ** 2 * times(W, delta))
        return M_nl, linear_forces + gyroscopic, form(qd, M_nl, qd) / 2

    M_nl, f_nl, T_stiff = nonlinear(W)
    M_nl_paper, f_nl_paper, T_paper = nonlinear(W_paper)
    energies = {"T": T_stiff, "T_paper": T_paper, "T_lin": form(qd, M, qd) / 2, "V": form(q, K, q) / 2, "R": form(qd, C, qd) / 2}
    H_tau = H * tau
    return SymbolicModel(n=n, params=P, q=q, qd=qd, qdd=qdd, tau=tau, energies=energies,
                         lagrange_nonlinear=times(M_nl, qdd) + f_nl - H_tau, lagrange_linear=times(M, qdd) + linear_forces - H_tau,
                         M_nl=M_nl, f_nl=f_nl, M_nl_paper=M_nl_paper, f_nl_paper=f_nl_paper, M=M, C=C, K=K, D=D, H=H,
                         W=W, W_paper=W_paper)


def lagrange_derivation(n: int) -> SymbolicModel:
    """Derive the SFLM equations (P4), (P8) from the Lagrangian.

    Derive the nonlinear (P4) and linear (P8) SFLM equations for ``n`` assumed modes by SymPy differentiation of the
    Lagrangian (the reference :func:`derive`'s assembly is tested against).

    Parameters
    ----------
    n : int
        Number of assumed modes (>= 1).

    Returns
    -------
    SymbolicModel

    Notes
    -----
    Energies (docs/method.md section 1; a point of the link is at
    ``(x cos theta - w sin theta, x sin theta + w cos theta)``)::

        T = I_h thetadot^2/2 + int rho [(x thetadot + wdot)^2 + (w thetadot)^2]/2 dx
            + m_t [(L thetadot + wdot(L))^2 + (w(L) thetadot)^2]/2
            + I_t (thetadot + wdot'(L))^2/2
        V = int EI (w'')^2/2 dx

    Examples
    --------
    >>> model = lagrange_derivation(1)
    >>> model.M[0, 0]
    I_h + I_t + L**3*rho/3 + L**2*m_t
    """
    if n < 1:
        raise ModelError(f"number of modes must be >= 1, got {n}")
    t = sp.Symbol("t", real=True)
    x = sp.Symbol("x", real=True)
    params = {name: sp.Symbol(name, real=True) for name in parameter_names(n)}
    tau = sp.Symbol("tau", real=True)

    coords = [sp.Function("theta", real=True)(t)] + [sp.Function(f"delta_{j}", real=True)(t) for j in range(1, n + 1)]
    T, T_stiff, V, R = _energies(t, x, coords, params)

    # Linear model: keep the part of T quadratic in (q, qdot) jointly (Eq. (6)).
    # xreplace works top-down, so the rates are scaled as whole nodes.
    eps = sp.Symbol("epsilon")
    small: dict[sp.Basic, sp.Basic] = {c.diff(t): eps * c.diff(t) for c in coords}
    small.update({c: eps * c for c in coords})
    T_lin = sp.expand(T.xreplace(small)).coeff(eps, 2)

    forces = [tau] + [sp.S.Zero] * n  # H tau

    def lagrange(kinetic: sp.Expr) -> list[sp.Expr]:
        lag = kinetic - V
        eqs = []
        for c, Q in zip(coords, forces):
            cd = c.diff(t)
            eqs.append(sp.expand(lag.diff(cd).diff(t) - lag.diff(c) + R.diff(cd) - Q))
        return eqs

    q, qd, qdd, plain = _plain_state(t, coords)

    def to_plain(exprs: list[sp.Expr]) -> sp.Matrix:
        # xreplace matches whole derivative nodes before the functions inside them
        return sp.Matrix([e.xreplace(plain) for e in exprs])

    eq_nl = to_plain(lagrange(T_stiff))
    eq_paper = to_plain(lagrange(T))
    eq_lin = to_plain(lagrange(T_lin))

    M_nl = eq_nl.jacobian(qdd)
    zero_acc = {d: 0 for d in qdd}
    H = -eq_lin.jacobian([tau])
    f_nl = sp.expand(eq_nl.subs(zero_acc).subs(tau, 0))
    M_nl_paper = eq_paper.jacobian(qdd)
    f_nl_paper = sp.expand(eq_paper.subs(zero_acc).subs(tau, 0))
    M = eq_lin.jacobian(qdd)
    C = eq_lin.jacobian(qd)
    K = eq_lin.jacobian(q)
    D = sp.Matrix([[params["x_out"]] + [params[f"phiX_{j}"] for j in range(1, n + 1)]])  # y = x_out theta + w(x_out)
    energies = {
        "T": to_plain([T_stiff])[0],
        "T_paper": to_plain([T])[0],
        "T_lin": to_plain([T_lin])[0],
        "V": to_plain([V])[0],
        "R": to_plain([R])[0],
    }
    return SymbolicModel(
        n=n,
        params=params,
        q=q,
        qd=qd,
        qdd=qdd,
        tau=tau,
        energies=energies,
        lagrange_nonlinear=eq_nl,
        lagrange_linear=eq_lin,
        M_nl=M_nl,
        f_nl=f_nl,
        M_nl_paper=M_nl_paper,
        f_nl_paper=f_nl_paper,
        M=M,
        C=C,
        K=K,
        D=D,
        H=H,
        W=sp.hessian(M_nl[0, 0], q[1:]) / 2,  # M_00(delta) is quadratic in the deflections
        W_paper=sp.hessian(M_nl_paper[0, 0], q[1:]) / 2,
    )


def _energies(t: sp.Symbol, x: sp.Symbol, coords: list[sp.Expr], params: dict[str, sp.Symbol]) -> tuple[sp.Expr, sp.Expr, sp.Expr, sp.Expr]:
    """The kinetic energy of (P4) ``T``, the same with the geometric stiffening ``T_stiff``, the strain energy ``V`` and
    the Rayleigh dissipation ``R`` (Eq. (7)), the link's integrals reduced to the modal parameters."""
    n = len(coords) - 1
    theta, delta = coords[0], coords[1:]
    phi = [sp.Function(f"phi_{j}", real=True) for j in range(1, n + 1)]
    L, EI, rho = params["L"], params["EI"], params["rho"]
    I_h, m_t, I_t = params["I_h"], params["m_t"], params["I_t"]
    b_h, zeta, omega_1 = params["b_h"], params["zeta"], params["omega_1"]

    w = sum((phi[j](x) * delta[j] for j in range(n)), sp.S.Zero)  # Eq. (3)
    wdot = w.diff(t)
    thetadot = theta.diff(t)
    tip = {phi[j](L): params[f"phiL_{j + 1}"] for j in range(n)}
    w_L = w.subs(x, L).subs(tip)
    slope_L = sum((params[f"dphiL_{j + 1}"] * delta[j] for j in range(n)), sp.S.Zero)  # w'(L)

    T_link = sp.Integral(rho / 2 * ((x * thetadot + wdot) ** 2 + (w * thetadot) ** 2), (x, 0, L))
    T = (
        I_h / 2 * thetadot**2
        + reduce_link_integrals(T_link, x, phi, params)
        + m_t / 2 * ((L * thetadot + w_L.diff(t)) ** 2 + (w_L * thetadot) ** 2)
        + I_t / 2 * (thetadot + slope_L.diff(t)) ** 2
    )
    # Geometric stiffening (docs/method.md section 1a): a point of the deflected link is drawn in by the
    # foreshortening u_c(x) = -1/2 int_0^x (w')^2, so its radius is x + u_c; to second order in the
    # deflections the kinetic energy gains rho thetadot^2 x u_c along the link and m_t thetadot^2 L u_c(L)
    # at the payload, i.e. -thetadot^2/2 int [rho (L^2 - x^2)/2 + m_t L] (w')^2 dx, which balances the
    # centrifugal softening (w thetadot)^2 (Kane, Ryan & Banerjee 1987)
    stiffening = sum(
        (delta[i] * delta[j] * (rho / 2 * params[f"P_{min(i, j) + 1}_{max(i, j) + 1}"] + m_t * L * params[f"Q_{min(i, j) + 1}_{max(i, j) + 1}"])
         for i in range(n) for j in range(n)),
        sp.S.Zero,
    )
    T_stiff = T - thetadot**2 / 2 * stiffening
    V = reduce_link_integrals(sp.Integral(EI / 2 * w.diff(x, 2) ** 2, (x, 0, L)), x, phi, params)
    # Rayleigh dissipation: stiffness-proportional material damping (Eq. (7)) and hub viscous damping.
    R = b_h / 2 * thetadot**2 + (2 * zeta / omega_1) * reduce_link_integrals(
        sp.Integral(EI / 2 * wdot.diff(x, 2) ** 2, (x, 0, L)), x, phi, params
    )
    rates = [c.diff(t) for c in coords]  # modal damping: qdot^T Dm qdot / 2 (zero for Rayleigh damping)
    R += sum((rates[i] * rates[j] * params[f"Dm_{min(i, j)}_{max(i, j)}"] / 2 for i in range(n + 1) for j in range(n + 1)), sp.S.Zero)
    return T, T_stiff, V, R


def _state_symbols(n: int) -> tuple[list[sp.Symbol], list[sp.Symbol], list[sp.Symbol]]:
    """Plain symbols ``[theta, delta_1..n]``, their rates and their accelerations."""
    q = [sp.Symbol("theta", real=True)] + [sp.Symbol(f"delta_{j}", real=True) for j in range(1, n + 1)]
    qd = [sp.Symbol("thetadot", real=True)] + [sp.Symbol(f"deltadot_{j}", real=True) for j in range(1, n + 1)]
    qdd = [sp.Symbol("thetaddot", real=True)] + [sp.Symbol(f"deltaddot_{j}", real=True) for j in range(1, n + 1)]
    return q, qd, qdd


def _plain_state(t: sp.Symbol, coords: list[sp.Expr]) -> tuple[list[sp.Symbol], list[sp.Symbol], list[sp.Symbol], dict[sp.Basic, sp.Basic]]:
    """Plain symbols for the state, its rates and accelerations, and the map from the functions of time to them."""
    n = len(coords) - 1
    q, qd, qdd = _state_symbols(n)
    plain: dict[sp.Basic, sp.Basic] = {}
    for c, a, b, d in zip(coords, q, qd, qdd):
        plain[c.diff(t, 2)] = d
        plain[c.diff(t)] = b
        plain[c] = a
    return q, qd, qdd, plain
