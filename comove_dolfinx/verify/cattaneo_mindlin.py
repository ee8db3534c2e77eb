"""Cattaneo-Mindlin partial slip: an elastic cylinder pressed onto a rigid flat, then sheared by a
tangential force Q < mu P.

Closed form (Johnson, Contact Mechanics, 1985, section 7.1; Cattaneo 1938; Mindlin 1949), in plane
strain for a line contact of half-width a and peak pressure p0 (Hertz): a central zone ``|x| < c``
sticks, with::

    c = a sqrt(1 - Q / (mu P)),

and the shear traction is the difference of two Hertz-like ellipses::

    q(x) = mu p0 sqrt(1 - x^2 / a^2) - (c / a) mu p0 sqrt(1 - x^2 / c^2)   (|x| < c),
    q(x) = mu p0 sqrt(1 - x^2 / a^2)                                     (c <= |x| <= a).

The closed form assumes that shear does not change the pressure and that the pressing leaves no shear
behind: elastically similar bodies, or here (an elastic body on a rigid flat) Dundurs' parameter
beta = (1 - 2 nu) / (2 (1 - nu)) = 0 (Johnson, section 5.4). With nu = 0.3 (beta = 0.29) the
frictional pressing leaves a stick zone of 0.73 a and outer zones slipping outwards (Spence's
problem), and the measured c misses the formula by 20 % at Q / (mu P) = 0.47; with nu = 0.45 (beta =
0.09) c is within 1.5 % but the pressing's antisymmetric residual shear still tilts the stick zone's
profile by up to 0.2 mu p0; the case takes nu = 0.49 (beta = 0.02).

Problem: the lower half of a cylinder R = 1 (E = 1000, nu = 0.49, P2, element size 0.01 at the
contact, 0.02 with ``small``), its flat cut face held; the flat rises by 0.02 in 5 increments, then
moves sideways by 0.008 in 8, mu = 0.3, penalty (gamma0 = 100) with the default friction law. The
increment whose Q / (mu P) is nearest 0.5 is compared: the stick zone's half-width c (half the
reference length of the contact that sticks, at the facet quadrature points, four per facet: a
resolution of about 3 % of c with ``small``) against a sqrt(1 - Q / (mu P)) with the measured contact
half-width a (half the contact extent), and a against Hertz's a = sqrt(4 P R / (pi E*)), E* = E /
(1 - nu^2); both within 5 %. Measured (``comove verify cattaneo_mindlin``, 2026-11-28, dolfinx 0.5.2, one
process): c 1.1 % and a 0.6 % off (80 Newton iterations, 3.0 s CPU), with ``small`` 1.7 % and 0.3 % (63,
0.8 s). Lengths and forces per unit
thickness in the user's units; Q is the friction force along x on the body, P the normal force.
"""
from __future__ import annotations

import pathlib
import time

import numpy as np

from . import Check

NAME = "cattaneo_mindlin"
TITLE = "Cattaneo-Mindlin partial slip of a cylinder on a flat"
SOURCE = "Johnson, Contact Mechanics (1985), section 7.1; Cattaneo (1938); Mindlin (1949)"

E, NU, MU, R = 1000.0, 0.49, 0.3, 1.0
DEPTH, SHIFT = 0.02, 0.008
N_PRESS, N_SHEAR = 5, 8
TARGET = 0.5                        # Q / (mu P) of the compared increment


def _profile_probe(contact):
    """A probe keeping, at every increment, the contact boundary's nodal pressure and shear traction
    (per current length) at the nodes' reference x (no history column)."""
    import comove_dolfinx as cm

    class Profile(cm.Probe):
        columns = ()

        def __init__(self):
            self.kept = []

        def __call__(self, model):
            contact.update_fields()
            x, p = contact.boundary_values(contact.pressure)
            _, q = contact.boundary_values(contact.shear)
            self.kept.append((x[:, 0].copy(), p.copy(), q.copy()))
            return {}
    return Profile()


def _solve(out: pathlib.Path, small: bool):
    import comove_dolfinx as cm
    from mpi4py import MPI

    mesh = cm.quarter_disc(R, 0.2, 0.02 if small else 0.01, 0.25, order=2, half=True,
                           cache_dir=str(out / "meshes"))
    flat = cm.Plane((0.0, 0.0), (0.0, 1.0),
                    motion=lambda f: (SHIFT * max(f - 1.0, 0.0), DEPTH * min(f, 1.0)))
    c = cm.Contact("contact", flat, method="penalty", gamma0=100.0, mu=MU)
    profile = _profile_probe(c)
    probes = [cm.ContactForce(c, "Q", component=0), cm.ContactForce(c, "P", component=1),
              cm.Value("stick", lambda m: c.stick_slip()[0]), cm.Value("extent", lambda m: c.zone().extent),
              profile]
    job = cm.Job(cm.Body(mesh, "plane_strain", cm.Elastic(E, NU)), [cm.Fixed("top"), c],
                 [cm.Step(N_PRESS, ramp={c: 1.0}), cm.Step(N_SHEAR, ramp={c: 2.0})], probes=probes)
    comm = MPI.COMM_WORLD
    t0 = time.process_time()
    res = job.run()
    cpu = comm.allreduce(time.process_time() - t0, op=MPI.SUM) / comm.size
    return res, profile.kept, cpu


def _plot(path, x, p, q, a, c, p0, ratio):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = np.linspace(-a, a, 401)
    hertz = np.sqrt(np.clip(1 - (s / a) ** 2, 0, None))
    inner = np.where(np.abs(s) < c, (c / a) * np.sqrt(np.clip(1 - (s / c) ** 2, 0, None)), 0.0)
    fig, ax = plt.subplots(figsize=(7, 4.2))
    ax.plot(s / a, hertz, "k-", lw=1, label="Hertz p / p0")
    ax.plot(s / a, hertz - inner, "C1-", lw=1.5, label="Cattaneo-Mindlin q / (mu p0)")
    ax.plot(s / a, hertz, "C1:", lw=1, label="mu p / (mu p0): full slip")
    ax.plot(x / a, p / p0, "ko", ms=3, label="computed p / p0")
    ax.plot(x / a, q / (MU * p0), "C0s", ms=3, label="computed q / (mu p0)")
    for sign in (-1, 1):
        ax.axvline(sign * c / a, color="C1", lw=0.6, ls="--")
    ax.set_xlim(-1.4, 1.4)
    ax.set_ylim(0, 1.15)
    ax.set_xlabel("x / a")
    ax.set_title(f"cylinder on a flat, Q / (mu P) = {ratio:.3f}: stick zone |x| < c = a sqrt(1 - Q/(mu P))")
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def run(out: pathlib.Path, small: bool = False) -> list[Check]:
    """Run the case into ``out`` (``out/cattaneo_mindlin.png``); one Check per compared quantity."""
    from mpi4py import MPI

    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    res, kept, cpu = _solve(out, small)
    its = int(sum(res.newton_its))
    if not res.completed:
        nan = float("nan")
        return [Check(TITLE, SOURCE, q, 1.0, nan, 0.05, its, cpu) for q in
                ("stick half-width c at Q/(mu P) = 0.5", "contact half-width a (Hertz)")]
    P = res["P"]
    ratio = np.abs(res["Q"]) / (MU * P)
    k = int(np.argmin(np.abs(ratio - TARGET)[N_PRESS:])) + N_PRESS
    a = res["extent"][k] / 2
    c = res["stick"][k] / 2
    Es = E / (1 - NU ** 2)
    a_hertz = np.sqrt(4 * P[k] * R / (np.pi * Es))
    p0 = 2 * P[k] / (np.pi * a)
    x, p, q = kept[k]
    inside = p > 0
    centre = 0.5 * (x[inside].min() + x[inside].max()) if inside.any() else 0.0
    tol = 0.05
    if MPI.COMM_WORLD.rank == 0:
        _plot(out / f"{NAME}.png", x - centre, p, np.abs(q), a, a * np.sqrt(1 - ratio[k]), p0, ratio[k])
    return [Check(TITLE, SOURCE, f"stick half-width c at Q/(mu P) = {ratio[k]:.3f}",
                  float(a * np.sqrt(1 - ratio[k])), float(c), tol, its, cpu),
            Check(TITLE, SOURCE, "contact half-width a against Hertz", float(a_hertz), float(a), tol,
                  its, cpu)]
