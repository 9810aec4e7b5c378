//! The example specs shipped with the crate (`examples/specs/*.json`), for demos and tests.
//! Each file's `description` says which figure of `dynamic-pde-surfaces.txt` it reproduces.

/// Section III, eq (13), Fig 1: the static problem with a closed-form solution; M = 36, N = 7.
pub const SECTION3: &str = include_str!("../examples/specs/section3.json");
/// Section IV, eq (24)-(26), Fig 2: the glass whose opening turns into petals.
pub const GLASS: &str = include_str!("../examples/specs/glass.json");
/// Section IV, eq (27)-(28), Fig 3: the vase whose upper boundary moves.
pub const VASE: &str = include_str!("../examples/specs/vase.json");
/// Section V-A, Fig 4(a): boundary tangents as a manipulation.
pub const FIG4A: &str = include_str!("../examples/specs/fig4a.json");
/// Section V-B, eq (29), Fig 5(a): shape functions of u and t,
/// `b = b0 (1 - t) u (u - 1)`, `c = c0 (1 + t) u (u - 1)`, `d = d0 (1 + t^2) u (u - 1)`.
///
/// The constants are not the printed ones (issue 22, `docs/pde-figures.md`). With
/// `x = F(u) cos v` the residual of eq (1) is `u (1 - u) [-(B F'''' - C F'' + D F) +
/// u (1 - u) q(u) + k(u)]`, where `B = b0 (1 - t)`, `C = c0 (1 + t)`, `D = d0 (1 + t^2)`, the
/// trial terms of eq (5) are `u^2 (1 - u)^2 p(u)`, `u (1 - u) q(u)` is the free part of the
/// density and damping terms (the basic functions `cos v`, `t^2 cos v`, `t^3 cos v` coincide
/// in shape, so eq (7) sees two independent polynomials) and `k(u)` their known part, linear in
/// u, from the tangent conditions `r1' t^3`, `r0' t^2`. With N = 7 the bracket can vanish: the
/// top coefficients force `F` to degree 5 and the rest reduces to
/// `(B F'''' - C F'' + D F)(u) = k(u)` at u = 0 and 1, so `F` is affine in `d0` (and the
/// shift by rho or eta does not depend on b0, c0, d0 at all). As printed (`b0 = 1, c0 = 2,
/// d0 = -1300`) the middle radius is 11.5 between boundary radii 0.9 and 0.4, and
/// `d0 = -9000` (Fig 5(b)) makes it 76.7: larger |d| more convex, against the paper's "the
/// larger |beta|, the more concave", whatever the magnitude when d0 < 0 with b0, c0 > 0.
/// Reading the text as having lost minus signs and decimal points, `b0 = -1, c0 = -2,
/// d0 = -1.3` (Fig 5(b): `-9`) makes b, c, d >= 0 as in every other example of the paper and
/// gives vases (radii 0.39 to 0.9) in which smaller |b0|, |c0| and larger |d0| are more
/// concave and more damping more convex, as stated; density then also makes the vase more
/// convex (the paper says concave): both enter only through `k`, whose two parts have the same
/// sign at t = 0.5 (`6 t r1' - 2 r0'` and `3 t^2 r1' - 2 t r0'`), so no constants give both
/// of section V-C's statements.
pub const FIG5A: &str = include_str!("../examples/specs/fig5a.json");
/// Section VI-A, eq (32), Fig 7(a): G1 local deformation.
pub const FIG7A: &str = include_str!("../examples/specs/fig7a.json");
/// Section VI-B, eq (33)-(37), Fig 8: four- and three-sided patches forming a five-sided one.
pub const FIG8: &str = include_str!("../examples/specs/fig8.json");
/// Section VI-C, Fig 9: the aircraft (`examples/pde/aircraft.json` at the workspace root):
/// six tube patches carrying fuselage, wings and tail, closed by two five-sided caps of
/// three-sided patches, G1 across every shared boundary; t raises the wing tips.
pub const AIRCRAFT: &str = include_str!("../../../examples/pde/aircraft.json");
