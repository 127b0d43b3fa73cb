"""An exact Euler-Bernoulli beam on a rotating hub, written apart from sflm's model: the data calibration is judged on.

The link's absolute transverse displacement ``u(x, t)`` (linear, the hub free to rotate about ``x = 0``), with
Kelvin-Voigt material damping ``EI (1 + a d/dt)``::

    rho u_tt + EI (1 + a d/dt) u'''' = 0,            0 < x < L
    u(0) = 0,   J_h u_x tt(0) = tau + EI* u''(0)      (the hub: theta = u'(0))
    EI* u''(L) = -J_p u_x tt(L),   EI* u'''(L) = m_p u_tt(L)   (the payload)

from the variation of ``T - V`` (no assumed modes). In the Laplace domain ``u = U(x) e^{st}`` and
``U'''' = beta^4 U`` with ``beta^4 = -rho s^2 / EI*``: the four boundary conditions on ``sin, cos(beta x)`` and
``exp(-beta x), exp(-beta (L - x))``
are a 4 x 4 linear system. Its solution at ``s = i omega`` is the frequency response (exact, no truncation); its
determinant at ``a = 0`` vanishes at the natural frequencies; its null vectors are the modes, normalised by the mass
form (beam, hub, payload) for the time records, which sum the modes (rigid body plus ``count``) each discretised
exactly with the torque held between samples.

Nothing here imports sflm: it is the other model the calibration's honesty is measured against.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.optimize as so


@dataclass(frozen=True)
class Beam:
    """A link as the continuum sees it (SI units); ``a``: Kelvin-Voigt time constant (s)."""

    L: float
    EI: float
    rho: float
    J_h: float
    m_p: float
    J_p: float
    a: float = 0.0

    def with_first_ratio(self, zeta: float) -> "Beam":
        """The same beam with the damping that gives its first flexible mode the ratio ``zeta`` (``a = 2 zeta / w1``)."""
        w1 = float(self.frequencies(1)[0]) * 2 * np.pi
        return Beam(self.L, self.EI, self.rho, self.J_h, self.m_p, self.J_p, 2 * zeta / w1)

    # -- the boundary-value problem --------------------------------------------------------------------------------------

    def _basis(self, beta: complex, x: np.ndarray | float, order: int) -> np.ndarray:
        """The ``order``-th derivatives of ``sin(beta x), cos(beta x), exp(-beta x), exp(-beta (L - x))`` at ``x``: the
        decaying exponentials, not ``sinh, cosh`` (whose difference loses every digit on a high mode)."""
        b, x = beta, np.asarray(x, dtype=complex)
        trig = [np.sin(b * x), np.cos(b * x), -np.sin(b * x), -np.cos(b * x)]
        sin = b**order * trig[order % 4]
        cos = b**order * trig[(order + 1) % 4]
        near = (-b) ** order * np.exp(-b * x)
        far = b**order * np.exp(-b * (self.L - x))
        return np.stack([sin, cos, near, far])

    def _system(self, s: complex, stiffness: complex) -> tuple[np.ndarray, complex]:
        """The 4 x 4 matrix of the boundary conditions on :meth:`_basis`, and ``beta`` (``Re beta > 0``)."""
        beta = complex((-self.rho * s * s / stiffness + 0j) ** 0.25)
        at = self._basis
        rows = [at(beta, 0.0, 0),
                self.J_h * s * s * at(beta, 0.0, 1) - stiffness * at(beta, 0.0, 2),
                stiffness * at(beta, self.L, 2) + self.J_p * s * s * at(beta, self.L, 1),
                stiffness * at(beta, self.L, 3) - self.m_p * s * s * at(beta, self.L, 0)]
        return np.array(rows, dtype=complex), beta

    def response(self, f_hz: np.ndarray, output: str = "theta") -> np.ndarray:
        """The exact frequency response from the hub torque to the hub angle (``theta``) or the tip (``y``)."""
        out = np.empty(len(f_hz), dtype=complex)
        for k, f in enumerate(f_hz):
            s = 2j * np.pi * f
            A, beta = self._system(s, self.EI * (1 + self.a * s))
            c = np.linalg.solve(A, np.array([0, 1, 0, 0], dtype=complex))
            out[k] = c @ (self._basis(beta, 0.0, 1) if output == "theta" else self._basis(beta, self.L, 0))
        return out

    def _determinant(self, w: float) -> float:
        """The undamped determinant at ``omega = w`` (real for real ``beta``), scaled by ``beta^6``."""
        A, beta = self._system(1j * w, self.EI)
        return float(np.real(np.linalg.det(A))) / max(abs(beta) ** 6, 1e-300)

    def frequencies(self, count: int) -> np.ndarray:
        """The lowest ``count`` natural frequencies (Hz) with the hub free, from the determinant's sign changes."""
        found: list[float] = []
        speed = np.sqrt(self.EI / self.rho)  # omega = speed beta^2; the roots in beta are about pi / L apart
        step = np.pi / (24 * self.L)
        b = 0.5 * step
        d = self._determinant(speed * b * b)
        while len(found) < count:
            b2 = b + step
            d2 = self._determinant(speed * b2 * b2)
            if np.sign(d2) != np.sign(d) and d != 0:
                found.append(so.brentq(self._determinant, speed * b * b, speed * b2 * b2, xtol=1e-13, rtol=1e-15))
            b, d = b2, d2
        return np.array(found) / (2 * np.pi)

    def _mode(self, w: float) -> tuple[float, float, float]:
        """The mode at ``omega = w``: its hub slope, tip displacement and modal mass (beam, hub and payload)."""
        A, beta = self._system(1j * w, self.EI)
        _, _, vh = np.linalg.svd(np.real(A))
        c = vh[-1]
        x, weights = np.polynomial.legendre.leggauss(200)
        x = 0.5 * self.L * (x + 1)
        weights = 0.5 * self.L * weights

        def at(z: np.ndarray | float, order: int) -> np.ndarray:
            return np.real(c @ self._basis(beta, z, order))

        mass = (self.rho * float(weights @ at(x, 0) ** 2) + self.J_h * float(at(0.0, 1)) ** 2
                + self.m_p * float(at(self.L, 0)) ** 2 + self.J_p * float(at(self.L, 1)) ** 2)
        return float(at(0.0, 1)), float(at(self.L, 0)), mass

    def modal_response(self, f_hz: np.ndarray, ratios: np.ndarray, count: int = 40) -> np.ndarray:
        """The hub angle's frequency response with modal damping: mode ``i`` its own ratio (``ratios``, the last
        repeated), the rigid body and ``count`` modes summed -- the damping a link has, not the model's form."""
        J = self.rho * self.L**3 / 3 + self.J_h + self.m_p * self.L**2 + self.J_p
        s = 2j * np.pi * np.asarray(f_hz)
        out = 1.0 / (J * s * s)
        for i, f in enumerate(self.frequencies(count)):
            w = 2 * np.pi * f
            hub, _, mass = self._mode(w)
            zeta = ratios[min(i, len(ratios) - 1)]
            out = out + hub * hub / (mass * (s * s + 2 * zeta * w * s + w * w))
        return out

    def record(self, t: np.ndarray, tau: np.ndarray, count: int = 40) -> tuple[np.ndarray, np.ndarray]:
        """Hub angle and tip of a record from rest, the torque held between the samples: the rigid body and ``count``
        flexible modes, each discretised exactly."""
        h = float(t[1] - t[0])
        J = self.rho * self.L**3 / 3 + self.J_h + self.m_p * self.L**2 + self.J_p  # the rigid mode u = x
        blocks = [(np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([0.0, 1.0 / J]), 1.0, self.L)]
        for f in self.frequencies(count):
            w = 2 * np.pi * f
            hub, tip, mass = self._mode(w)
            blocks.append((np.array([[0.0, 1.0], [-w * w, -self.a * w * w]]), np.array([0.0, hub / mass]), hub, tip))
        theta = np.zeros(t.size)
        y = np.zeros(t.size)
        for A, B, hub, tip in blocks:
            E = sla.expm(np.block([[A, B[:, None]], [np.zeros((1, 3))]]) * h)
            Ad, Bd = E[:2, :2], E[:2, 2]
            q = np.zeros((t.size, 2))
            x = np.zeros(2)
            for k in range(t.size):
                q[k] = x
                x = Ad @ x + Bd * tau[k]
            theta += hub * q[:, 0]
            y += tip * q[:, 0]
        return theta, y
