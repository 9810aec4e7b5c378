//! The D-NURBS engines as one trait, [`DnurbsEngine`]: what the one D-NURBS model
//! ([`super::generalized::GeneralizedModel`]) asks of the engine under it, whichever it is.
//!
//! Two families implement it, each once, generically over its geometry:
//! - the generalized engine `GeneralizedDnurbs<G>` (`d-nurbs.txt` eq 15 with the matrices of
//!   eqs 16-17 of any geometry `G`, every coordinate dynamic, weights included; section 6.2
//!   constraints), for rational curves and surfaces, swung surfaces (eq 7), triangular
//!   surfaces (section 4.4) and joined patches;
//! - the frozen-weight engine `Dnurbs<G>` (footnote 2: weights held, so eq 16-17's matrices
//!   are constant), for tensor-product surfaces, open curves and the closed periodic curve of
//!   the `ring` primitive (Fig 6).
//!
//! Both step by eq 18 and take the forces of section 6.1. Where the frozen engine lacks
//! something (constraints, weights, a weight penalty) its method refuses with a message that
//! names the generalized engine, and the model's tools leave out the actions it refuses
//! ([`DnurbsEngine::refused_actions`]); its rest shape is control points in its state, so
//! plastic flow and the smooth brush act on it as on the generalized engine's rest
//! coordinates. A control point is what fix, free, move-point and set-weight count: the x, y,
//! z (and w) group of the generalized coordinates, or a point of the frozen engine's net.

use std::ops::Range;

use vclay_core::Vec3;
use vclay_dynamics::DynamicsError;
use vclay_dynamics::dnurbs::{
    Constraint, Dnurbs, DnurbsGeometry, Force, GeneralizedDnurbs, GeneralizedGeometry, Integrator,
    LocalJacobian, Material, QuadratureRule,
};

use crate::error::SessionError;

fn cmd(reason: impl std::fmt::Display) -> SessionError {
    SessionError::command("", "", reason)
}

/// Why a frozen-weight engine refuses a constraint.
pub(crate) const NO_FROZEN_CONSTRAINTS: &str = "the frozen-weight engine has no constraints (section 6.2 needs the generalized engine: `engine = \"generalized\"`)";

/// A D-NURBS engine as the session model drives it (see the [module docs](self)).
pub trait DnurbsEngine: Clone + std::fmt::Debug + Send + Sync + 'static {
    /// The state an undo snapshot and a session file keep (`state()`/`set_state()`).
    type State: Clone + std::fmt::Debug + PartialEq + Send + Sync + 'static;
    /// Whether the weights are frozen (footnote 2).
    fn is_frozen(&self) -> bool;
    /// The actions the engine refuses whatever their values, which the model's tools leave
    /// out: on the frozen engine `constraint` (section 6.2 needs the generalized one) and
    /// `set-weight` (its weights are held).
    fn refused_actions(&self) -> &'static [&'static str] {
        if self.is_frozen() {
            &["constraint", "set-weight"]
        } else {
            &[]
        }
    }
    /// Simulated time.
    fn time(&self) -> f64;
    /// Steps the engine took.
    fn steps(&self) -> u64;
    /// One implicit step of size `dt` (eq 18).
    fn step(&mut self, dt: f64) -> Result<vclay_dynamics::StepReport, DynamicsError>;
    /// The state.
    fn state(&self) -> Self::State;
    /// Puts back a state.
    fn set_state(&mut self, s: &Self::State) -> Result<(), DynamicsError>;
    /// The applied forces (section 6.1).
    fn forces(&self) -> &[Force];
    /// The applied forces, mutably.
    fn forces_mut(&mut self) -> &mut Vec<Force>;
    /// Changes the material (eqs 16-17), keeping the state.
    fn set_material(&mut self, m: Material) -> Result<(), DynamicsError>;
    /// Stops all motion.
    fn stop(&mut self);
    /// The rest shape becomes the current shape.
    fn plastic_reset(&mut self) -> Result<(), DynamicsError>;
    /// Plastic flow (`vclay_core::plasticity`): rest positions follow the points displaced past
    /// the yield distance (per control point on both engines; the rest shape is in both
    /// engines' states, so undo restores it).
    fn plastic_flow(&mut self, fraction: f64, yield_distance: f64) -> Result<usize, SessionError>;
    /// Elastic energy of the current state.
    fn elastic_energy(&self) -> Result<f64, DynamicsError>;
    /// The parameter of the point nearest `x`.
    fn nearest_param(&self, x: &Vec3) -> Result<[f64; 2], DynamicsError>;
    /// The point at `param`.
    fn point_at(&self, param: [f64; 2]) -> Result<Vec3, DynamicsError>;
    /// Distances of the data points (section 7.3) to the model.
    fn data_distances(&self) -> Result<Vec<f64>, DynamicsError>;
    /// Control points, current or at rest (see the [module docs](self)).
    fn control_points(&self, rest: bool) -> Vec<Vec3>;
    /// Whether control point `i` is fixed.
    fn is_point_fixed(&self, i: usize) -> bool;
    /// [`Self::is_point_fixed`] of every control point, in one pass (the display marks them
    /// every frame; one query per point rebuilt the coordinate groups per point).
    fn fixed_points(&self) -> Vec<bool> {
        (0..self.control_points(false).len())
            .map(|i| self.is_point_fixed(i))
            .collect()
    }
    /// Fixes or frees control point `i` (a generalized geometry's default-held coordinates
    /// stay held).
    fn set_point_fixed(&mut self, i: usize, fixed: bool) -> Result<(), DynamicsError>;
    /// Moves control point `i` to `to`, at rest.
    fn move_point(&mut self, i: usize, to: Vec3) -> Result<(), SessionError>;
    /// Sets the weight of control point `i`.
    fn set_weight(&mut self, i: usize, weight: f64) -> Result<(), SessionError>;
    /// The weight penalty (`None`: the weights are held).
    fn weight_penalty(&self) -> Option<f64>;
    /// Sets the weight penalty.
    fn set_weight_penalty(&mut self, c: f64) -> Result<(), SessionError>;
    /// Puts `points` (one per control point) into the rest shape (weights and default-held
    /// coordinates stay).
    fn set_rest_points(&mut self, points: &[Vec3]) -> Result<(), SessionError>;
    /// The constraints (section 6.2).
    fn constraints(&self) -> Vec<Constraint>;
    /// Replaces the constraints by `cs` (`name`, constraint); the error names the one refused.
    fn set_constraints(&mut self, cs: &[(&str, Constraint)]) -> Result<(), SessionError>;
    /// The quadrature rule (`None`: the frozen engine's, picked at construction).
    fn quadrature_rule(&self) -> Option<QuadratureRule>;
    /// The energy stored in the ropes' and data points' springs
    /// (`vclay_dynamics::dnurbs::spring_energy`).
    fn tool_energy(&self) -> f64 {
        vclay_dynamics::dnurbs::spring_energy(
            self.forces(),
            self.time(),
            &|u| self.point_at(u),
            &|x| self.nearest_param(x),
        )
        .unwrap_or(f64::NAN)
    }
}

/// Coordinate ranges of the control points (x, y, z, w) of a generalized geometry.
fn groups<G: GeneralizedGeometry>(g: &G) -> Vec<Range<usize>> {
    g.coordinate_groups()
        .into_iter()
        .filter(|g| g.len() == 4)
        .collect()
}

/// The x, y, z coordinates of the control point whose group is `r` that fix/free act on
/// (those the geometry does not hold by default, `held`).
fn free_coords<'a>(r: &Range<usize>, held: &'a [usize]) -> impl Iterator<Item = usize> + 'a {
    (r.start..r.start + 3).filter(|c| !held.contains(c))
}

/// The x, y, z coordinates of control point `i` that fix/free act on.
fn point_coords<G: GeneralizedGeometry>(g: &G, i: usize) -> Vec<usize> {
    let held = g.default_fixed_coordinates();
    groups(g)
        .get(i)
        .map(|r| free_coords(r, &held).collect())
        .unwrap_or_default()
}

/// Sets x, y, z (and zeroes their velocity) or the weight of control point `i` through the
/// engine's state.
fn edit_coords<G: GeneralizedGeometry + Clone + std::fmt::Debug + Send + Sync + 'static>(
    d: &mut GeneralizedDnurbs<G>,
    i: usize,
    values: &[(usize, f64)],
) -> Result<(), SessionError> {
    let groups = groups(d.geometry());
    let Some(g) = groups.get(i) else {
        return Err(cmd(format!(
            "control point {i} does not exist (there are {})",
            groups.len()
        )));
    };
    let mut s = d.state();
    for &(k, v) in values {
        s.coordinates[g.start + k] = v;
        s.velocity[g.start + k] = 0.0;
    }
    d.set_state(&s).map_err(SessionError::command_from)
}

/// The [`DnurbsEngine`] methods both engine families answer alike: the inherent method of
/// the same name (`$T`: `GeneralizedDnurbs` or `Dnurbs`), the implicit step of eq 18, and the
/// geometry's nearest parameter. Inside the two `impl DnurbsEngine`.
macro_rules! same_in_both {
    ($T:ident) => {
        fn time(&self) -> f64 {
            $T::time(self)
        }
        fn steps(&self) -> u64 {
            $T::steps(self) as u64
        }
        fn step(&mut self, dt: f64) -> Result<vclay_dynamics::StepReport, DynamicsError> {
            $T::step(self, Integrator::Implicit { dt })
        }
        fn state(&self) -> Self::State {
            $T::state(self)
        }
        fn set_state(&mut self, s: &Self::State) -> Result<(), DynamicsError> {
            $T::set_state(self, s)
        }
        fn forces(&self) -> &[Force] {
            $T::forces(self)
        }
        fn forces_mut(&mut self) -> &mut Vec<Force> {
            $T::forces_mut(self)
        }
        fn set_material(&mut self, m: Material) -> Result<(), DynamicsError> {
            $T::set_material(self, m)
        }
        fn stop(&mut self) {
            $T::stop(self)
        }
        fn data_distances(&self) -> Result<Vec<f64>, DynamicsError> {
            $T::data_distances(self)
        }
        fn nearest_param(&self, x: &Vec3) -> Result<[f64; 2], DynamicsError> {
            self.geometry().nearest_param(x)
        }
    };
}

impl<G> DnurbsEngine for GeneralizedDnurbs<G>
where
    G: GeneralizedGeometry + Clone + std::fmt::Debug + Send + Sync + 'static,
{
    type State = vclay_dynamics::dnurbs::GeneralizedState;
    fn is_frozen(&self) -> bool {
        false
    }
    same_in_both!(GeneralizedDnurbs);
    fn plastic_reset(&mut self) -> Result<(), DynamicsError> {
        self.set_rest_shape_to_current()
    }
    fn plastic_flow(&mut self, fraction: f64, yield_distance: f64) -> Result<usize, SessionError> {
        GeneralizedDnurbs::plastic_flow(self, fraction, yield_distance).map_err(SessionError::from)
    }
    fn elastic_energy(&self) -> Result<f64, DynamicsError> {
        GeneralizedDnurbs::elastic_energy(self)
    }
    fn point_at(&self, param: [f64; 2]) -> Result<Vec3, DynamicsError> {
        let mut lj = LocalJacobian::default();
        self.geometry().jacobian_at(param, &mut lj)?;
        Ok(lj.s[0])
    }
    fn control_points(&self, rest: bool) -> Vec<Vec3> {
        let q = if rest {
            self.rest_coordinates()
        } else {
            self.geometry().coordinates()
        };
        groups(self.geometry())
            .iter()
            .map(|g| Vec3::new(q[g.start], q[g.start + 1], q[g.start + 2]))
            .collect()
    }
    fn is_point_fixed(&self, i: usize) -> bool {
        point_coords(self.geometry(), i)
            .first()
            .is_some_and(|&c| self.is_fixed_coordinate(c))
    }
    fn fixed_points(&self) -> Vec<bool> {
        // `point_coords` for every group at once: the groups and the held set built once.
        let held = self.geometry().default_fixed_coordinates();
        groups(self.geometry())
            .iter()
            .map(|r| {
                free_coords(r, &held)
                    .next()
                    .is_some_and(|c| self.is_fixed_coordinate(c))
            })
            .collect()
    }
    fn set_point_fixed(&mut self, i: usize, fixed: bool) -> Result<(), DynamicsError> {
        point_coords(self.geometry(), i)
            .iter()
            .try_for_each(|&c| self.set_fixed_coordinate(c, fixed))
    }
    fn move_point(&mut self, i: usize, to: Vec3) -> Result<(), SessionError> {
        edit_coords(self, i, &[(0, to.x), (1, to.y), (2, to.z)])
    }
    fn set_weight(&mut self, i: usize, weight: f64) -> Result<(), SessionError> {
        edit_coords(self, i, &[(3, weight)])
    }
    fn weight_penalty(&self) -> Option<f64> {
        Some(GeneralizedDnurbs::weight_penalty(self))
    }
    fn set_weight_penalty(&mut self, c: f64) -> Result<(), SessionError> {
        GeneralizedDnurbs::set_weight_penalty(self, c).map_err(SessionError::command_from)
    }
    fn set_rest_points(&mut self, points: &[Vec3]) -> Result<(), SessionError> {
        let held = self.geometry().default_fixed_coordinates();
        let mut q0 = self.rest_coordinates().to_vec();
        for (g, p) in groups(self.geometry()).iter().zip(points) {
            for k in 0..3 {
                if !held.contains(&(g.start + k)) {
                    q0[g.start + k] = p[k];
                }
            }
        }
        self.set_rest_coordinates(&q0).map_err(SessionError::from)
    }
    fn constraints(&self) -> Vec<Constraint> {
        GeneralizedDnurbs::constraints(self).to_vec()
    }
    fn set_constraints(&mut self, cs: &[(&str, Constraint)]) -> Result<(), SessionError> {
        self.clear_constraints();
        for (name, c) in cs {
            self.add_constraint(c.clone())
                .map_err(|e| cmd(format!("constraint `{name}`: {e}")))?;
        }
        Ok(())
    }
    fn quadrature_rule(&self) -> Option<QuadratureRule> {
        Some(GeneralizedDnurbs::quadrature_rule(self))
    }
}

impl<G> DnurbsEngine for Dnurbs<G>
where
    G: DnurbsGeometry + std::fmt::Debug + 'static,
    Dnurbs<G>: Clone + std::fmt::Debug,
{
    type State = vclay_dynamics::dnurbs::DnurbsState;
    fn is_frozen(&self) -> bool {
        true
    }
    same_in_both!(Dnurbs);
    fn plastic_reset(&mut self) -> Result<(), DynamicsError> {
        self.set_rest_shape_to_current();
        Ok(())
    }
    fn plastic_flow(&mut self, fraction: f64, yield_distance: f64) -> Result<usize, SessionError> {
        Dnurbs::plastic_flow(self, fraction, yield_distance).map_err(SessionError::from)
    }
    fn elastic_energy(&self) -> Result<f64, DynamicsError> {
        Ok(Dnurbs::elastic_energy(self))
    }
    /// The point at `param` (its first `G::DIM` entries).
    fn point_at(&self, param: [f64; 2]) -> Result<Vec3, DynamicsError> {
        Ok(self.geometry().basis_at(&param[..G::DIM])?.2)
    }
    fn control_points(&self, rest: bool) -> Vec<Vec3> {
        if rest {
            self.rest_shape().to_vec()
        } else {
            self.geometry().points().to_vec()
        }
    }
    fn is_point_fixed(&self, i: usize) -> bool {
        self.is_fixed(i)
    }
    fn set_point_fixed(&mut self, i: usize, fixed: bool) -> Result<(), DynamicsError> {
        self.set_fixed(i, fixed)
    }
    fn move_point(&mut self, i: usize, to: Vec3) -> Result<(), SessionError> {
        self.move_control_point(i, to)
            .map_err(SessionError::command_from)
    }
    fn set_weight(&mut self, _: usize, _: f64) -> Result<(), SessionError> {
        Err(cmd(
            "the frozen-weight engine holds its weights (footnote 2 of d-nurbs.txt); use `engine = \"generalized\"`",
        ))
    }
    fn weight_penalty(&self) -> Option<f64> {
        None
    }
    fn set_weight_penalty(&mut self, _: f64) -> Result<(), SessionError> {
        Err(cmd(
            "the frozen-weight engine has no weight penalty (its weights are held)",
        ))
    }
    fn set_rest_points(&mut self, points: &[Vec3]) -> Result<(), SessionError> {
        self.set_rest_shape(points).map_err(SessionError::from)
    }
    fn constraints(&self) -> Vec<Constraint> {
        Vec::new()
    }
    fn set_constraints(&mut self, cs: &[(&str, Constraint)]) -> Result<(), SessionError> {
        if cs.is_empty() {
            Ok(())
        } else {
            Err(cmd(NO_FROZEN_CONSTRAINTS))
        }
    }
    fn quadrature_rule(&self) -> Option<QuadratureRule> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::DnurbsEngine;
    use vclay_dynamics::dnurbs::benchmarks;

    /// `fixed_points` (one pass, used by the display every frame) gives `is_point_fixed` of
    /// every control point: a dynamic-weight sheet with its first row held, one more point
    /// held and one point held in `y` only (not a fixed point: its first free coordinate,
    /// `x`, is free).
    #[test]
    fn fixed_points_are_is_point_fixed_of_every_point() {
        let mut d = benchmarks::dynamic_sheet(6).unwrap();
        d.set_point_fixed(20, true).unwrap();
        d.set_fixed_coordinate(4 * 13 + 1, true).unwrap();
        let fixed = d.fixed_points();
        let each: Vec<bool> = (0..36).map(|i| d.is_point_fixed(i)).collect();
        assert_eq!(fixed, each);
        assert!(fixed[20] && !fixed[13] && !fixed[35]);
        assert!(
            fixed.iter().filter(|&&f| f).count() >= 7,
            "the held row and point 20"
        );
    }
}
