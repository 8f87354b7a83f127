"""The contact's share of an explicit step with a mesh body (issue 38): a ~100 k-triangle sphere
under a 10^4-node sheet.

The sphere scene (Sec. 4.2) on an n x n mesh (default 100 x 100: 10 201 nodes) is relaxed to its
draped steady state on the analytic sphere (contact_share.draped).  From that state three integrators
take the same steps, interleaved in rounds so that they see the same machine load
(contact_share.one_pass): with the sphere as a mesh body (gmsh triangles of ``--size``, default
0.085 cm: ~100 k triangles; distance grid spacing ``--spacing``), with the analytic sphere, and
without bodies.  Printed per pass: the mesh body's triangles and grid, element-steps per second, and
the contact's share of a step 1 - rate_with / rate_without for the mesh and the analytic sphere, with
the load average.

    python benchmarks/mesh_contact_share.py [--n 100] [--size 0.085] [--spacing 0.1] [--passes 2]
"""

from __future__ import annotations

import argparse
import copy
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from contact_share import draped, one_pass  # noqa: E402

from solidshell.scenes import Scene, load  # noqa: E402
from solidshell.scenes.build import build_problem  # noqa: E402


def mesh_problem(out_mesh, size: float, spacing: float):
    raw = copy.deepcopy(load("sphere").raw)
    c = raw["contact"][0]
    raw["contact"] = [
        {
            "type": "mesh",
            "primitives": [{"sphere": [*c["centre"], c["radius"]]}],
            "mesh_size": size,
            "spacing": spacing,
            "offset": c["offset"],
            "friction": c["friction"],
        }
    ]
    return build_problem(Scene.from_dict(raw, source="sphere (mesh body)"), out_mesh)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument("--size", type=float, default=0.085, help="the mesh sphere's triangle size [cm]")
    ap.add_argument("--spacing", type=float, default=0.1, help="its distance grid's spacing [cm]")
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--passes", type=int, default=2)
    ap.add_argument("--threads", type=int, default=None)
    a = ap.parse_args(argv)
    t = time.perf_counter()
    prob, bare, U, summary = draped(a.n)
    print(f"sphere {a.n}x{a.n} ({U.shape[0]} nodes) relaxed in {time.perf_counter() - t:.1f} s: DC "
          f"{summary['drape_coefficient']:.4f}", flush=True)  # fmt: skip
    t = time.perf_counter()
    pm = mesh_problem(prob.model.mesh, a.size, a.spacing)
    body = pm.contact[0]
    print(f"mesh body: {body.n_triangles} triangles, grid spacing {body.spacing:g} cm, band {body.band:g} cm, "
          f"{body.n_blocks} blocks ({body.grid.nbytes / 1e6:.1f} MB), built in {time.perf_counter() - t:.1f} s",
          flush=True)  # fmt: skip
    for i in range(a.passes):
        rm = one_pass(pm, bare, U, a.steps, a.rounds, a.threads)
        ra = one_pass(prob, bare, U, a.steps, a.rounds, a.threads)
        print(
            f"pass {i + 1}: {rm['elements']} elements, {rm['face_points']} face points, {rm['threads']} threads: "
            f"mesh body {rm['el_steps_per_s_contact'] / 1e6:.2f} M element-steps/s, without bodies "
            f"{rm['el_steps_per_s_bare'] / 1e6:.2f} M: contact share {100 * rm['contact_share_wall']:.1f} % "
            f"(CPU {100 * rm['contact_share_cpu']:.1f} %); analytic sphere: {100 * ra['contact_share_wall']:.1f} % "
            f"(CPU {100 * ra['contact_share_cpu']:.1f} %); load average "
            f"{' '.join(f'{x:.2f}' for x in rm['loadavg'])}",
            flush=True,
        )


if __name__ == "__main__":
    main()
