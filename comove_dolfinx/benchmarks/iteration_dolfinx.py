"""dolfinx: the ring's Newton iteration against plain dolfinx's on the same mesh.

Per ring size, the CPU time of one Newton iteration of the ring's short run (the scene's first
``--increments`` nominal increments: S-R update, J2 return map, contact, friction, predictor, line
searches, cut-backs and failed iterations included; run time / all iterations) against one iteration
of what a user would write with dolfinx alone: the compressible neo-Hookean crown press of
:mod:`~comove_dolfinx.benchmarks.plain_dolfinx` on the same mesh, space, quadrature and supports,
solved by dolfinx's Newton solver with MUMPS (loop time / all iterations). The two run in one
process, alternately (the ring first in even repeats, the plain problem first in odd ones), so that
the machine's drift enters both alike; the ratio of each pair, ring over plain, is the figure. The
linear-elastic floor (:class:`~comove_dolfinx.benchmarks.runs.ElasticFloor`, sampled after every
increment of the ring's runs) is reported beside it as a diagnostic. One rank.
"""
from __future__ import annotations

import json
import pathlib

from .. import compat
from .iteration_floor import _sampled_run
from .plain_dolfinx import PlainNeoHooke, pushes_of
from .runs import COMM, RING_SIZES, build, say, stats, write_csv


def _pairs(size: float, increments: int, repeats: int, overrides) -> list[dict]:
    """``repeats`` pairs (ring run, plain run) at one size, alternating which goes first: each a dict
    of both CPU seconds per iteration, their iterations and the floor's sample."""
    scene, model = build("ring", size, overrides)
    plain = PlainNeoHooke(model, scene.R_out)
    pushes = pushes_of(scene, increments)
    plain.run(pushes[:1])                          # the first factorisation's analysis, not timed
    out = []
    for k in range(repeats):
        order = ("ring", "plain") if k % 2 == 0 else ("plain", "ring")
        got = {}
        for which in order:
            got[which] = (_sampled_run(size, increments, overrides) if which == "ring"
                          else plain.run(pushes))
        (ring, floor), p = got["ring"], got["plain"]
        if not p["converged"]:
            raise RuntimeError(f"the plain neo-Hookean problem did not converge at size {size}")
        out.append({"ring_s": ring["cpu"] / max(ring["iterations"], 1),
                    "plain_s": p["cpu"] / p["iterations"], "ring_its": ring["iterations"],
                    "plain_its": p["iterations"], "floor_s": floor[0], "dofs": ring["dofs"],
                    "residuals_per_it": ring["residuals"] / max(ring["iterations"], 1)})
    return out


def _row(size: float, pairs: list[dict]) -> dict:
    """dolfinx.csv's row of one size: medians and spreads (max - min) over the pairs."""
    row = {"size": size, "dofs": pairs[0]["dofs"], "ring_iterations": pairs[-1]["ring_its"],
           "plain_iterations": pairs[-1]["plain_its"],
           "residuals_per_it": round(pairs[-1]["residuals_per_it"], 2)}
    for key, name in (("plain_s", "plain"), ("ring_s", "ring")):
        row[f"{name}_cpu_s"], row[f"{name}_spread_s"] = stats([p[key] for p in pairs])
    row["ratio"], row["ratio_spread"] = stats([p["ring_s"] / p["plain_s"] for p in pairs])
    row["floor_cpu_s"], _ = stats([p["floor_s"] for p in pairs])
    row["ring_over_floor"], _ = stats([p["ring_s"] / p["floor_s"] for p in pairs])
    return row


def against_dolfinx(out: pathlib.Path, sizes=RING_SIZES, repeats: int = 5, increments: int = 8,
                    overrides=()) -> list[dict]:
    """The ring's iteration against plain dolfinx's at each size, ``repeats`` pairs of runs of
    ``increments`` increments (ring scene parameters ``overrides``, "key=value"): dolfinx.csv (one
    row per size) and dolfinx_pairs.json (every pair's CPU seconds per iteration)."""
    rows, every = [], {}
    for size in sizes:
        pairs = _pairs(size, increments, repeats, overrides)
        every[str(size)] = pairs
        row = _row(size, pairs)
        rows.append(row)
        say(f"ring size {size}: {row['dofs']} dofs, plain dolfinx {row['plain_cpu_s'] * 1e3:.2f} ms/it "
            f"({row['plain_iterations']} its), ring {row['ring_cpu_s'] * 1e3:.2f} ms/it "
            f"({row['ring_iterations']} its), ratio {row['ratio']:.2f} "
            f"(spread {row['ratio_spread']:.2f}), ring / floor {row['ring_over_floor']:.2f}")
    write_csv(out / "dolfinx.csv", rows)
    if COMM.rank == 0:
        (out / "dolfinx_pairs.json").write_text(json.dumps(
            {"increments": increments, "repeats": repeats, "overrides": list(overrides),
             "dolfinx": compat.dolfinx.__version__, "plain_solver": compat.plain_newton_kind(),
             "pairs": every}, indent=1))
    return rows
