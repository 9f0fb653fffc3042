# test/io_gmsh/data/make_gmsh_data.py: regenerates the Gmsh-written test files
# (needs Gmsh's Python API; these were made with Gmsh 4.8.4): mixed.geo meshed,
# saved as MSH 4.1 and 2.2, ASCII and binary, with a node dataset of two time
# steps ("xyz sum" = x + 2y + 4z, then its negative) and a 2-component element
# dataset ("cell id" = tag, -tag) on the volume cells; and as MEDIT .mesh.
import os

import gmsh

here = os.path.dirname(os.path.abspath(__file__))
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.open(os.path.join(here, "mixed.geo"))
gmsh.model.mesh.generate(3)
gmsh.option.setNumber("PostProcessing.SaveMesh", 0)
gmsh.option.setNumber("PostProcessing.SaveInterpolationMatrices", 0)
tags, xyz, _ = gmsh.model.mesh.getNodes()
vals = [[xyz[3 * i] + 2 * xyz[3 * i + 1] + 4 * xyz[3 * i + 2]] for i in range(len(tags))]
v = gmsh.view.add("xyz sum")
gmsh.view.addModelData(v, 0, "", "NodeData", list(tags), vals)
gmsh.view.addModelData(v, 1, "", "NodeData", list(tags), [[-x[0]] for x in vals], 1.0)
_, etags, _ = gmsh.model.mesh.getElements(3)
cells = [t for block in etags for t in block]
w = gmsh.view.add("cell id")
gmsh.view.addModelData(w, 0, "", "ElementData", cells, [[float(t), -float(t)] for t in cells])
for version, binary, name in [(4.1, 0, "gmsh41a.msh"), (4.1, 1, "gmsh41b.msh"),
                              (2.2, 0, "gmsh22a.msh"), (2.2, 1, "gmsh22b.msh")]:
    path = os.path.join(here, name)
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.option.setNumber("Mesh.Binary", binary)
    gmsh.write(path)
    gmsh.view.write(v, path, append=True)
    gmsh.view.write(w, path, append=True)
gmsh.option.setNumber("Mesh.Binary", 0)
gmsh.write(os.path.join(here, "gmsh.mesh"))
gmsh.finalize()
