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
/// Section V-B, eq (29), Fig 5(a): shape functions of u and t.
pub const FIG5A: &str = include_str!("../examples/specs/fig5a.json");
/// Section VI-A, eq (32), Fig 7(a): G1 local deformation.
pub const FIG7A: &str = include_str!("../examples/specs/fig7a.json");
/// Section VI-B, eq (33)-(37), Fig 8: four- and three-sided patches forming a five-sided one.
pub const FIG8: &str = include_str!("../examples/specs/fig8.json");
