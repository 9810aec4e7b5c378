//! Mirror symmetry of the tools (Blender sculpt mode's X / Y / Z toggles).
//!
//! With symmetry on across an axis, an action at point `p` is also made at its mirror image
//! about the plane through the model's bounding-box centre `c` perpendicular to that axis:
//! `p'_i = 2 c_i - p_i` on the mirrored axes (directions `d'_i = -d_i`). With several axes on,
//! every combination of mirrors acts (x and y on: the mirrors x, y and xy, four actions in
//! all). The centre is taken once per press, so the planes do not drift during a stroke.
//!
//! Limitations: the planes are the axis-aligned ones through the bounding box's centre, not a
//! model's own symmetry planes.

use vclay_core::Vec3;
use vclay_session::Ray;

/// Which axes are mirrored (`[x, y, z]`).
pub type Axes = [bool; 3];

/// The tool symmetry: the axes it mirrors across (see the [module docs](self)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Symmetry(pub Axes);

impl Symmetry {
    /// Whether any axis is on.
    pub fn any(self) -> bool {
        self.0.iter().any(|&a| a)
    }

    /// The mirrors besides the identity: every non-empty combination of the axes that are on.
    pub fn mirrors(self) -> Vec<Axes> {
        (1u8..8)
            .map(|m| [m & 1 != 0, m & 2 != 0, m & 4 != 0])
            .filter(|f| (0..3).all(|i| !f[i] || self.0[i]))
            .collect()
    }

    /// Short text for the status bar ("x", "xz"; "off").
    pub fn label(self) -> String {
        let s: String = ["x", "y", "z"]
            .iter()
            .zip(self.0)
            .filter(|(_, on)| *on)
            .map(|(a, _)| *a)
            .collect();
        if s.is_empty() { "off".into() } else { s }
    }
}

/// `p` mirrored across the planes through `centre` of the axes in `flip`.
pub fn reflect(flip: Axes, centre: Vec3, p: Vec3) -> Vec3 {
    let mut q = p;
    for i in 0..3 {
        if flip[i] {
            q[i] = 2.0 * centre[i] - p[i];
        }
    }
    q
}

/// The direction `d` mirrored across the axes in `flip`.
pub fn reflect_dir(flip: Axes, d: Vec3) -> Vec3 {
    let mut q = d;
    for i in 0..3 {
        if flip[i] {
            q[i] = -d[i];
        }
    }
    q
}

/// The ray mirrored across the planes through `centre` (it picks the mirror image of what
/// the ray picks).
pub fn reflect_ray(flip: Axes, centre: Vec3, ray: &Ray) -> Ray {
    Ray {
        origin: reflect(flip, centre, ray.origin),
        direction: reflect_dir(flip, ray.direction),
    }
}

/// The suffix of a mirrored tool's name (`-x`, `-xy`; empty for the identity).
pub fn suffix(flip: Axes) -> String {
    let s: String = ["x", "y", "z"]
        .iter()
        .zip(flip)
        .filter(|(_, on)| *on)
        .map(|(a, _)| *a)
        .collect();
    if s.is_empty() { s } else { format!("-{s}") }
}

/// The centre of the bounding box of `points` (`None` when there is no finite point).
pub fn centre(points: &[Vec3]) -> Option<Vec3> {
    let mut lo = Vec3::repeat(f64::INFINITY);
    let mut hi = Vec3::repeat(f64::NEG_INFINITY);
    for p in points.iter().filter(|p| p.iter().all(|c| c.is_finite())) {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    lo.x.is_finite().then(|| (lo + hi) * 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirrors_are_the_combinations_of_the_axes_on() {
        assert!(Symmetry::default().mirrors().is_empty());
        assert_eq!(
            Symmetry([true, false, false]).mirrors(),
            [[true, false, false]]
        );
        assert_eq!(Symmetry([true, false, true]).mirrors().len(), 3);
        assert_eq!(Symmetry([true; 3]).mirrors().len(), 7);
        assert_eq!(Symmetry([true, false, true]).label(), "xz");
        assert_eq!(suffix([true, true, false]), "-xy");
    }

    #[test]
    fn reflection_is_an_involution_about_the_centre() {
        let c = Vec3::new(0.5, 1.0, -2.0);
        let p = Vec3::new(0.1, 3.0, 0.0);
        let f = [true, false, true];
        let q = reflect(f, c, p);
        assert_eq!(q, Vec3::new(0.9, 3.0, -4.0));
        assert!((reflect(f, c, q) - p).norm() < 1e-12);
        assert_eq!(
            centre(&[Vec3::zeros(), Vec3::new(2.0, 4.0, 6.0)]),
            Some(Vec3::new(1.0, 2.0, 3.0))
        );
    }
}
