"""What the study runs on each scene: the quantity it compares, the reference, and the grid of methods.

Each scene has one quantity of interest q, read from the run's history (docs/study.md):

* elastica: the tip deflection at lam = 5, against the closed form of the inextensible elastica;
* beam: the force on the foundation at the full pressure (the tip rests on it, so its deflection is
  fixed by the gap and tells nothing);
* plate: the force on the base at the full pressure (the centre rests on it);
* ring: the crushing force P at the approach delta = 1, with the rigid-plastic load of DeRunz and Hodge
  as a lower bound (the steel hardens).

Without a closed form, the reference is the project's own converged value: Richardson extrapolation in
the mesh size (at twice the default increments) plus the increments' own extrapolated correction on the
default mesh, with the two remainders as its estimated error (study.report.reference).

The grid is one factor at a time around the scene's defaults, plus a sweep of the number of increments
for every stress update (the paper's claim is about increments) and for the other methods.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

# v / L of the inextensible elastica at lam = P L^2 / (E I) = 5 (docs/theory.md section 8.1)
ELASTICA_TIP = 0.71379
# ring: plastic collapse load 4 M_p / R and the crushing curve P0 / sqrt(1 - (delta / D)^2) of a
# rigid-perfectly plastic ring (docs/scenes.md, ring)
RING_P0, RING_D = 459.1, 10.564


@dataclass(frozen=True)
class Case:
    """One run: its family (one curve of the charts), the value of the family's swept parameter, the
    scene overrides."""

    family: str
    x: float
    sets: tuple[str, ...]

    @property
    def tag(self) -> str:
        return "_".join(s.replace("=", "") for s in self.sets) or "default"


@dataclass
class ScenePlan:
    name: str
    column: str                      # history column of q
    at: float | None                 # load level at which q is read (None: the last row)
    label: str                       # what q is, with units
    sign: float = 1.0                # q = sign * column
    closed_form: float | None = None
    bounds: dict = field(default_factory=dict)      # name -> value, drawn on the charts
    n0: int = 20
    size0: float = 0.25
    steps: tuple[int, ...] = ()
    updates: tuple[str, ...] = ("sr", "hughes_winget", "polar", "svk", "neo_hooke")
    contacts: tuple[tuple[str, tuple[str, ...]], ...] = ()
    extra: tuple[tuple[str, tuple[str, ...]], ...] = ()     # other families swept in increments
    predictors: tuple[str, ...] = ("none", "linear", "tangent")

    def cases(self, quick: bool = False) -> list[Case]:
        steps = self.steps[1:4] if quick else self.steps
        out = []
        for u in (self.updates[:2] if quick else self.updates):
            out += [Case(f"update {u}", n, (f"update={u}", f"n_increments={n}")) for n in steps]
        if quick:
            return out
        for name, sets in self.contacts + self.extra:
            out += [Case(name, n, (*sets, f"n_increments={n}")) for n in steps if n in self.steps[1:4]]
        for p in self.predictors:
            out += [Case(f"predictor {p}", n, (f"predictor={p}", f"n_increments={n}")) for n in self.steps[1:4]]
        for degree in (1, 2):
            for f in (2.0, 1.0, 0.5):
                out.append(Case(f"mesh P{degree}", self.size0 * f,
                                (f"degree={degree}", f"size={self.size0 * f:g}")))
        return list(dict.fromkeys(out))

    def reference_cases(self) -> dict[str, Case]:
        """Runs of the reference: three meshes at 2 n0, three increment counts on the default mesh."""
        n2 = 2 * self.n0
        out = {f"h{k}": Case("reference", self.size0 * f, (f"size={self.size0 * f:g}", f"n_increments={n2}"))
               for k, f in enumerate((2.0, 1.0, 0.5))}
        out.update({f"n{k}": Case("reference", n, (f"n_increments={n}",))
                    for k, n in enumerate((self.n0, 2 * self.n0, 4 * self.n0))})
        return out


# penalty at a tenth and ten times the default gamma0 = 100, Nitsche's three variants at the default
ELASTIC_CONTACTS = (("penalty gamma0 10", ("gamma0=10",)), ("penalty gamma0 1000", ("gamma0=1000",)),
                    ("nitsche theta 1", ("contact=nitsche", "theta=1")),
                    ("nitsche theta 0", ("contact=nitsche", "theta=0")),
                    ("nitsche theta -1", ("contact=nitsche", "theta=-1")))


def _ring_bound() -> float:
    return RING_P0 / math.sqrt(1.0 - (1.0 / RING_D) ** 2)


PLANS = {
    "elastica": ScenePlan(
        "elastica", "tip_uy", None, "tip deflection v [cm] at lam = 5", sign=-1.0,
        closed_form=ELASTICA_TIP * 10.0, n0=10, size0=0.125, steps=(1, 2, 3, 5, 10, 20, 40)),
    "beam": ScenePlan(
        "beam", "contact_force", None, "force on the foundation [kgf/cm] at q = 0.5", n0=20, size0=0.125,
        steps=(5, 10, 20, 40, 80),
        contacts=ELASTIC_CONTACTS),
    "plate": ScenePlan(
        "plate", "contact_force", None, "force on the base [kgf] at p = 10", n0=20, size0=0.25,
        steps=(5, 10, 20, 40, 80),
        contacts=ELASTIC_CONTACTS),
    "ring": ScenePlan(
        "ring", "force", 1.0, "crushing force P [kgf/cm] at delta = 1", n0=36, size0=0.22,
        bounds={"rigid-plastic (DeRunz-Hodge), a lower bound": _ring_bound()},
        steps=(9, 18, 36, 72, 144), updates=("sr", "hughes_winget"),
        contacts=(("penalty gamma0 0.3", ("gamma0=0.3",)), ("penalty gamma0 10", ("gamma0=10",)),
                  ("nitsche theta 1", ("contact=nitsche", "gamma0=10", "theta=1")),
                  ("nitsche theta 0", ("contact=nitsche", "gamma0=10", "theta=0")),
                  ("nitsche theta -1", ("contact=nitsche", "gamma0=10", "theta=-1"))),
        extra=(("law chen", ("law=chen",)),)),
}
