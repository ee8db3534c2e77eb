"""The accuracy of the contact results against Hertz's line contact (docs/api.md, "Contact results").

    python -m comove_dolfinx.contact.accuracy --out results/contact_accuracy

A quarter of an elastic cylinder (R = 1, E = 1000, nu = 0.3, plane strain, the update ``sr``; ``quarter_disc`` with
element size h at the contact), its flat face pressed down by 0.02 onto a rigid flat, on four meshes,
with penalty and Nitsche (theta = 0) at gamma0 = 10, 100, 1000. Against Hertz at the computed load P
per unit length of the whole cylinder (twice the quarter's): half-width a = sqrt(4 P R / (pi E*)),
E* = E / (1 - nu^2), peak pressure p0 = 2 P / (pi a). Reported: the errors of the half-width from
``ContactEdges`` (its largest x) and ``ContactLength``, of the peak from ``ContactPeak``, and, for
comparison, of the largest x of the boundary nodes where the nodal pressure field is positive (the
support of a smoothed field, one node past the edge). Writes ``hertz_accuracy.csv`` and prints the
table (relative errors in per cent). Built with the public API (and the finished job's model, for the
nodes' positions).
"""
from __future__ import annotations

import argparse
import pathlib
import time

import numpy as np
from mpi4py import MPI

R, E, NU, DEPTH = 1.0, 1000.0, 0.3, 0.02
SIZES = (0.04, 0.02, 0.01, 0.005)
GAMMAS = (10.0, 100.0, 1000.0)
METHODS = ("penalty", "nitsche")


def hertz_run(size: float, method: str, gamma0: float, cache_dir="meshes", depth: float = DEPTH,
              n_increments: int = 2) -> dict:
    """One run; the errors of the contact results against Hertz (relative, signed)."""
    import comove_dolfinx as cm
    t0 = time.process_time()
    mesh = cm.quarter_disc(R, 0.1, size, 0.2, order=2, cache_dir=cache_dir)
    contact = cm.Contact("contact", cm.Plane((0.0, 0.0), (0.0, 1.0)), method=method, gamma0=gamma0)
    items = [cm.Fixed("xsym", component=0), cm.Displacement("top", -depth, component=1), contact]
    probes = [cm.ContactForce(contact, "P", component=1, scale=2.0), cm.ContactEdges(contact, "edge"),
              cm.ContactLength(contact, "half_width"), cm.ContactPeak(contact, "p_max")]
    job = cm.Job(cm.Body(mesh, "plane_strain", cm.Elastic(E, NU), update="sr"), items, [cm.Step(n_increments)], probes)
    res = job.run()
    if not res.completed:
        raise RuntimeError(res.message)
    last = res.last
    P = last["P"]
    a = np.sqrt(4.0 * P * R / (np.pi * E / (1.0 - NU ** 2)))
    p0 = 2.0 * P / (np.pi * a)
    # the nodal field's support: the largest current x of a boundary node (this rank's) with p > 0
    nodes, sdof, model = contact.nodes, contact.node_sdof, job.model
    xn = model.V.tabulate_dof_coordinates()[nodes, :2] + model.u.x.array.reshape(-1, 2)[nodes]
    pressure = contact.pressure.x.array
    pn = np.where(sdof >= 0, pressure[np.maximum(sdof, 0)], 0.0)
    comm = MPI.COMM_WORLD
    support = comm.allreduce(float(xn[pn > 0, 0].max()) if (pn > 0).any() else -np.inf, op=MPI.MAX)
    cpu = comm.allreduce(time.process_time() - t0, op=MPI.SUM) / comm.size
    return dict(size=size, method=method, gamma0=gamma0, P=P, a=a, p0=p0, edge=last["edge_max"],
                length=last["half_width"], peak=last["p_max"], support=support,
                err_edge=last["edge_max"] / a - 1.0, err_length=last["half_width"] / a - 1.0,
                err_peak=last["p_max"] / p0 - 1.0, err_support=support / a - 1.0,
                elements_in_a=a / size, cpu_s=cpu)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("results/contact_accuracy"))
    ap.add_argument("--sizes", type=float, nargs="+", default=list(SIZES))
    ap.add_argument("--gammas", type=float, nargs="+", default=list(GAMMAS))
    ap.add_argument("--methods", nargs="+", default=list(METHODS), choices=METHODS)
    args = ap.parse_args(argv)
    comm = MPI.COMM_WORLD
    if comm.rank == 0:
        args.out.mkdir(parents=True, exist_ok=True)
    rows = []
    if comm.rank == 0:
        print("| method | gamma0 | h | a / h | edge % | length % | peak % | nodal support % | CPU s |\n"
              "|---|---|---|---|---|---|---|---|---|", flush=True)
    for method in args.methods:
        for gamma0 in args.gammas:
            for size in args.sizes:
                rows.append(hertz_run(size, method, gamma0, cache_dir=args.out / "meshes"))
                if comm.rank == 0:
                    r = rows[-1]
                    print(f"| {method} | {gamma0:g} | {size:g} | {r['a'] / size:.1f} | "
                          f"{100 * r['err_edge']:+.2f} | {100 * r['err_length']:+.2f} | {100 * r['err_peak']:+.2f} | "
                          f"{100 * r['err_support']:+.2f} | {r['cpu_s']:.1f} |", flush=True)
    if comm.rank == 0:
        from ..io.csv_tables import write_table
        write_table(args.out / "hertz_accuracy.csv", rows)


if __name__ == "__main__":
    main()
