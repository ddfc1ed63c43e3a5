#!/usr/bin/env python3
"""Writes the unstructured bilayer strip of issue #33 as a Gmsh 2.2 mesh.

A 100 x 10 x 4 mm strip made of two 2 mm layers: the bottom layer z in [0, 2] is physical
volume 0 (the body), the top layer z in [2, 4] is physical volume 1 (the pneumatic actuator).
Both layers are meshed by Gmsh's Delaunay tetrahedraliser with a conforming interface, at a
target element size chosen so that the strip has about 12,000 tets. Only the tets are saved.

Needs the Debian package python3-gmsh. Usage:
    python3 make_bilayer_strip.py [--size H] [--out FILE]
The mesh is deterministic for a given Gmsh version and size (Gmsh 4.8.4 wrote the committed
bilayer_strip_12k.msh with the default size).
"""
import argparse
import sys

try:
    import gmsh
except ImportError:
    sys.exit("make_bilayer_strip.py: needs the Python module gmsh "
             "(Debian: apt-get install python3-gmsh)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=float, default=1.21,
                        help="target element edge length in mm (default 1.21)")
    parser.add_argument("--out", default="bilayer_strip_12k.msh",
                        help="output file (Gmsh 2.2 ASCII)")
    args = parser.parse_args()
    if not args.size > 0:
        sys.exit("make_bilayer_strip.py: --size must be a positive length in mm")

    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.model.add("bilayer_strip")
    occ = gmsh.model.occ
    bottom = occ.addBox(0, 0, 0, 100, 10, 2)
    top = occ.addBox(0, 0, 2, 100, 10, 2)
    # Fragment so that the two layers share the interface's vertices and faces.
    occ.fragment([(3, bottom)], [(3, top)])
    occ.synchronize()
    volumes = gmsh.model.getEntities(3)
    if len(volumes) != 2:
        sys.exit("make_bilayer_strip.py: expected two volumes after fragmenting, got %d"
                 % len(volumes))
    for dim, tag in volumes:
        zmin = gmsh.model.getBoundingBox(dim, tag)[2]
        region = 0 if zmin < 1.0 else 1
        gmsh.model.addPhysicalGroup(3, [tag], region)
    gmsh.option.setNumber("Mesh.MeshSizeMin", args.size)
    gmsh.option.setNumber("Mesh.MeshSizeMax", args.size)
    gmsh.option.setNumber("Mesh.Algorithm3D", 1)  # Delaunay
    gmsh.option.setNumber("Mesh.RandomSeed", 1)
    gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.removeDuplicateNodes()
    types, tags, _ = gmsh.model.mesh.getElements(3)
    count = sum(len(t) for t in tags)
    gmsh.write(args.out)
    gmsh.finalize()
    print("wrote %s: %d tets" % (args.out, count))


if __name__ == "__main__":
    main()
