//! Exact NURBS primitives: circles, surfaces of revolution, tori, spheres, boxes.
//!
//! The full circle is the standard nine-point rational quadratic (Piegl & Tiller section 7.5):
//! corners of the circumscribed square with weight `sqrt(2)/2`, knots
//! `{0,0,0,1/4,1/4,1/2,1/2,3/4,3/4,1,1,1}`. A surface of revolution is the tensor product of a
//! profile curve with that circle (Piegl & Tiller section 8.5), so spheres and tori are exact.

use crate::curve::NurbsCurve;
use crate::error::SplineError;
use crate::knots::KnotVector;
use crate::surface::NurbsSurface;
use vclay_core::Vec3;

const CIRCLE_KNOTS: [f64; 12] = [0., 0., 0., 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1., 1., 1.];

/// Unit-circle control points (in the xy-plane) and weights.
fn unit_circle() -> (Vec<(f64, f64)>, Vec<f64>) {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let pts = vec![
        (1., 0.),
        (1., 1.),
        (0., 1.),
        (-1., 1.),
        (-1., 0.),
        (-1., -1.),
        (0., -1.),
        (1., -1.),
        (1., 0.),
    ];
    let w = vec![1., h, 1., h, 1., h, 1., h, 1.];
    (pts, w)
}

impl NurbsCurve {
    /// The exact circle of `radius` around `center` in the plane spanned by the orthonormal
    /// directions `x_axis`, `y_axis`, starting at `center + radius x_axis`, counter-clockwise.
    pub fn circle(
        center: Vec3,
        x_axis: Vec3,
        y_axis: Vec3,
        radius: f64,
    ) -> Result<Self, SplineError> {
        if !(radius.is_finite() && radius > 0.0) {
            return Err(SplineError::Shape {
                what: "circle radius must be positive; radius given (as integer part)".into(),
                found: radius.max(0.0) as usize,
                expected: 1,
            });
        }
        let (pts, w) = unit_circle();
        let points = pts
            .into_iter()
            .map(|(a, b)| center + (x_axis * a + y_axis * b) * radius)
            .collect();
        Self::new(2, CIRCLE_KNOTS.to_vec(), points, Some(w))
    }
}

impl NurbsSurface {
    /// Revolves `profile` (given in the xz-plane, x >= 0 the distance from the axis) a full turn
    /// around the z axis, counter-clockwise seen from +z. Parameter u follows the profile, v the
    /// rotation; the normal `S_u x S_v` points away from the axis where the profile runs
    /// downwards (towards -z).
    pub fn revolve(profile: &NurbsCurve) -> Result<Self, SplineError> {
        let (circle, cw) = unit_circle();
        let n = profile.control_points().len();
        let mut pts = Vec::with_capacity(n * 9);
        let mut ws = Vec::with_capacity(n * 9);
        for (p, &w) in profile.control_points().iter().zip(profile.weights()) {
            for ((a, b), &c) in circle.iter().zip(&cw) {
                pts.push(Vec3::new(p.x * a, p.x * b, p.z));
                ws.push(w * c);
            }
        }
        let kv = KnotVector::new(CIRCLE_KNOTS.to_vec(), 2, 9)
            .map_err(|source| SplineError::Knots { axis: 1, source })?;
        Self::from_flat([profile.knots().clone(), kv], pts, ws)
    }

    /// The exact torus around the z axis with major radius `major` and tube radius `minor`
    /// (`0 < minor < major`). Its normal `S_u x S_v` points out of the solid torus: the tube
    /// circle runs clockwise in the xz-plane (downwards on its outer side), so that with the
    /// counter-clockwise sweep of [`NurbsSurface::revolve`] the closed surface is oriented
    /// outward, as mesh and CAD consumers expect.
    pub fn torus(major: f64, minor: f64) -> Result<Self, SplineError> {
        let c = NurbsCurve::circle(Vec3::new(major, 0., 0.), Vec3::x(), -Vec3::z(), minor)?;
        Self::revolve(&c)
    }

    /// The exact sphere of `radius` around the origin (poles on the z axis), oriented outward
    /// (`S_u x S_v` points away from the centre): u runs from the north pole to the south pole.
    pub fn sphere(radius: f64) -> Result<Self, SplineError> {
        // Half circle from the north pole to the south pole in the xz-plane.
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let r = radius;
        let profile = NurbsCurve::new(
            2,
            vec![0., 0., 0., 0.5, 0.5, 1., 1., 1.],
            vec![
                Vec3::new(0., 0., r),
                Vec3::new(r, 0., r),
                Vec3::new(r, 0., 0.),
                Vec3::new(r, 0., -r),
                Vec3::new(0., 0., -r),
            ],
            Some(vec![1., h, 1., h, 1.]),
        )?;
        Self::revolve(&profile)
    }
}
