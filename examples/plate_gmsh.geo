// layershell example mesh: a 3 m x 3 m plate in the x-y plane as 3 x 3 nine-node quadrilaterals
// (one per unit square), with physical groups that examples/plate_gmsh.toml uses by name:
//   clamp         (curve)   the edge y = 0                      -> [[supports]] set = "clamp"
//   plate         (surface) all elements                        -> [[loads]] set = "plate"
//   strengthened  (surface) y < 2: concrete + TRC layer         -> [[stacks]] set = "strengthened"
//   plain         (surface) y > 2: concrete only                -> [[stacks]] set = "plain"
//   debonded      (surface) 1 < x < 2, 1 < y < 2 (its 9 nodes)  -> initially_debonded = [{set = "debonded"}]
// Regenerate the .msh (Gmsh 4.1 ASCII) with
//   gmsh plate_gmsh.geo -2 -o plate_gmsh.msh
// or with the Python API: gmsh.open("plate_gmsh.geo"); gmsh.model.mesh.generate(2); gmsh.write("plate_gmsh.msh").
// Surfaces are traversed counter-clockwise seen from +z, so the element normal A3 = A1 x A2 is +z:
// the reference face is the bottom face of the plate and the layers lie above it.

Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
Mesh.ElementOrder = 2;           // quadratic ...
Mesh.SecondOrderIncomplete = 0;  // ... with the centre node: 9-node quadrilaterals
Mesh.RecombineAll = 1;           // quadrilaterals, not triangles

// points (i, j) at x = i, y = j: tag 1 + i + 4 j
For j In {0:3}
  For i In {0:3}
    Point(1 + i + 4 * j) = {i, j, 0, 1.0};
  EndFor
EndFor
// lines along x from (i, j) to (i + 1, j): tag 1 + i + 3 j  (1 ... 12)
For j In {0:3}
  For i In {0:2}
    Line(1 + i + 3 * j) = {1 + i + 4 * j, 2 + i + 4 * j};
  EndFor
EndFor
// lines along y from (i, j) to (i, j + 1): tag 13 + i + 4 j  (13 ... 24)
For j In {0:2}
  For i In {0:3}
    Line(13 + i + 4 * j) = {1 + i + 4 * j, 5 + i + 4 * j};
  EndFor
EndFor
// unit squares (i, j): tag 1 + i + 3 j, counter-clockwise
For j In {0:2}
  For i In {0:2}
    Curve Loop(1 + i + 3 * j) = {1 + i + 3 * j, 14 + i + 4 * j, -(4 + i + 3 * j), -(13 + i + 4 * j)};
    Plane Surface(1 + i + 3 * j) = {1 + i + 3 * j};
  EndFor
EndFor

Transfinite Curve {1:24} = 2;    // one element per unit square
Transfinite Surface {1:9};
Recombine Surface {1:9};

Physical Curve("clamp") = {1, 2, 3};
Physical Surface("plate") = {1:9};
Physical Surface("strengthened") = {1:6};
Physical Surface("plain") = {7:9};
Physical Surface("debonded") = {5};
