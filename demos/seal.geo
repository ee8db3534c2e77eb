// O-ring seal section for demos/demo_seal.py: the quarter x >= 0, y >= 0 of a circle of radius R
// centred at the origin (cm). The upper plate touches the circle at its crown (0, R), where the
// contact starts and spreads along the arc as the plate moves down; the elements are small there
// (size_top) and grow with the distance from the crown to size_far.
//
// Physical groups, read by name with cm.load_msh(..., required=("xsym", "ysym", "outer")):
//   Curve "xsym"  the edge on x = 0 (symmetry: u_x = 0)
//   Curve "ysym"  the edge on y = 0 (symmetry: u_y = 0)
//   Curve "outer" the arc, which meets the plate
//   Surface "body"
// Mesh it with `gmsh -2 -order 2 seal.geo` (the demo does the same through gmsh's Python API).

R = 1.0;            // radius [cm]
size_top = 0.015;   // element size at the crown [cm]
size_far = 0.10;    // element size far from it [cm]
refined = 0.12;     // distance from the crown within which the size stays size_top [cm]
growth = 0.5;       // growth of the size beyond that, per unit distance

Point(1) = {0, 0, 0, size_far};   // centre
Point(2) = {R, 0, 0, size_far};   // where the arc meets y = 0
Point(3) = {0, R, 0, size_top};   // the crown, first contact with the plate

Line(1) = {1, 2};                 // on y = 0
Circle(2) = {2, 1, 3};            // the outer arc, counter-clockwise
Line(3) = {3, 1};                 // on x = 0
Curve Loop(1) = {1, 2, 3};
Plane Surface(1) = {1};

// element size: size_top within `refined` of the crown, then growing linearly to size_far
Field[1] = Distance;
Field[1].PointsList = {3};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = size_top;
Field[2].SizeMax = size_far;
Field[2].DistMin = refined;
Field[2].DistMax = refined + (size_far - size_top) / growth;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Curve("ysym") = {1};
Physical Curve("outer") = {2};
Physical Curve("xsym") = {3};
Physical Surface("body") = {1};
