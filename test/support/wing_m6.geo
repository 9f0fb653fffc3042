// test/support/wing_m6.geo: a wing as Gmsh meshes one from CAD, for the
// tests that take a surface the project did not make: the ONERA M6
// planform (root chord 0.806, taper 0.56, semispan 1.196, leading edge
// swept 30 degrees), NACA 0010 sections, a sharp trailing edge, flat root
// and tip caps (OpenCASCADE, ruled between the two sections). The sizes
// come from the command line: gmsh -2 wing_m6.geo -clmax H -clmin h
// -clcurv N -o wing.stl -format stl.
SetFactory("OpenCASCADE");
N = 60; c0 = 0.806; c1 = 0.806 * 0.56; yt = 1.196; xt = yt * Tan(30 * Pi / 180);
For s In {0:1}
  y = s * yt; xle = s * xt; c = c0 + s * (c1 - c0);
  up[] = {};
  For i In {0:N}
    x = 0.5 * (1 - Cos(Pi * (N - i) / N));
    t = 0.5 * (0.2969 * Sqrt(x) - 0.1260 * x - 0.3516 * x^2 + 0.2843 * x^3 - 0.1036 * x^4);
    p = newp; Point(p) = {xle + c * x, y, c * t}; up[] += p;
  EndFor
  lo[] = {up[N]};
  For i In {1:N-1}
    x = 0.5 * (1 - Cos(Pi * i / N));
    t = 0.5 * (0.2969 * Sqrt(x) - 0.1260 * x - 0.3516 * x^2 + 0.2843 * x^3 - 0.1036 * x^4);
    p = newp; Point(p) = {xle + c * x, y, -c * t}; lo[] += p;
  EndFor
  lo[] += up[0];
  l1 = newl; Spline(l1) = up[];
  l2 = newl; Spline(l2) = lo[];
  w[s] = newll; Wire(w[s]) = {l1, l2};
EndFor
Ruled ThruSections(1) = {w[0], w[1]};
