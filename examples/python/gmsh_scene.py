#!/usr/bin/env python3
"""A scene from a Gmsh mesh read with meshio: the tets and their physical groups become a
softkin.Scene (scene_from_arrays), which is then bent and written for ParaView.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/gmsh_scene.py --mesh my.msh \\
        --chamber-tag 2 --out bent.vtu

Without --mesh it first writes a small bilayer bar (physical groups 1: body, 2: chamber) as a
Gmsh file with meshio, so that it runs anywhere meshio is installed (Debian python3-meshio).
The fixed face is the mesh's x = min face, the tip marker its x = max face.
"""
import argparse
import os
import tempfile

import numpy as np

import softkin

try:
    import meshio
except ImportError:  # pragma: no cover - the example says what to install
    raise SystemExit("this example needs meshio: apt-get install python3-meshio")


def write_bilayer_bar(path, nx=10, ny=2, nz=2, h=2.0):
    """A bar of nx x ny x nz cubes (edge h, mm), six tets per cube (mirrored in y every other
    row, so that the mesh is symmetric about the mid-plane y = ny h / 2 for even ny); the upper
    half is tagged 2 (chamber), the lower half 1 (body). Written as Gmsh 2.2 with physical
    groups."""
    idx = lambda i, j, k: i + (nx + 1) * (j + (ny + 1) * k)
    points = np.array([[i * h, j * h, k * h] for k in range(nz + 1) for j in range(ny + 1)
                       for i in range(nx + 1)], dtype=float)
    tets, tags = [], []
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                m = j >= ny // 2  # mirror the upper half of the rows
                corner = lambda b: idx(i + (b & 1), j + (((b >> 1) & 1) ^ m), k + ((b >> 2) & 1))
                for a, b in [(1, 3), (1, 5), (2, 3), (2, 6), (4, 5), (4, 6)]:
                    tets.append([corner(0), corner(a), corner(b), corner(7)])
                    tags.append(2 if k >= nz // 2 else 1)
    mesh = meshio.Mesh(points, [("tetra", np.array(tets))],
                       cell_data={"gmsh:physical": [np.array(tags)],
                                  "gmsh:geometrical": [np.array(tags)]})
    meshio.write(path, mesh, file_format="gmsh22", binary=False)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", help="a Gmsh .msh file with tets in physical groups")
    ap.add_argument("--chamber-tag", type=int, default=2, help="physical group of the chamber")
    ap.add_argument("--alpha", type=float, default=1.5, help="chamber volume ratio")
    ap.add_argument("--out", default="gmsh_scene.vtu", help="deformed mesh for ParaView")
    args = ap.parse_args()

    path = args.mesh
    if path is None:
        path = os.path.join(tempfile.mkdtemp(), "bilayer_bar.msh")
        write_bilayer_bar(path)
        print(f"wrote {path}")
    mesh = meshio.read(path)
    tets = np.vstack([c.data for c in mesh.cells if c.type == "tetra"])
    tags = np.concatenate([d for c, d in zip(mesh.cells, mesh.cell_data["gmsh:physical"])
                           if c.type == "tetra"])
    lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
    eps = 1e-6 * np.linalg.norm(hi - lo)
    regions = [{"tag": int(t), "role": "pneumatic", "name": "chamber", "max": 3}
               if t == args.chamber_tag else {"tag": int(t), "role": "body"}
               for t in np.unique(tags)]
    scene = softkin.scene_from_arrays(
        mesh.points, tets, tags, regions=regions,
        fixed=[{"plane": {"point": lo.tolist(), "normal": [1, 0, 0]}}],
        markers=[{"name": "tip", "box": {"min": [hi[0] - eps, lo[1] - 1, lo[2] - 1],
                                         "max": [hi[0] + eps, hi[1] + 1, hi[2] + 1]}}],
        name=os.path.splitext(os.path.basename(path))[0])
    print(scene)
    result = softkin.solve_fk(scene, args.alpha)
    tip0 = scene.marker_positions(scene.vertices)["tip"]
    print(f"{result.status} in {result.iterations} iterations; tip moved "
          f"{np.round(result.markers['tip'] - tip0, 2)} mm; chamber volume ratio "
          f"{result.volume_ratios[0]:.3f}")
    result.write_vtu(args.out)
    print(f"wrote {args.out}")
    if not result.converged:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
