"""An independent reference for tests: a linear soft body of revolution in a uniform axial
field by an axisymmetric surface-charge solve (numpy and scipy only).

It shares no code with :mod:`magdesign.fields.soft_surface`: the surface is the body's
generatrix (its outline in the (rho, z) half plane), cut into panels that carry a uniform
surface charge sigma (A/m) as coaxial rings; a ring's field is the closed form in complete
elliptic integrals (scipy.special.ellipkm1 / ellipe, parameter m = k^2, 1 - m computed
directly so that the log singularity at the ring keeps its digits); the panel integrals are
24-point Gauss-Legendre far away, adaptive quadrature (scipy.integrate.quad) within NEAR
panel lengths, and, on a panel's own midpoint, where its normal field is log-singular,
Gauss-Legendre on each half in w with t - t_mid ~ w^3 (smooth in w). The charge satisfies,
at each panel's midpoint (collocation),

    (1 / chi + 1 / 2) sigma - n . H_sigma = H0 . n,

H_sigma the principal-value field of the charge, n the outward normal, chi = mu_r - 1 (the
normal field just inside is H0 . n + n . H_sigma - sigma / 2 and sigma = chi H_in . n).

The mean magnetisation is the moment over the volume, <M> = (integral of sigma z dA) / V,
and the magnetometric demagnetising factor is N_m = H0 / <M> - 1 / chi, the same definition as
soft_surface.demagnetizing_factor's (<M> = chi H0 / (1 + chi N_m); with <H> = <M> / chi it is
N_m = (H0 - <H>) / <M>).

Panels of uniform charge converge like h^2 on the sphere and like about h^1.3 at a
cylinder's edges (the edge charge's singularity); ``extrapolated`` takes the limit of three
panel counts n, 2n, 4n with the order they show (tests/fields/test_soft_accuracy.py
measures how well).
"""

import functools

import numpy as np
from scipy import integrate, special

GAUSS = np.polynomial.legendre.leggauss(24)
NEAR = 3.0  # panels nearer than this many of their lengths to a point: adaptive quadrature


def ring_field(rho, z, radius, height):
    """(H_rho, H_z) (1/m^2) at (rho, z) of a ring of unit total charge (H = q r / (4 pi r^3)),
    of ``radius`` at ``height``, all lengths in m (rho > 0; singular on the ring itself)."""
    dz = z - height
    plus = (rho + radius) ** 2 + dz**2
    minus = (rho - radius) ** 2 + dz**2
    complement = minus / plus  # 1 - m, exact near the ring where m -> 1
    k, e = special.ellipkm1(complement), special.ellipe(1.0 - complement)
    h_z = dz * e / (2.0 * np.pi**2 * np.sqrt(plus) * minus)
    with np.errstate(divide="ignore", invalid="ignore"):
        h_rho = (k + e * (rho**2 - radius**2 - dz**2) / minus) / (4.0 * np.pi**2 * rho * np.sqrt(plus))
    return h_rho, h_z


class Outline:
    """Panels on a generatrix made of pieces; each piece maps t in [0, 1] to (rho, z) and
    gives the outward normal (n_rho, n_z) and the speed |d(rho, z)/dt|."""

    def __init__(self, pieces):
        # pieces: list of (curve, breaks): curve(t) -> (rho, z, n_rho, n_z, speed), breaks the
        # panel ends in t (increasing, 0 .. 1).
        self.panels = [(curve, a, b) for curve, breaks in pieces for a, b in zip(breaks[:-1], breaks[1:])]
        mid = np.array([curve(0.5 * (a + b)) for curve, a, b in self.panels])
        self.rho, self.z, self.n_rho, self.n_z = mid[:, 0], mid[:, 1], mid[:, 2], mid[:, 3]
        self.length = np.array([integrate.quad(lambda t, c=c: c(t)[4], a, b)[0] for c, a, b in self.panels])

    def normal_field(self, i, j):
        """n_i . H at panel i's midpoint of panel j's unit surface charge (principal value)."""
        curve, a, b = self.panels[j]

        def integrand(t):
            rho, z, _, _, speed = np.broadcast_arrays(*curve(t))
            h_rho, h_z = ring_field(self.rho[i], self.z[i], rho, z)
            h_z = np.where(z == self.z[i], 0.0, h_z)  # the same flat disc: no normal field there
            return 2.0 * np.pi * rho * speed * (self.n_rho[i] * h_rho + self.n_z[i] * h_z)

        nodes, weights = GAUSS
        if i == j:  # log-singular at the midpoint: each half with t - mid ~ w^3, smooth in w
            w, half = 0.5 + 0.5 * nodes, 0.5 * (b - a)
            jacobian = 0.5 * weights * 3.0 * w**2 * half
            mid = 0.5 * (a + b)
            return sum(jacobian @ integrand(mid + side * half * w**3) for side in (-1.0, 1.0))
        distance = np.hypot(self.rho[i] - self.rho[j], self.z[i] - self.z[j])
        if distance < NEAR * self.length[j]:
            return integrate.quad(integrand, a, b, epsabs=0.0, epsrel=1e-11, limit=200)[0]
        t = 0.5 * (a + b) + 0.5 * (b - a) * nodes
        return 0.5 * (b - a) * weights @ integrand(t)

    @functools.cached_property
    def operator(self):
        """(P, P): n_i . H at panel i's midpoint of panel j's unit charge."""
        n = len(self.panels)
        return np.array([[self.normal_field(i, j) for j in range(n)] for i in range(n)])

    def solve(self, permeability):
        """The panels' charge sigma (A/m) in a unit axial field H0 = 1 A/m."""
        chi = permeability - 1.0
        system = (1.0 / chi + 0.5) * np.eye(len(self.panels)) - self.operator
        return np.linalg.solve(system, self.n_z)

    def moment(self, sigma):
        """The axial moment (A m^2 for the unit body) of the panels' charge sigma (A/m)."""
        z_area = np.array(
            [
                integrate.quad(lambda t, c=c: 2.0 * np.pi * c(t)[0] * c(t)[1] * c(t)[4], a, b)[0]
                for c, a, b in self.panels
            ]
        )
        return sigma @ z_area


def _graded(n, power):
    """n + 1 points on [0, 1], dense at both ends (power > 1 the stronger)."""
    s = np.linspace(-1.0, 1.0, n + 1)
    return 0.5 + 0.5 * np.sign(s) * (1.0 - (1.0 - np.abs(s)) ** power)


def sphere(panels):
    """A unit sphere: the half circle theta = 0 .. pi in ``panels`` equal arcs."""

    def curve(t):
        theta = np.pi * t
        return np.sin(theta), np.cos(theta), np.sin(theta), np.cos(theta), np.pi

    return Outline([(curve, np.linspace(0.0, 1.0, panels + 1))]), 4.0 / 3.0 * np.pi


def cylinder(ratio, panels, power=2.0):
    """A cylinder of unit radius and length 2 ``ratio`` (length/diameter ``ratio``): top disc
    (centre to rim), side (top to bottom), bottom disc (rim to centre), ``panels`` along each
    disc's radius and about ``panels`` * ratio (at least ``panels``) along the side, graded
    towards the edges."""
    half = ratio

    def top(t):
        return t, half, 0.0, 1.0, 1.0

    def side(t):
        return 1.0, half - 2.0 * half * t, 1.0, 0.0, 2.0 * half

    def bottom(t):
        return 1.0 - t, -half, 0.0, -1.0, 1.0

    disc = _graded(2 * panels, power)[panels:] * 2.0 - 1.0  # dense at the rim only
    along = _graded(panels * max(1, int(round(np.sqrt(ratio)))), power)
    pieces = [(top, disc), (side, along), (bottom, 1.0 - disc[::-1])]
    return Outline(pieces), 2.0 * np.pi * half


def mean_magnetization(body, permeability):
    """<M> / H0 of ``body`` = (outline, volume) in a uniform axial field."""
    outline, volume = body
    return outline.moment(outline.solve(permeability)) / volume


def demagnetizing_factor(body, permeability):
    """The magnetometric factor N_m = H0 / <M> - 1 / chi."""
    return 1.0 / mean_magnetization(body, permeability) - 1.0 / (permeability - 1.0)


def extrapolated(values):
    """The limit of three values at panel counts n, 2n, 4n whose error falls like C h^p, p
    taken from the three (Aitken's delta-squared): (3, ...) -> (...)."""
    values = np.asarray(values)
    step, last = values[1] - values[0], values[2] - values[1]
    return values[2] + last / (step / last - 1.0)


def cylinder_factors(ratio, permeabilities, counts=(10, 20, 40)):
    """N_m of a cylinder of length/diameter ``ratio`` at each permeability, extrapolated from
    the three panel counts ``counts`` (n, 2n, 4n)."""
    values = []
    for panels in counts:
        body = cylinder(ratio, panels)
        values.append([demagnetizing_factor(body, permeability) for permeability in permeabilities])
    return extrapolated(values)
