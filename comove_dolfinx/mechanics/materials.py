"""Materials as objects: elastic constants, or elastic-plastic laws with one update signature.

A body's material is one of

* :class:`Elastic` (E, nu): the stress is the stress update's (hypo- or hyperelastic, see updates.py);
* :class:`J2` (E, nu, hardening): von Mises plasticity, radial return (plane strain, axisymmetry) or
  Simo and Taylor's plane-stress return, with isotropic hardening (docs/theory.md section 4);
* :class:`Chen` (E, nu, hardening): Chen Zhi-da's single-parameter rate law, integrated implicitly:
  the radial return on the law's own loading surface (return_maps.chen_loading_surface).

An elastic-plastic material maps, at every quadrature point, the rotated old stress and the trial
stress of the increment (and the plastic strain of the last converged increment) to the new stress,
its derivatives and, in plane stress, the thickness strain of the increment with its derivatives
(:meth:`Plastic.update`, NumPy); the same map in UFL to be compiled into the stress evaluation
(:meth:`Plastic.compiled`, plane strain and axisymmetry); and the same law in UFL for facet
integrals (:meth:`Plastic.facet`).
Storage: 4-vectors (xx, yy, zz, xy) per point, as in return_maps.py.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import return_maps as rm
from . import return_maps_ufl as rm_ufl
from .material_data import Elastic, Hardening, MaterialError

__all__ = ["Chen", "Elastic", "Hardening", "J2", "MaterialError", "Plastic", "PointUpdate", "as_material"]

PLANE_STRESS = "plane_stress"


@dataclass
class PointUpdate:
    """What a plastic material returns for N points (arrays over the points)."""

    sig: np.ndarray                 # (N, 4) stress at the end of the increment
    p: np.ndarray                   # (N,) equivalent plastic strain
    index: np.ndarray               # (k,) the points that yield
    D: np.ndarray | None            # (k, 4, 4) d sig / d sig_tr at those points (sig depends on sig_rot
                                    # through sig_tr only); elsewhere return_maps.elastic_tangent(kind);
                                    # None when the update was asked for no tangent
    ezz: np.ndarray | None = None   # plane stress: log thickness strain of the increment
    dezz_tr: np.ndarray | None = None    # (N, 4) its derivative by sig_tr
    dezz_rot: np.ndarray | None = None   # (N, 4) its derivative by sig_rot

    def tangent(self, kind: str) -> np.ndarray:
        """d sig / d sig_tr at every point, (N, 4, 4)."""
        return rm.full_tangent(self.index, self.D, len(self.p), kind)


@dataclass(frozen=True)
class Plastic:
    """An elastic-plastic material: elastic constants and a hardening law (docs/theory.md 4)."""

    E: float
    nu: float
    hardening: Hardening
    law = ""

    def __post_init__(self):
        object.__setattr__(self, "elastic", Elastic(self.E, self.nu))
        if not isinstance(self.hardening, Hardening):
            raise MaterialError(f"hardening = {self.hardening!r}: give a Hardening (Hardening(strains, "
                                "stresses), .linear, .perfect or .saturation)")

    def update(self, sig_rot: np.ndarray, sig_tr: np.ndarray, p_n: np.ndarray, kind: str,
               tangent: bool = True) -> PointUpdate:
        """The increment at N points: rotated old stress, trial stress, plastic strain at its start.
        ``tangent`` False: D is not computed where the law can leave it out (its ``D`` is then
        None; the Jacobian takes D x from :meth:`tangent_times`)."""
        out = self._update(sig_rot, sig_tr, p_n, kind, tangent or kind == PLANE_STRESS)
        if kind == PLANE_STRESS:
            out.ezz, out.dezz_tr, out.dezz_rot = rm.plane_stress_thickness(
                out.sig, sig_tr, sig_rot, out.index, out.D, self.elastic)
        return out

    def facet(self, sig_rot, sig_tr, p_n, kind: str, elastic=None):
        """The same law in UFL at a facet point: (stress, thickness strain or None). ``elastic``: the
        elastic constants as UFL values (e.g. the model's Constants; default this material's numbers)."""
        elastic = self.elastic if elastic is None else elastic
        sig = self._facet(sig_rot, sig_tr, p_n, kind, elastic)
        ezz = (rm_ufl.plane_stress_thickness(sig, sig_tr, sig_rot, elastic)
               if kind == PLANE_STRESS else None)
        return sig, ezz

    def compiled(self, sig_tr, p_n, kind: str, elastic, table):
        """The update at the quadrature points in UFL, to be compiled with the stress update:
        (stress, plastic strain) from the trial stress (4-vector) and p_n, or None where the law
        has no compiled form (then :meth:`update` runs in NumPy). ``table``: the loading surface's
        segments as UFL values (return_maps_ufl.Table)."""
        return None

    def tangent_times(self, sig, p, p_n, x, kind: str, elastic, table):
        """D x in UFL, D = d sigma / d sigma_tr of the update, from the state it stored at the points
        (stress sig, plastic strain p, p_n of the converged increment: quadrature functions), for
        the Jacobian; None where D must be stored by each evaluation instead (:meth:`update` with
        ``tangent``)."""
        return None

    def _update(self, sig_rot, sig_tr, p_n, kind, tangent) -> PointUpdate:  # pragma: no cover - interface
        raise NotImplementedError

    def _facet(self, sig_rot, sig_tr, p_n, kind, elastic):  # pragma: no cover - interface
        raise NotImplementedError


class J2(Plastic):
    """Von Mises plasticity with isotropic hardening, backward-Euler return map."""

    law = "j2"

    @property
    def surface(self) -> Hardening:
        """The loading surface sigma_eq = Y(p) that the return map holds the stress on."""
        return self.hardening

    def _update(self, sig_rot, sig_tr, p_n, kind, tangent):
        ret = rm.j2_return_points(sig_tr, p_n, self.elastic, self.surface, kind, tangent=tangent)
        return PointUpdate(ret.sig, ret.p, ret.index, ret.D)

    def compiled(self, sig_tr, p_n, kind, elastic, table):
        if kind == PLANE_STRESS:              # Simo and Taylor's iteration stays in NumPy
            return None
        return rm_ufl.j2_return_points(sig_tr, p_n, elastic, table)

    def tangent_times(self, sig, p, p_n, x, kind, elastic, table):
        if kind == PLANE_STRESS:              # its D comes from Simo and Taylor's iteration
            return None
        return rm_ufl.j2_tangent_times(sig, p, p_n, x, elastic, table)

    def _facet(self, sig_rot, sig_tr, p_n, kind, elastic):
        if kind == PLANE_STRESS:
            return rm_ufl.j2_return_plane_stress(sig_tr, p_n, elastic, self.surface)
        return rm_ufl.j2_return(sig_tr, p_n, elastic, self.surface)


class Chen(J2):
    """Chen Zhi-da's single-parameter rate law, beta = 1 - E_t / (3G) (docs/theory.md section 4.4),
    integrated implicitly: the same flow as J2, held on the law's own loading surface, whose slope
    3G E_t / (3G - E_t) follows from beta (return_maps.chen_loading_surface)."""

    law = "chen"

    def __post_init__(self):
        super().__post_init__()
        if self.hardening.smooth:
            raise MaterialError("Chen's law takes a piecewise-linear hardening table, not a saturation "
                                f"term (dsigma = {self.hardening.dsigma!r}): use J2, or give Chen a table")
        object.__setattr__(self, "_surface", rm.chen_loading_surface(self.elastic, self.hardening))

    @property
    def surface(self) -> Hardening:
        return self._surface


LAWS = {"j2": J2, "chen": Chen}


def as_material(E: float, nu: float, law: str | None = None, hardening: Hardening | None = None):
    """Elastic(E, nu) or the plastic law ``law`` ("j2", "chen") with ``hardening``."""
    if law is None:
        return Elastic(E, nu)
    if law not in LAWS:
        raise MaterialError(f"law = {law!r} is unknown: choose one of {', '.join(LAWS)}")
    return LAWS[law](E, nu, hardening)
