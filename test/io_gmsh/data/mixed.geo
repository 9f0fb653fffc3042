// test/io_gmsh/data/mixed.geo: a mesh with every linear cell type, meshed by
// Gmsh itself for the reader tests (see make_gmsh_data.py).
// Box 1: one hexahedron; box 2: tetrahedra plus a pyramid on the quadrangle it
// shares with box 1; an extruded triangulated rectangle: prisms; physical
// groups with and without names.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {1, 0, 0, 1, 1, 1};
BooleanFragments{ Volume{1, 2}; Delete; }{}
Mesh.MeshSizeMax = 1.0;
Transfinite Curve{:} = 2;
s1[] = Surface In BoundingBox{-0.1, -0.1, -0.1, 1.1, 1.1, 1.1};
Transfinite Surface{s1[]};
Recombine Surface{s1[]};
Transfinite Volume{1};
Rectangle(50) = {0, 0, 1.5, 1, 1};
pr[] = Extrude{0, 0, 1}{ Surface{50}; Layers{1}; Recombine; };
Physical Volume("hex block") = {1};
Physical Volume(7) = {2};
Physical Volume("prism block") = {pr[1]};
Physical Surface("floor") = Surface In BoundingBox{-0.1, -0.1, -0.1, 2.1, 1.1, 0.1};
