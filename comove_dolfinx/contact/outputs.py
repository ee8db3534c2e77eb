"""The contact item's results: the contact zone, its edges, the pressure profile and boundary fields.

A :class:`ContactOutputs` belongs to one :class:`contact.Contact` (``contact.outputs``); the item's
own methods (``zone``, ``zone_edges``, ``profile``, ``peak_pressure``, ``pressure``, ...) hand over to it.

Units and signs: those of the model. The traction of the obstacle on the body is p n_o + q t_o per
unit current area, n_o the obstacle's normal (towards the body), t_o = (-n_o[1], n_o[0]); the
pressure p >= 0. The contact laws give the pressure per unit reference area (``Contact.p_ref``);
divided by the area stretch ``|J F^-T N|`` it is per current area (in axisymmetry the stretch includes the
hoop stretch r / R, so the force is the integral of the traction times 2 pi r over the current
boundary).

What is measured where:

* The profile: pressure, shear and gap at the facet quadrature points of the contact boundary (four
  Gauss points per facet, the points where the residual evaluates the contact law), with their
  reference and current coordinates and the arc length along the boundary, sorted along the
  boundary and the same on every rank (:class:`ContactProfile`).
* The zones: the runs of consecutive profile points with p > 0 (a stiff penalty, gamma0 = 1000, can
  leave single points without pressure inside a zone: the discrete solution opens there). A run that
  reaches the end of the boundary ends at the boundary's end point (a symmetry line, say); elsewhere
  its edge lies between the last point in contact and the first one out, where the pressure reaches
  zero. Near the edge of a smooth contact p^2 falls linearly with the distance to the edge
  (p ~ sqrt(a - x), Hertz's solution and every smooth edge alike), while the discrete pressure
  oscillates from point to point; so a straight line is fitted by least squares to p^2 at the last
  eight points in contact (two facets) and the edge put where it reaches zero, kept between the two
  points (half-way when p^2 does not fall there, e.g. at a sharp corner). The estimate's own error is
  thus below the points' spacing (a quarter to a third of an element); the discrete solution's zone
  differs from the exact one by about as much (docs/api.md, "Contact results", against Hertz).
* The peak pressure: a parabola fitted by least squares to the pressures of the facet with the
  largest mean pressure and its two neighbours, at its largest value there (the discrete pressure
  oscillates by a few per cent from point to point where the penalty is stiff; the fit follows the
  profile's curvature, a facet's mean would not).
* The fields ``pressure`` and ``shear``: nodal values on the boundary (zero elsewhere), lumped
  projections of the quadrature values with the linear hat functions (weights >= 0, so the pressure
  never goes below zero), interpolated onto the boundary field space (the displacement's degree). A
  smoothed field: its support reaches one node past the contact zone. Filled on demand: every read
  gets the current values.

Every method is collective (every rank calls it, and gets the same result).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from .. import compat
from ..mechanics.ufl_dag import unique_nodes
from .obstacles import ContactError

# the reference cells' facets: (first vertex, second vertex, outward normal), dolfinx's numbering
_FACETS = {
    "triangle": (((1, 0), (0, 1), (1, 1)), ((0, 0), (0, 1), (-1, 0)), ((0, 0), (1, 0), (0, -1))),
    "quadrilateral": (((0, 0), (1, 0), (0, -1)), ((0, 0), (0, 1), (-1, 0)), ((1, 0), (1, 1), (1, 0)),
                      ((0, 1), (1, 1), (0, 1))),
}
_COLUMNS = ("X", "Y", "x", "y", "p", "q", "gap", "nx", "ny")      # what the profile expression gives
_C = {name: k for k, name in enumerate(_COLUMNS)}


def gauss_points(n: int) -> np.ndarray:
    """The n Gauss-Legendre points on [0, 1] (the facet rule of a degree 2n - 1 integral)."""
    return 0.5 * (np.polynomial.legendre.leggauss(n)[0] + 1.0)


@dataclass
class ContactProfile:
    """The contact boundary's quadrature points, sorted along the boundary (numpy arrays, n points).

    Attributes
    ----------
    X, x : (n, 2)
        Reference and current coordinates.
    S, s : (n,)
        Reference and current arc length from the start of the boundary (a boundary of several
        pieces: one after the other, without a gap); under linear kinematics (``small_strain``)
        s is the reference one, as every length there.
    p, q : (n,)
        Contact pressure (>= 0) and tangential traction along t_o, per unit current area.
    gap : (n,)
        The gap to the obstacle (negative: penetration).
    normal : (n, 2)
        The obstacle's normal n_o at the point (towards the body): the traction is p n_o + q t_o.
    piece : (n,)
        Which connected piece of the boundary the point lies on (0, 1, ...).

    The boundary starts at its end point with the smallest x (then y) in the reference configuration.
    """

    X: np.ndarray
    x: np.ndarray
    S: np.ndarray
    s: np.ndarray
    p: np.ndarray
    q: np.ndarray
    gap: np.ndarray
    normal: np.ndarray
    piece: np.ndarray


@dataclass
class Zone:
    """One connected part of the contact set: its edges (current coordinates and arc length)."""

    start: np.ndarray          # current coordinates of the edge at the smaller arc length
    end: np.ndarray
    s_start: float
    s_end: float

    @property
    def length(self) -> float:
        return self.s_end - self.s_start


EDGE_POINTS = 8            # points in contact that the edge's fit takes (two facets' worth)


def edge_fraction(d_in: np.ndarray, p_in: np.ndarray, d_out: float) -> float:
    """Where the pressure reaches zero between the last point in contact and the first one out, as
    a fraction of their distance ``d_out`` (0: at the point in contact). ``d_in``, ``p_in``: the
    points in contact nearest the edge, their distances from the last one (0 for it, > 0 into the
    zone) and pressures. Near the edge of a smooth contact p^2 falls linearly towards the edge, so a
    straight line fitted to p^2 by least squares gives the edge where it reaches zero, kept within
    [0, 1]; half-way when the fit does not fall towards the edge or there is one point only."""
    d_in, p_in = np.asarray(d_in, float), np.asarray(p_in, float)
    if d_in.size < 2 or not d_out > 0.0 or np.ptp(d_in) <= 0.0:
        return 0.5
    slope, value = np.polyfit(-d_in, p_in ** 2, 1)           # p^2 = value + slope t, t towards the edge
    if not slope < 0.0:
        return 0.5
    return float(min(max(-value / slope / d_out, 0.0), 1.0))


def zones_of(prof: ContactProfile, ends: list) -> list[Zone]:
    """The contact zones of a profile (runs of points with p > 0 within a piece): ``ends`` gives
    each piece's end points as ((x_start, s_start), (x_end, s_end)), current coordinates and arc
    length."""
    out = []
    for k, ((x0, s0), (x1, s1)) in enumerate(ends):
        idx = np.flatnonzero(prof.piece == k)
        if idx.size == 0:
            continue
        on = prof.p[idx] > 0.0
        if not on.any():
            continue
        d = np.diff(on.astype(np.int8))
        starts = list(np.flatnonzero(d == 1) + 1)
        stops = list(np.flatnonzero(d == -1))
        if on[0]:
            starts.insert(0, 0)
        if on[-1]:
            stops.append(len(on) - 1)
        for a, b in zip(starts, stops):
            run = idx[a:b + 1]
            if a == 0:
                xa, sa = np.asarray(x0, float), float(s0)
            else:
                xa, sa = _edge(prof, run[:EDGE_POINTS], idx[a - 1])
            if b == len(on) - 1:
                xb, sb = np.asarray(x1, float), float(s1)
            else:
                xb, sb = _edge(prof, run[::-1][:EDGE_POINTS], idx[b + 1])
            out.append(Zone(xa, xb, sa, sb))
    return out


def _edge(prof: ContactProfile, inside: np.ndarray, i_out: int) -> tuple[np.ndarray, float]:
    """The edge between ``inside[0]``, the last point in contact (``inside``: it and the ones
    before it), and the first point out ``i_out``."""
    s, i_in = prof.s, inside[0]
    t = edge_fraction(np.abs(s[inside] - s[i_in]), prof.p[inside], abs(s[i_out] - s[i_in]))
    return (prof.x[i_in] + t * (prof.x[i_out] - prof.x[i_in]), float(s[i_in] + t * (s[i_out] - s[i_in])))


def peak_of(prof: ContactProfile, ends: list, npoints: int) -> float:
    """The peak pressure of a profile (``npoints`` points per facet): a parabola fitted by least
    squares to the pressures in contact on the facet of the largest mean pressure and its two
    neighbours, at its largest value within them (or at the end of the boundary they reach); the
    largest pressure when fewer than three points are in contact there. 0 without contact."""
    p = prof.p
    if not (p > 0).any():
        return 0.0
    w = np.polynomial.legendre.leggauss(npoints)[1] / 2.0
    means = (p.reshape(-1, npoints) * w).sum(axis=1)
    k = int(np.argmax(means))
    piece = prof.piece[::npoints]
    facets = [f for f in (k - 1, k, k + 1) if 0 <= f < len(means) and piece[f] == piece[k]]
    pts = (np.array(facets)[:, None] * npoints + np.arange(npoints)).ravel()
    pts = pts[p[pts] > 0]
    if pts.size < 3:
        return float(p.max())
    s = prof.s[pts]
    c2, c1, c0 = np.polyfit(s, p[pts], 2)
    at = [s.min(), s.max()]
    if c2 < 0 and s.min() <= -c1 / (2 * c2) <= s.max():
        at.append(-c1 / (2 * c2))
    (_, s_start), (_, s_end) = ends[piece[k]]
    first, last = np.flatnonzero(piece == piece[k])[[0, -1]]
    if facets[0] == first:
        at.append(s_start)
    if facets[-1] == last:
        at.append(s_end)
    return float(max(c0 + c1 * v + c2 * v * v for v in at))


def _chains(A: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Facets (end points A, B, (n, 2)) joined end to end: (order, flipped, piece) with ``order``
    the facets along the boundary, ``flipped`` where a facet runs from B to A, ``piece`` the
    connected piece of each. A piece starts at its free end with the smallest (x, y) (a closed one
    at its smallest point, towards its smaller neighbour). Deterministic: the same on every rank."""
    n = len(A)
    scale = max(float(np.ptp(np.vstack([A, B]))), 1e-300)
    key = lambda P: [tuple(r) for r in np.rint(P / scale * 1e9).astype(np.int64).tolist()]  # noqa: E731
    ka, kb = key(A), key(B)
    at: dict = {}
    for f in range(n):
        at.setdefault(ka[f], []).append(f)
        at.setdefault(kb[f], []).append(f)
    used = np.zeros(n, dtype=bool)
    order, flipped, piece = [], [], []
    while not used.all():
        free = [k for f in np.flatnonzero(~used) for k in (ka[f], kb[f])
                if sum(not used[g] for g in at[k]) == 1]
        start = min(free) if free else min(k for f in np.flatnonzero(~used) for k in (ka[f], kb[f]))
        cands = [f for f in at[start] if not used[f]]
        f = min(cands, key=lambda g: kb[g] if ka[g] == start else ka[g])
        k, pc = start, (piece[-1] + 1 if piece else 0)
        while True:
            flip = ka[f] != k
            used[f] = True
            order.append(f), flipped.append(flip), piece.append(pc)
            k = ka[f] if flip else kb[f]
            nxt = [g for g in at[k] if not used[g]]
            if not nxt:
                break
            f = nxt[0]
    return np.array(order, dtype=np.int64), np.array(flipped, dtype=bool), np.array(piece, dtype=np.int64)



def _terminals(exprs) -> tuple[list, list]:
    """(coefficients, constants) that the UFL expressions or forms ``exprs`` depend on, each once; the walk
    marks the nodes it has seen by identity (mechanics/ufl_dag.py says why)."""
    seen, funcs, consts = set(), {}, {}
    stack = [i.integrand() for e in exprs if isinstance(e, ufl.Form) for i in e.integrals()]
    stack += [e for e in exprs if not isinstance(e, ufl.Form)]
    while stack:
        e = stack.pop()
        if id(e) in seen:
            continue
        seen.add(id(e))
        if isinstance(e, ufl.Coefficient):
            funcs[id(e)] = e
        elif isinstance(e, ufl.Constant):
            consts[id(e)] = e
        stack.extend(e.ufl_operands)
    return list(funcs.values()), list(consts.values())

class ContactOutputs:
    """The results of one contact item (built by the item's ``attach``, at the end).

    It reads the item's terms (``R_c``, ``p_ref``, ``q_ref``, ``ds_c`` and, with friction, the lag
    state's pressure and the stick/slip indicator) and compiles its forms and expressions on first
    use, so that a run that never asks for a result does not pay for its compilation.
    """

    NPOINTS = 4                # Gauss points per facet: the contact terms' rule (FACET_DEGREE = 7)

    def __init__(self, item, ctx):
        self.item = item
        self.comm = item.comm
        msh = ctx.mesh
        self.mesh = msh
        self._e = fem.Constant(msh, PETSc.ScalarType((0.0, 0.0)))
        S = compat.function_space(msh, "Lagrange", ctx.degree)
        phi = ufl.TestFunction(S)
        # pressure and shear are projected with linear weights (non-negative hat functions), so a
        # pressure that the law keeps >= 0 stays >= 0 at the nodes; then interpolated onto S
        S1 = compat.function_space(msh, "Lagrange", 1)
        phi1 = ufl.TestFunction(S1)
        F = ctx.update.F(ctx.u)
        N = ufl.FacetNormal(msh)
        N3 = ufl.as_vector([N[0], N[1], 0.0])
        cof = ufl.det(F) * ufl.inv(F).T
        stretch = ufl.sqrt(ufl.dot(cof * N3, cof * N3))
        chi = ufl.conditional(ufl.gt(item.p_ref, 0.0), 1.0, 0.0)
        dsc = item.ds_c
        self.ufl = {"force": -ufl.replace(item.R_c, {ctx.v: self._e}), "mass": phi * dsc,
                    "mass1": phi1 * dsc, "p": item.p_ref / stretch * phi1 * dsc}
        if item.mu > 0:
            # reference length of the contact set that slips (friction at its threshold) and sticks
            slipping = ufl.conditional(item._slipping, 1.0, 0.0)
            self.ufl.update(slip=chi * slipping * dsc, stick=chi * (1.0 - slipping) * dsc,
                            q=item.q_ref / stretch * phi1 * dsc)
            if item._p_lag is not None:        # the lagged law's threshold state (none for coulomb)
                self.ufl.update(p_lag=item._p_lag * phi * dsc,
                                lag_force=item._p_lag * ufl.dot(item._n_lag, self._e) * ctx.weight * dsc)
            if item.method == "penalty":
                self.ufl["e"] = item._e_new * phi * dsc
        self.compiled = {}
        if "e" in self.ufl:            # every commit needs it: compiled with the model's forms
            self.form("e")
        self._pressure = fem.Function(S, name="contact_pressure")
        self._shear = fem.Function(S, name="contact_shear")
        self._vec = compat.create_vector(self.form("mass"))
        self._lumped = self.assemble_vec(self.form("mass"))
        self._f1 = fem.Function(S1)
        self._vec1 = compat.create_vector(self.form("mass1"))
        self._lumped1 = self.assemble_vec(self.form("mass1"), self._vec1)
        # nodes of the contact boundary (owned), for the penetration
        fdim = msh.topology.dim - 1
        facets = ctx.facets(item.boundary)
        dofs = fem.locate_dofs_topological(ctx.V.sub(0), fdim, facets)   # unrolled indices of V
        nodes = np.unique(dofs // ctx.V.dofmap.index_map_bs)
        self._nodes = nodes[nodes < ctx.V.dofmap.index_map.size_local]   # owned nodes only
        self._X = ctx.V.tabulate_dof_coordinates()[self._nodes, :2]
        sdofs = fem.locate_dofs_topological(S, fdim, facets)
        self._sdofs = sdofs[sdofs < S.dofmap.index_map.size_local]
        self._off = np.ones(S.dofmap.index_map.size_local + S.dofmap.index_map.num_ghosts, dtype=bool)
        self._off[sdofs] = False                     # dofs away from the contact boundary
        # the boundary field's dof at each of the boundary's nodes (same points, matched by position
        # among the boundary's dofs, ghosts included)
        XS = np.round(S.tabulate_dof_coordinates()[sdofs, :2], 12).tolist()
        key = {tuple(x): int(d) for x, d in zip(XS, sdofs)}
        self._node_sdof = np.array([key.get(tuple(x), -1) for x in np.round(self._X, 12).tolist()],
                                   dtype=np.int64)
        s1 = fem.locate_dofs_topological(S1, fdim, facets)
        self._s1dofs = s1[s1 < S1.dofmap.index_map.size_local]
        self._p1_to_s = self._p1_interpolation(S, S1, ctx.degree)
        self._fields_key, self._depends = None, {}
        self._profile_setup(ctx, facets, stretch, N)

    # -- forms ----------------------------------------------------------------------------------
    def form(self, name: str):
        """The compiled form ``name`` (collective: every rank asks for it at the same point)."""
        if name not in self.compiled:
            self.compiled[name] = fem.form(self.ufl[name])
        return self.compiled[name]

    def assemble_vec(self, form, vec=None) -> np.ndarray:
        """Owned entries of an assembled linear form on the boundary field space (or ``vec``'s)."""
        vec = self._vec if vec is None else vec
        compat.assemble_vector(vec, form)
        return vec.array.copy()

    def _stale(self, last_key, name: str, exprs) -> tuple[bool, tuple]:
        """(whether anything that ``exprs`` depend on changed since ``last_key`` on any rank, the
        new key): the values of their functions and constants (found once, under ``name``).
        Collective."""
        if name not in self._depends:
            funcs, consts = _terminals(exprs)
            self._depends[name] = (funcs, [c for c in consts if c is not self._nref])
        funcs, consts = self._depends[name]
        key = tuple(hash(f.x.array.tobytes()) for f in funcs) + tuple(np.asarray(c.value).tobytes() for c in consts)
        return bool(self.comm.allreduce(key != last_key, op=MPI.LOR)), key

    # -- nodal fields ---------------------------------------------------------------------------
    def update_fields(self) -> None:
        """Contact pressure and tangential traction (per current area) as boundary fields: lumped
        projections with the linear hat functions (weights >= 0: the pressure never goes below
        zero) onto the boundary's vertices, interpolated onto the boundary field space. Recomputed
        only when something they depend on changed. Collective."""
        names = [n for n in ("p", "q") if n in self.ufl]
        stale, key = self._stale(self._fields_key, "fields", [self.ufl[n] for n in names])
        if not stale:
            return
        m, b, g = self._lumped1, self._s1dofs, self._f1
        for name in names:
            f = self._pressure if name == "p" else self._shear
            vals = self.assemble_vec(self.form(name), self._vec1)
            g.x.array[:] = 0.0
            g.x.array[b] = vals[b] / m[b]
            g.x.scatter_forward()
            if self._p1_to_s is None:
                f.interpolate(g)
            else:
                dofs, ea, eb = self._p1_to_s
                f.x.array[dofs] = 0.5 * (g.x.array[ea] + g.x.array[eb])
            f.x.array[self._off] = 0.0                # the interpolation reaches into the cells
            f.x.scatter_forward()
        self._fields_key = key

    def field(self, name: str):
        """The boundary field ``"pressure"`` or ``"shear"``, current (collective)."""
        if name not in ("pressure", "shear"):
            raise ContactError(f"contact field {name!r} is unknown: choose 'pressure' or 'shear'")
        self.update_fields()
        return self._pressure if name == "pressure" else self._shear

    def boundary_values(self, f) -> tuple[np.ndarray, np.ndarray]:
        """(reference coordinates, values) of a boundary field (a Function or its name, ``"pressure"``
        or ``"shear"``) at every node of the contact boundary, gathered on all ranks."""
        if isinstance(f, str):
            f = self.field(f)
        elif f is self._pressure or f is self._shear:
            self.update_fields()
        X = f.function_space.tabulate_dof_coordinates()[self._sdofs, :2]
        return (np.concatenate(self.comm.allgather(X)),
                np.concatenate(self.comm.allgather(f.x.array[self._sdofs])))

    @staticmethod
    def _p1_interpolation(S, S1, degree: int):
        """(dofs of S, the two P1 dofs whose mean is their value) for the interpolation of a P1
        field into the boundary fields' space S (P1 or P2: a vertex takes its value, an edge's
        midpoint the mean of the edge's ends), in numpy: dolfinx's interpolation between two spaces
        cost as much as the rest of the output. None for other degrees."""
        if degree not in (1, 2):
            return None
        tdim = S.mesh.topology.dim
        imap = S.mesh.topology.index_map(tdim)
        n = imap.size_local + imap.num_ghosts
        cs, c1 = compat.cell_dofs(S, n), compat.cell_dofs(S1, n)
        # the P2 triangle's dofs: the vertices, then the edges opposite vertices 0, 1 and 2
        ends = [(0, 0), (1, 1), (2, 2)] + ([(1, 2), (0, 2), (0, 1)] if degree == 2 else [])
        dofs = np.concatenate([cs[:, k] for k in range(len(ends))])
        a = np.concatenate([c1[:, i] for i, _ in ends])
        b = np.concatenate([c1[:, j] for _, j in ends])
        return dofs, a, b

    # -- the profile at the quadrature points ------------------------------------------------------
    def _profile_setup(self, ctx, facets, stretch, N) -> None:
        """The owned facets of the boundary, their cells and local numbers, and the expression of
        the profile's columns on a facet whose reference normal is the Constant ``_nref`` (the
        facet normal of the facet terms, rebuilt from the cell's Jacobian: expressions are
        evaluated in cells)."""
        msh, item = self.mesh, self.item
        tdim = msh.topology.dim
        msh.topology.create_connectivity(tdim - 1, tdim)
        msh.topology.create_connectivity(tdim, tdim - 1)
        fc, cf = msh.topology.connectivity(tdim - 1, tdim), msh.topology.connectivity(tdim, tdim - 1)
        n_owned = msh.topology.index_map(tdim).size_local
        facets = np.asarray(facets, dtype=np.int64)
        cells = fc.array[fc.offsets[facets]]            # a boundary facet has one cell
        keep = cells < n_owned                           # integrated by the rank owning its cell
        self._pfacets, self._pcells = facets[keep], cells[keep].astype(np.int32)
        ref = _FACETS[compat.cell_name(msh)]
        per = cf.offsets[1] - cf.offsets[0]
        cell_facets = cf.array.reshape(-1, per)
        self._local = np.argmax(cell_facets[self._pcells] == self._pfacets[:, None], axis=1)
        t = np.concatenate([[0.0], gauss_points(self.NPOINTS), [1.0]])
        pts = [np.array(a) + t[:, None] * (np.array(b) - np.array(a)) for a, b, _ in ref]
        self._npts = len(t)
        self._points = np.vstack(pts).astype(np.float64)
        self._normals = [np.array(nr, dtype=float) / np.linalg.norm(nr) for _, _, nr in ref]
        self._nref = fem.Constant(msh, PETSc.ScalarType((0.0, 0.0)))
        K = ufl.JacobianInverse(msh)
        Nk = ufl.dot(K.T, self._nref)
        Nk = Nk / ufl.sqrt(ufl.dot(Nk, Nk))
        x = ctx.x + item.u
        obs = item.obstacle
        p = ufl.replace(item.p_ref / stretch, {N: Nk})
        q = ufl.replace(item.q_ref / stretch, {N: Nk}) if item.q_ref is not None else 0.0 * p
        n_o = obs.normal(x)
        self._pexpr_ufl = ufl.as_vector([ctx.x[0], ctx.x[1], x[0], x[1], p, q, obs.gap(x), n_o[0], n_o[1]])
        self._pexpr = None
        self._order = None
        # linear kinematics (an update whose ``geometric`` is False) measures lengths on the reference
        self._geometric = bool(getattr(ctx.update, "geometric", True))
        self._profile_key, self._profile = None, None

    def _evaluate(self) -> np.ndarray:
        """The profile's columns at the six points (end, four Gauss points, end) of every facet of
        the boundary, (facets, 6, columns), in the order of the ranks' facets, on every rank."""
        if self._pexpr is None:
            self._pexpr = compat.expression(unique_nodes(self._pexpr_ufl), self._points)
        nc, npt = len(_COLUMNS), self._npts
        local = np.zeros((len(self._pfacets), npt, nc))
        for k, nr in enumerate(self._normals):
            sel = np.flatnonzero(self._local == k)
            if sel.size == 0:
                continue
            self._nref.value = nr
            vals = compat.evaluate(self._pexpr, self.mesh, self._pcells[sel]).reshape(sel.size, -1, nc)
            local[sel] = vals[:, k * npt:(k + 1) * npt]
        return np.concatenate(self.comm.allgather(local))

    def profile(self) -> ContactProfile:
        """The pressure, shear and gap at the quadrature points of the contact boundary, sorted along
        it (:class:`ContactProfile`; the same on every rank). Collective."""
        self._refresh_profile()
        return self._profile

    def _refresh_profile(self) -> None:
        stale, key = self._stale(self._profile_key, "profile", [self._pexpr_ufl])
        if not stale:
            return
        D = self._evaluate()
        C = _C
        if self._order is None:
            self._order = _chains(D[:, 0, [C["X"], C["Y"]]], D[:, -1, [C["X"], C["Y"]]])
        order, flipped, piece = self._order
        D = D[order]
        D[flipped] = D[flipped, ::-1]
        ends, S_all, s_all = [], np.zeros(D.shape[:2]), np.zeros(D.shape[:2])
        S0 = s0 = 0.0
        ref, cur = (C["X"], C["Y"]), ((C["x"], C["y"]) if self._geometric else (C["X"], C["Y"]))
        for k in range(int(piece.max()) + 1 if piece.size else 0):
            rows = np.flatnonzero(piece == k)
            for col, out, base in ((ref, S_all, S0), (cur, s_all, s0)):
                P = D[rows][:, :, list(col)].reshape(-1, 2)
                seg = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))]
                out[rows] = (base + seg).reshape(len(rows), -1)
            xs = D[rows[0], 0, [C["x"], C["y"]]], D[rows[-1], -1, [C["x"], C["y"]]]
            ends.append(((xs[0], s_all[rows[0], 0]), (xs[1], s_all[rows[-1], -1])))
            S0, s0 = S_all[rows[-1], -1], s_all[rows[-1], -1]
        g = slice(1, self._npts - 1)                  # the Gauss points
        G = D[:, g].reshape(-1, D.shape[2])
        self._profile = ContactProfile(
            X=G[:, [C["X"], C["Y"]]].copy(), x=G[:, [C["x"], C["y"]]].copy(), S=S_all[:, g].ravel(),
            s=s_all[:, g].ravel(), p=G[:, C["p"]].copy(), q=G[:, C["q"]].copy(), gap=G[:, C["gap"]].copy(),
            normal=G[:, [C["nx"], C["ny"]]].copy(), piece=np.repeat(piece, self._npts - 2))
        self._ends = ends
        self._zones = zones_of(self._profile, ends)
        self._peak = peak_of(self._profile, ends, self._npts - 2)
        self._profile_key = key

    def zones(self) -> list[Zone]:
        """The connected parts of the contact set, with their edges (module docstring). Collective."""
        self._refresh_profile()
        return self._zones

    def extent(self) -> float:
        """Current length of the contact set: the sum of its zones' lengths (arc length between
        their edges). Collective."""
        return float(sum(z.length for z in self.zones()))

    def zone_edges(self, axis: int = 0) -> tuple[float, float]:
        """Smallest and largest current coordinate ``axis`` of the contact set's edges (NaN, NaN
        without contact). Collective."""
        zs = self.zones()
        if not zs:
            return np.nan, np.nan
        v = [z.start[axis] for z in zs] + [z.end[axis] for z in zs]
        return float(min(v)), float(max(v))

    def peak_pressure(self) -> float:
        """The peak contact pressure per current area (:func:`peak_of`; 0 without contact). Collective."""
        self._refresh_profile()
        return self._peak

    # -- other results --------------------------------------------------------------------------
    def stick_slip(self) -> tuple[float, float]:
        """Reference lengths of the contact set where friction sticks and where it slips (zeros
        without friction), at the current iterate, from the quadrature points."""
        if "slip" not in self.ufl:
            return 0.0, 0.0
        return tuple(self.comm.allreduce(fem.assemble_scalar(f), op=MPI.SUM)
                     for f in (self.form("stick"), self.form("slip")))

    def max_penetration(self) -> float:
        """The largest -g over the nodes of the contact boundary (0 if none)."""
        item = self.item
        x = self._X + item.u.x.array.reshape(-1, 2)[self._nodes]
        g = item.obstacle.gap_np(x, item.obstacle.displacement(item.factor))
        return self.comm.allreduce(float(max(-g.min(), 0.0)) if g.size else 0.0, op=MPI.MAX)
