//! Face lists of common cell types, for [`crate::Lattice::from_cells`].
//!
//! Each function returns the faces of one cell as vertex loops oriented outward
//! (counter-clockwise seen from outside) when the corners are given in the documented order.

/// A hexahedron: `c[0..4]` the bottom quad counter-clockwise seen from above, `c[4..8]` the top
/// quad with `c[4 + i]` above `c[i]`.
pub fn hexahedron(c: [u32; 8]) -> Vec<Vec<u32>> {
    vec![
        vec![c[0], c[3], c[2], c[1]],
        vec![c[4], c[5], c[6], c[7]],
        vec![c[0], c[1], c[5], c[4]],
        vec![c[1], c[2], c[6], c[5]],
        vec![c[2], c[3], c[7], c[6]],
        vec![c[3], c[0], c[4], c[7]],
    ]
}

/// A prism over any polygon: `bottom` counter-clockwise seen from above, `top[i]` above
/// `bottom[i]`. A triangle gives the triangular prism (wedge).
///
/// # Panics
/// If the loops differ in length or have fewer than 3 vertices.
#[track_caller]
pub fn prism(bottom: &[u32], top: &[u32]) -> Vec<Vec<u32>> {
    assert!(
        bottom.len() == top.len() && bottom.len() >= 3,
        "prism: bad loops"
    );
    let k = bottom.len();
    let mut faces = Vec::with_capacity(k + 2);
    faces.push(bottom.iter().rev().copied().collect());
    faces.push(top.to_vec());
    for i in 0..k {
        let j = (i + 1) % k;
        faces.push(vec![bottom[i], bottom[j], top[j], top[i]]);
    }
    faces
}

/// A tetrahedron: `c[3]` above the triangle `c[0] c[1] c[2]`, which is counter-clockwise seen from
/// above.
pub fn tetrahedron(c: [u32; 4]) -> Vec<Vec<u32>> {
    vec![
        vec![c[0], c[2], c[1]],
        vec![c[0], c[1], c[3]],
        vec![c[1], c[2], c[3]],
        vec![c[2], c[0], c[3]],
    ]
}

/// A pyramid: `c[0..4]` the base counter-clockwise seen from above, `c[4]` the apex above it.
pub fn pyramid(c: [u32; 5]) -> Vec<Vec<u32>> {
    vec![
        vec![c[0], c[3], c[2], c[1]],
        vec![c[0], c[1], c[4]],
        vec![c[1], c[2], c[4]],
        vec![c[2], c[3], c[4]],
        vec![c[3], c[0], c[4]],
    ]
}
