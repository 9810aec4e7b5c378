//! What a picture shows: shaded meshes, polylines (control nets, lattices, springs) and point
//! markers (data points, constraints, forces).

use crate::error::RenderError;
use vclay_core::{TriMesh, Vec3};

/// An 8-bit sRGB colour.
pub type Rgb = [u8; 3];

/// Default surface colour: a clay-like terracotta.
pub const CLAY: Rgb = [200, 120, 90];
/// Default colour of control nets and lattices: dark blue-grey.
pub const NET: Rgb = [40, 60, 110];
/// Default colour of point markers: dark red.
pub const MARKER: Rgb = [180, 20, 30];

/// A shaded triangle mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneMesh {
    /// The triangles; per-vertex normals give smooth shading, without them faces are flat.
    pub mesh: TriMesh,
    /// Base colour.
    pub color: Rgb,
    /// Draw the triangle edges in this colour (a mesh wireframe), if set.
    pub edges: Option<Rgb>,
}

/// A polyline drawn with a constant pixel width, hidden behind surfaces.
#[derive(Clone, Debug, PartialEq)]
pub struct Polyline {
    /// Vertices, joined in order.
    pub points: Vec<Vec3>,
    /// Colour.
    pub color: Rgb,
    /// Width in output pixels.
    pub width: f64,
    /// Join the last vertex back to the first.
    pub closed: bool,
}

/// A round point marker with a constant pixel radius, hidden behind surfaces.
#[derive(Clone, Debug, PartialEq)]
pub struct Marker {
    /// Position.
    pub position: Vec3,
    /// Colour.
    pub color: Rgb,
    /// Radius in output pixels.
    pub radius: f64,
}

/// Everything one picture shows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scene {
    /// Shaded meshes.
    pub meshes: Vec<SceneMesh>,
    /// Polylines: control nets, lattice edges, springs, curves.
    pub lines: Vec<Polyline>,
    /// Point markers.
    pub markers: Vec<Marker>,
}

impl Scene {
    /// An empty scene.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a mesh in the default clay colour (builder style).
    pub fn with_mesh(mut self, mesh: TriMesh) -> Self {
        self.add_mesh(mesh, CLAY);
        self
    }

    /// Adds a mesh with a colour.
    pub fn add_mesh(&mut self, mesh: TriMesh, color: Rgb) {
        self.meshes.push(SceneMesh {
            mesh,
            color,
            edges: None,
        });
    }

    /// Adds an open polyline of the given pixel width.
    pub fn add_polyline(&mut self, points: Vec<Vec3>, color: Rgb, width: f64) {
        self.lines.push(Polyline {
            points,
            color,
            width,
            closed: false,
        });
    }

    /// Adds line segments (springs, forces): each pair `(a, b)` becomes a two-point polyline.
    pub fn add_segments(&mut self, segments: &[(Vec3, Vec3)], color: Rgb, width: f64) {
        for &(a, b) in segments {
            self.add_polyline(vec![a, b], color, width);
        }
    }

    /// Adds point markers of the given pixel radius.
    pub fn add_markers(&mut self, points: &[Vec3], color: Rgb, radius: f64) {
        self.markers.extend(points.iter().map(|&position| Marker {
            position,
            color,
            radius,
        }));
    }

    /// Adds the wireframe of a tensor-product control net or lattice: `points` are stored with
    /// the last index fastest (vclay's order), `dims` has 1, 2 or 3 entries whose product is
    /// `points.len()`. Every row along every axis becomes a polyline; net points get markers.
    pub fn add_control_net(
        &mut self,
        points: &[Vec3],
        dims: &[usize],
        color: Rgb,
    ) -> Result<(), RenderError> {
        let total: usize = dims.iter().product();
        if dims.is_empty() || dims.len() > 3 || total != points.len() {
            return Err(RenderError::NonFinite {
                what: format!(
                    "control net of {} points with dimensions {dims:?} (inconsistent shape)",
                    points.len()
                ),
            });
        }
        let mut strides = vec![1usize; dims.len()];
        for a in (0..dims.len().saturating_sub(1)).rev() {
            strides[a] = strides[a + 1] * dims[a + 1];
        }
        for axis in 0..dims.len() {
            // Every start index whose coordinate along `axis` is 0.
            for start in 0..total {
                if !(start / strides[axis]).is_multiple_of(dims[axis]) {
                    continue;
                }
                let row: Vec<Vec3> = (0..dims[axis])
                    .map(|k| points[start + k * strides[axis]])
                    .collect();
                if row.len() > 1 {
                    self.add_polyline(row, color, 1.2);
                }
            }
        }
        self.add_markers(points, color, 2.0);
        Ok(())
    }

    /// Whether the scene has nothing to draw.
    pub fn is_empty(&self) -> bool {
        self.meshes.iter().all(|m| m.mesh.positions.is_empty())
            && self.lines.iter().all(|l| l.points.is_empty())
            && self.markers.is_empty()
    }

    /// Every point of the scene (mesh vertices, polyline vertices, markers).
    pub(crate) fn all_points(&self) -> impl Iterator<Item = &Vec3> + Clone {
        self.meshes
            .iter()
            .flat_map(|m| m.mesh.positions.iter())
            .chain(self.lines.iter().flat_map(|l| l.points.iter()))
            .chain(self.markers.iter().map(|m| &m.position))
    }

    /// A bounding sphere `(centre, radius)`: the box centre and the largest distance from it.
    pub fn bounding_sphere(&self) -> Option<(Vec3, f64)> {
        bounding_sphere(std::slice::from_ref(self))
    }

    /// Checks meshes, polylines and markers for invalid or non-finite data.
    pub fn validate(&self) -> Result<(), RenderError> {
        for (index, m) in self.meshes.iter().enumerate() {
            m.mesh
                .validate()
                .map_err(|source| RenderError::Mesh { index, source })?;
        }
        let finite = |v: &Vec3| v.iter().all(|c| c.is_finite());
        for (i, l) in self.lines.iter().enumerate() {
            if let Some(k) = l.points.iter().position(|p| !finite(p)) {
                return Err(RenderError::NonFinite {
                    what: format!("polyline {i}, point {k}"),
                });
            }
            if !(l.width.is_finite() && l.width >= 0.0) {
                return Err(RenderError::NonFinite {
                    what: format!("polyline {i} width {}", l.width),
                });
            }
        }
        for (i, m) in self.markers.iter().enumerate() {
            if !(finite(&m.position) && m.radius.is_finite() && m.radius >= 0.0) {
                return Err(RenderError::NonFinite {
                    what: format!("marker {i}"),
                });
            }
        }
        Ok(())
    }
}

/// Bounding sphere of several scenes together (used to frame every frame of an animation with
/// one camera). `None` when all are empty.
pub fn bounding_sphere(scenes: &[Scene]) -> Option<(Vec3, f64)> {
    let mut it = scenes.iter().flat_map(|s| s.all_points());
    let first = *it.next()?;
    let (lo, hi) = it.fold((first, first), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
    let centre = 0.5 * (lo + hi);
    let radius = scenes
        .iter()
        .flat_map(|s| s.all_points())
        .map(|p| (p - centre).norm())
        .fold(0.0, f64::max);
    Some((centre, radius))
}
