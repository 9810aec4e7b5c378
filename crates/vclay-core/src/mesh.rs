//! Triangle meshes and the sink trait that every tessellator writes through.
//!
//! Tessellators (spline surfaces, volume boundaries, subdivision lattices, PDE surfaces) never build
//! a concrete mesh type: they call a [`MeshSink`], so an exporter, a renderer or the studio can take
//! the triangles in the layout it wants. [`TriMesh`] is the plain indexed mesh that most callers use.

use crate::math::Vec3;
use crate::par::Parallelism;
use rayon::prelude::*;
use thiserror::Error;

/// Receiver of tessellated geometry: vertices (with optional normals) and triangles by index.
///
/// Indices passed to [`MeshSink::add_triangle`] are those returned by [`MeshSink::add_vertex`] on
/// the same sink. Triangles are counter-clockwise seen from the side the normal points to.
pub trait MeshSink {
    /// Hint of how many vertices and triangles will follow (may be ignored).
    fn reserve(&mut self, _vertices: usize, _triangles: usize) {}
    /// Adds a vertex and returns its index.
    fn add_vertex(&mut self, position: Vec3, normal: Option<Vec3>) -> u32;
    /// Adds a triangle by vertex indices.
    fn add_triangle(&mut self, indices: [u32; 3]);
    /// Adds a quad `a b c d` (counter-clockwise) as two triangles split along `a-c`.
    fn add_quad(&mut self, [a, b, c, d]: [u32; 4]) {
        self.add_triangle([a, b, c]);
        self.add_triangle([a, c, d]);
    }
}

/// Problems found by [`TriMesh::validate`].
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshError {
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFiniteVertex {
        /// Index of the vertex.
        vertex: usize,
    },
    /// A triangle references a vertex that does not exist.
    #[error(
        "triangle {triangle} references vertex {index}, but the mesh has {vertex_count} vertices"
    )]
    IndexOutOfRange {
        /// Index of the triangle.
        triangle: usize,
        /// The offending vertex index.
        index: u32,
        /// Number of vertices in the mesh.
        vertex_count: usize,
    },
    /// The normal array is neither empty nor one per vertex.
    #[error("mesh has {normals} normals for {vertices} vertices")]
    NormalCount {
        /// Number of normals.
        normals: usize,
        /// Number of vertices.
        vertices: usize,
    },
}

/// An indexed triangle mesh with optional per-vertex normals.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex unit normals: empty, or one per vertex.
    pub normals: Vec<Vec3>,
    /// Triangles, counter-clockwise.
    pub triangles: Vec<[u32; 3]>,
}

/// Angle between adjacent triangles (of different faces, for a CAD part's display) above
/// which the edge between them is shaded sharp ([`TriMesh::with_creases`]), in degrees: the
/// edges of a box and a hole's rim turn by 90, fillets join their faces tangentially.
pub const CREASE_ANGLE_DEG: f64 = 30.0;

impl TriMesh {
    /// An empty mesh.
    pub fn new() -> Self {
        Self::default()
    }

    /// A surface of revolution about the z axis, with normals: `profile` holds `(r, z)` from
    /// bottom to top, `segments` points around each ring. A ring with `r == 0` becomes one pole
    /// vertex (triangle fans there, quads split in two elsewhere); triangles run
    /// counter-clockwise seen from outside when the profile's outside faces away from the axis.
    /// Starting and ending the profile at `r == 0` closes the surface.
    pub fn revolution(profile: &[(f64, f64)], segments: usize) -> TriMesh {
        let mut mesh = TriMesh::new();
        let mut rings: Vec<Vec<u32>> = Vec::new();
        for &(r, z) in profile {
            if r == 0.0 {
                mesh.positions.push(Vec3::new(0.0, 0.0, z));
                rings.push(vec![mesh.positions.len() as u32 - 1; segments]);
            } else {
                let ring = (0..segments)
                    .map(|s| {
                        let a = std::f64::consts::TAU * s as f64 / segments as f64;
                        mesh.positions.push(Vec3::new(r * a.cos(), r * a.sin(), z));
                        mesh.positions.len() as u32 - 1
                    })
                    .collect();
                rings.push(ring);
            }
        }
        for w in rings.windows(2) {
            let (lo, hi) = (&w[0], &w[1]);
            for s in 0..segments {
                let t = (s + 1) % segments;
                let (a, b, c, d) = (lo[s], lo[t], hi[t], hi[s]);
                if a != b {
                    mesh.triangles.push([a, b, c]);
                }
                if c != d {
                    mesh.triangles.push([a, c, d]);
                }
            }
        }
        mesh.compute_normals();
        mesh
    }

    /// Checks finiteness, index ranges and normal count.
    pub fn validate(&self) -> Result<(), MeshError> {
        if let Some(v) = self
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFiniteVertex { vertex: v });
        }
        if !self.normals.is_empty() && self.normals.len() != self.positions.len() {
            return Err(MeshError::NormalCount {
                normals: self.normals.len(),
                vertices: self.positions.len(),
            });
        }
        let n = self.positions.len();
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&i) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::IndexOutOfRange {
                    triangle: t,
                    index: i,
                    vertex_count: n,
                });
            }
        }
        Ok(())
    }

    /// Replaces the normals by area-weighted averages of the adjacent face normals, in parallel
    /// for large meshes ([`Parallelism::Auto`] from [`NORMALS_PARALLEL_THRESHOLD`] triangles).
    ///
    /// Vertices with no non-degenerate adjacent face get the zero vector.
    pub fn compute_normals(&mut self) {
        self.compute_normals_with(Parallelism::Auto);
    }

    /// [`TriMesh::compute_normals`] with the caller's parallelism policy; `Auto` goes parallel
    /// from [`NORMALS_PARALLEL_THRESHOLD`] triangles.
    ///
    /// The normal of vertex `v` is `s / |s|` (zero where `|s| = 0`), with
    /// `s = 0 + n_{t_1} + n_{t_2} + ...` summed in ascending triangle order over the triangles
    /// `t_k` that reference `v` (twice for a triangle that names it twice), and
    /// `n_t = (b - a) x (c - a)` (twice the area times the unit normal, so area weighting comes
    /// for free). Every policy and thread count performs these same floating-point operations
    /// in the same order, so the normals are the same to the bit.
    ///
    /// In parallel the vertices are cut into contiguous ranges, a few per rayon thread; one
    /// pass over the triangles finds the interval of triangles that touches each range, and
    /// each range's task walks its interval in order, computing the cross products of the
    /// triangles that touch the range and adding them to its own slice of the output. Only the
    /// normals are allocated (and their buffer is reused from the previous call). A mesh whose
    /// triangles join nearby vertex indices (any tessellator's output, a revolution surface)
    /// computes few cross products twice; on a mesh without index locality the ranges fall
    /// back to one per thread, each walking every triangle, and the parallel run gains little.
    ///
    /// # Panics
    /// If a triangle references a vertex that does not exist.
    pub fn compute_normals_with(&mut self, par: Parallelism) {
        let n = self.positions.len();
        // Reuse the buffer of the previous call (a deforming mesh calls this every frame):
        // no allocation and no page faults on fresh memory.
        let mut acc = std::mem::take(&mut self.normals);
        acc.truncate(n);
        let threads = rayon::current_num_threads();
        if threads < 2 || !par.is_parallel_from(self.triangles.len(), NORMALS_PARALLEL_THRESHOLD) {
            acc.clear();
            acc.resize(n, Vec3::zeros());
            for tri in &self.triangles {
                let [a, b, c] = tri.map(|i| self.positions[i as usize]);
                let n = (b - a).cross(&(c - a));
                for &i in tri {
                    acc[i as usize] += n;
                }
            }
            acc.iter_mut().for_each(normalize_or_zero);
        } else {
            normals_parallel(&self.positions, &self.triangles, threads, &mut acc);
        }
        self.normals = acc;
    }

    /// A copy for display with sharp edges kept sharp (what Blender calls auto smooth): at
    /// each vertex, the adjacent triangles are grouped so that a triangle joins a group whose
    /// average normal is within `crease` radians of its own, each group gets its own copy of
    /// the vertex, and each copy the area-weighted average normal of its group. Smooth
    /// regions keep shared vertices and smooth normals; across an edge where the surface
    /// turns by more than `crease` (a box's edges, a hole's rim) the two sides are shaded
    /// apart. The copy is not watertight by index: use it to draw, not to measure or export
    /// as a solid. Degenerate triangles join the first group.
    pub fn with_creases(&self, crease: f64) -> TriMesh {
        self.with_creases_between(crease, None)
    }

    /// [`TriMesh::with_creases`] where the triangles come in parts (`parts[t]`, e.g. the faces
    /// of a CAD part): at a vertex, the triangles of one part always share one copy (its
    /// surface is smooth there, however coarse its triangles), and the copies of different
    /// parts join when their average normals are within `crease` radians. So a fillet meshed
    /// with few triangles still shades smooth, and the sharp edges between faces sharp.
    /// `None`: every triangle a part of its own ([`TriMesh::with_creases`]).
    ///
    /// # Panics
    /// When `parts` is given and its length is not the number of triangles.
    pub fn with_creases_between(&self, crease: f64, parts: Option<&[u32]>) -> TriMesh {
        if let Some(p) = parts {
            assert_eq!(p.len(), self.triangles.len(), "one part per triangle");
        }
        let part = |ti: usize| parts.map_or(ti, |p| p[ti] as usize);
        let cos = crease.cos();
        let n = self.positions.len();
        let face_n: Vec<Vec3> = self
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                (b - a).cross(&(c - a))
            })
            .collect();
        // Triangles around each vertex (CSR layout).
        let mut start = vec![0usize; n + 1];
        for t in &self.triangles {
            for &i in t {
                start[i as usize + 1] += 1;
            }
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut around = vec![(0usize, 0usize); start[n]];
        for (ti, t) in self.triangles.iter().enumerate() {
            for (corner, &i) in t.iter().enumerate() {
                around[fill[i as usize]] = (ti, corner);
                fill[i as usize] += 1;
            }
        }
        let mut out = TriMesh {
            positions: Vec::with_capacity(n),
            normals: Vec::with_capacity(n),
            triangles: self.triangles.clone(),
        };
        let unit = |v: Vec3| {
            let l = v.norm();
            if l > 0.0 { v / l } else { v }
        };
        let mut groups: Vec<(Vec3, u32)> = Vec::new();
        // The parts at a vertex: (part, sum of its triangles' normals, group).
        let mut at: Vec<(usize, Vec3, usize)> = Vec::new();
        for v in 0..n {
            groups.clear();
            at.clear();
            for &(ti, _) in &around[start[v]..start[v + 1]] {
                match at.iter_mut().find(|x| x.0 == part(ti)) {
                    Some(x) => x.1 += face_n[ti],
                    None => at.push((part(ti), face_n[ti], 0)),
                }
            }
            for x in at.iter_mut() {
                let dir = unit(x.1);
                let g = groups
                    .iter()
                    .position(|(sum, _)| dir.norm() == 0.0 || unit(*sum).dot(&dir) >= cos);
                x.2 = match g {
                    Some(g) => g,
                    None => {
                        out.positions.push(self.positions[v]);
                        out.normals.push(Vec3::zeros());
                        groups.push((Vec3::zeros(), (out.positions.len() - 1) as u32));
                        groups.len() - 1
                    }
                };
                groups[x.2].0 += x.1;
            }
            for &(ti, corner) in &around[start[v]..start[v + 1]] {
                let g = at.iter().find(|x| x.0 == part(ti)).map_or(0, |x| x.2);
                out.triangles[ti][corner] = groups[g].1;
            }
            for (sum, id) in &groups {
                out.normals[*id as usize] = unit(*sum);
            }
            if groups.is_empty() {
                // A vertex no triangle uses: kept, with a zero normal.
                out.positions.push(self.positions[v]);
                out.normals.push(Vec3::zeros());
            }
        }
        out
    }

    /// The triangle nearest `p` and the nearest point on it (a linear scan; triangles with an
    /// index out of range are skipped), or `None` for a mesh without triangles.
    pub fn closest_triangle(&self, p: Vec3) -> Option<(usize, Vec3)> {
        let mut best: Option<(usize, Vec3, f64)> = None;
        for (t, tri) in self.triangles.iter().enumerate() {
            let corner = |k: usize| self.positions.get(tri[k] as usize).copied();
            let (Some(a), Some(b), Some(c)) = (corner(0), corner(1), corner(2)) else {
                continue;
            };
            let q = closest_on_triangle(p, [a, b, c]);
            let d = (q - p).norm_squared();
            if best.is_none_or(|x| d < x.2) {
                best = Some((t, q, d));
            }
        }
        best.map(|(t, q, _)| (t, q))
    }

    /// Axis-aligned bounding box `(min, max)`, or `None` for an empty mesh.
    pub fn bounding_box(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), p| (lo.inf(p), hi.sup(p))),
        )
    }

    /// Appends another mesh (indices are shifted).
    pub fn append(&mut self, other: &TriMesh) {
        let off = self.positions.len() as u32;
        let had_normals = !self.normals.is_empty() || self.positions.is_empty();
        self.positions.extend_from_slice(&other.positions);
        if had_normals && other.normals.len() == other.positions.len() {
            self.normals.extend_from_slice(&other.normals);
        } else {
            self.normals.clear();
        }
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + off)));
    }
}

impl MeshSink for TriMesh {
    fn reserve(&mut self, vertices: usize, triangles: usize) {
        self.positions.reserve(vertices);
        self.normals.reserve(vertices);
        self.triangles.reserve(triangles);
    }

    fn add_vertex(&mut self, position: Vec3, normal: Option<Vec3>) -> u32 {
        let idx = self.positions.len() as u32;
        self.positions.push(position);
        match normal {
            Some(n) if self.normals.len() == idx as usize => self.normals.push(n),
            // A vertex without a normal (or a gap earlier) drops normals for the whole mesh:
            // a partial normal array would be silent garbage.
            _ => self.normals.clear(),
        }
        idx
    }

    fn add_triangle(&mut self, indices: [u32; 3]) {
        self.triangles.push(indices);
    }
}

/// Closest point to `p` on triangle `abc` (Ericson, Real-Time Collision Detection, 5.1.5).
pub fn closest_on_triangle(p: Vec3, [a, b, c]: [Vec3; 3]) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Triangles above which [`Parallelism::Auto`] computes normals in parallel
/// ([`TriMesh::compute_normals_with`]): below it the thread hand-off costs more than it saves
/// (measured 2026-12-03 with `examples/bench_normals.rs`; docs/performance.md, Direct FFD).
pub const NORMALS_PARALLEL_THRESHOLD: usize = 32_768;

/// Vertex ranges per rayon thread in [`TriMesh::compute_normals_with`]: more than one, so that
/// work stealing evens out a core that is busy with something else.
const NORMAL_RANGES_PER_THREAD: usize = 4;

/// The parallel path of [`TriMesh::compute_normals_with`]: `acc` (at most `positions.len()`
/// long, its contents ignored) receives the normals.
///
/// The vertices are cut into ranges of `2^shift` (about [`NORMAL_RANGES_PER_THREAD`] per
/// thread). A first parallel pass over blocks of triangles finds, for each range, the first and
/// last triangle that reference one of its vertices (and checks every index); then each range's
/// task walks only that interval of triangles, in order, adding the cross products to its own
/// slice of `acc`. When the intervals overlap so much that together they exceed
/// `2 x triangles` (a mesh without index locality), the ranges are merged to one per thread, so
/// that no more than `threads` passes over the triangles are made.
fn normals_parallel(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    threads: usize,
    acc: &mut Vec<Vec3>,
) {
    let n = positions.len();
    // A fresh buffer is filled in parallel, so that its page faults are spread over the
    // threads; each task zeroes its own slice just before its sums, while it is in cache.
    acc.par_extend(rayon::iter::repeat_n(Vec3::zeros(), n - acc.len()));
    let shift = n
        .div_ceil(threads * NORMAL_RANGES_PER_THREAD)
        .max(1)
        .next_power_of_two()
        .trailing_zeros();
    let ranges = n.div_ceil(1 << shift);
    let block = triangles
        .len()
        .div_ceil(threads * NORMAL_RANGES_PER_THREAD)
        .max(1);
    let empty = (usize::MAX, 0);
    let spans: Vec<(usize, usize)> = triangles
        .par_chunks(block)
        .enumerate()
        .map(|(b, chunk)| {
            let mut spans = vec![empty; ranges];
            // The range of the last triangle that lay in one range, and the end of its
            // interval so far, kept out of memory while consecutive triangles stay there (the
            // common case).
            let (mut cur, mut cur_end) = (usize::MAX, 0);
            for (i, tri) in chunk.iter().enumerate() {
                let t = b * block + i;
                let (lo, hi) = (tri.iter().min().unwrap(), tri.iter().max().unwrap());
                assert!(
                    (*hi as usize) < n,
                    "a triangle references vertex {hi}, but the mesh has {n} vertices"
                );
                let (r0, r1) = ((lo >> shift) as usize, (hi >> shift) as usize);
                if r0 == r1 {
                    if r0 != cur {
                        if cur != usize::MAX {
                            spans[cur].1 = spans[cur].1.max(cur_end);
                        }
                        cur = r0;
                        spans[r0].0 = spans[r0].0.min(t);
                    }
                    cur_end = t + 1;
                } else {
                    for &v in tri {
                        let s = &mut spans[(v >> shift) as usize];
                        s.0 = s.0.min(t);
                        s.1 = t + 1;
                    }
                }
            }
            if cur != usize::MAX {
                spans[cur].1 = spans[cur].1.max(cur_end);
            }
            spans
        })
        .reduce(
            || vec![empty; ranges],
            |a, b| {
                a.iter()
                    .zip(&b)
                    .map(|(x, y)| (x.0.min(y.0), x.1.max(y.1)))
                    .collect()
            },
        );
    let walked: usize = spans.iter().map(|&(lo, hi)| hi.saturating_sub(lo)).sum();
    let per_task = if walked > 2 * triangles.len() {
        // One range per thread: each walks the union of its ranges' intervals.
        ranges.div_ceil(threads)
    } else {
        1
    };
    acc.par_chunks_mut(per_task << shift)
        .zip(spans.par_chunks(per_task))
        .enumerate()
        .for_each(|(k, (out, spans))| {
            out.fill(Vec3::zeros());
            let lo = spans.iter().map(|s| s.0).min().unwrap_or(usize::MAX);
            let hi = spans.iter().map(|s| s.1).max().unwrap_or(0);
            if lo < hi {
                accumulate_normals(positions, &triangles[lo..hi], (k * per_task) << shift, out);
            }
            out.iter_mut().for_each(normalize_or_zero);
        });
}

/// Adds the cross product `(b - a) x (c - a)` of every triangle, in triangle order, to the
/// accumulators of its corners that lie in `first..first + out.len()` (`out[v - first]`).
fn accumulate_normals(positions: &[Vec3], triangles: &[[u32; 3]], first: usize, out: &mut [Vec3]) {
    let len = out.len();
    for tri in triangles {
        let local = tri.map(|i| (i as usize).wrapping_sub(first));
        if local.iter().all(|&l| l >= len) {
            continue;
        }
        let [a, b, c] = tri.map(|i| positions[i as usize]);
        let n = (b - a).cross(&(c - a));
        for l in local {
            if l < len {
                out[l] += n;
            }
        }
    }
}

/// Divides `n` by its length, leaving a zero (or non-finite) vector as it is.
fn normalize_or_zero(n: &mut Vec3) {
    let len = n.norm();
    if len > 0.0 {
        *n /= len;
    }
}

#[cfg(test)]
mod tests {

    /// The unit square of z = 0 as two triangles, and one triangle of x = 0 standing on its
    /// edge from (0, 0, 0) to (0, 1, 0).
    fn square_and_wall() -> TriMesh {
        let mut m = TriMesh::new();
        m.positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ];
        m.triangles = vec![[0, 2, 1], [2, 3, 1], [0, 1, 4]];
        m
    }

    #[test]
    fn closest_triangle_finds_the_face_point_edge_or_corner_nearest() {
        // The unit square of z = 0 as two triangles, and one triangle of x = 0 above its edge.
        let m = square_and_wall();
        // Above the inside of the second triangle: its foot.
        let (t, q) = m.closest_triangle(Vec3::new(0.8, 0.8, 0.3)).unwrap();
        assert_eq!(t, 1);
        assert!((q - Vec3::new(0.8, 0.8, 0.0)).norm() < 1e-15);
        // In front of the wall x = 0: its foot on the wall.
        let (t, q) = m.closest_triangle(Vec3::new(-0.5, 0.2, 0.4)).unwrap();
        assert_eq!(t, 2);
        assert!((q - Vec3::new(0.0, 0.2, 0.4)).norm() < 1e-15);
        // Beyond corner 3: the corner itself.
        let (_, q) = m.closest_triangle(Vec3::new(2.0, 2.0, -1.0)).unwrap();
        assert_eq!(q, Vec3::new(1.0, 1.0, 0.0));
        assert!(TriMesh::new().closest_triangle(Vec3::zeros()).is_none());
    }

    #[test]
    fn parts_keep_a_coarse_curve_smooth_and_split_between_parts() {
        // Two triangles of one part folded by 60 degrees along edge 0-1, and a third triangle
        // of another part meeting the first at 90 degrees along edge 0-2.
        let mut m = TriMesh::new();
        let h = 60f64.to_radians();
        m.positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(-h.cos(), 0.0, h.sin()),
            Vec3::new(0.0, 0.0, -1.0),
        ];
        m.triangles = vec![[0, 2, 1], [0, 1, 3], [0, 4, 2]];
        let by_angle = m.with_creases(30f64.to_radians());
        let by_part = m.with_creases_between(30f64.to_radians(), Some(&[0, 0, 1]));
        // By angle alone the 60-degree fold splits vertices 0 and 1; by part it does not.
        assert_ne!(by_angle.triangles[0][0], by_angle.triangles[1][0]);
        assert_eq!(by_part.triangles[0][0], by_part.triangles[1][0]);
        assert_eq!(by_part.triangles[0][2], by_part.triangles[1][1]);
        // The other part's triangle is split off at the 90-degree edge, both ways.
        assert_ne!(by_part.triangles[2][0], by_part.triangles[0][0]);
        assert_ne!(by_part.triangles[2][2], by_part.triangles[0][1]);
        assert_eq!(by_part.positions.len(), 5 + 2);
    }

    #[test]
    fn creases_split_a_cube_corner_and_keep_a_smooth_fan() {
        // Two triangles of the plane z = 0 and one of the plane x = 0 meeting at edge a-b.
        let m = square_and_wall();
        let c = m.with_creases(30f64.to_radians());
        // Vertices 0 and 1 are on the 90-degree edge: two copies each; 2, 3, 4 one.
        assert_eq!(c.positions.len(), 7);
        assert_eq!(c.triangles.len(), 3);
        for (t, tri) in c.triangles.iter().enumerate() {
            let [a, b, d] = tri.map(|i| c.positions[i as usize]);
            let face = (b - a).cross(&(d - a)).normalize();
            for &i in tri {
                assert!(
                    (c.normals[i as usize] - face).norm() < 1e-12,
                    "triangle {t}"
                );
                assert_eq!(
                    c.positions[i as usize],
                    m.positions[m.triangles[t][tri.iter().position(|&x| x == i).unwrap()] as usize]
                );
            }
        }
        // With a crease of 100 degrees nothing splits.
        assert_eq!(m.with_creases(100f64.to_radians()).positions.len(), 5);
    }

    use super::*;

    #[test]
    fn revolution_is_closed_and_outward() {
        // A closed capsule-like profile: poles at both ends.
        let profile = [(0.0, 0.0), (1.0, 0.5), (1.0, 1.5), (0.0, 2.0)];
        let m = TriMesh::revolution(&profile, 12);
        m.validate().unwrap();
        assert_eq!(m.positions.len(), 2 + 2 * 12);
        // Two fans and one band of quads: 12 + 12 + 24 triangles; V - E + F = 2 (a sphere).
        assert_eq!(m.triangles.len(), 48);
        let edges = 3 * m.triangles.len() / 2;
        assert_eq!(
            m.positions.len() as i64 - edges as i64 + m.triangles.len() as i64,
            2
        );
        // Outward: the signed volume is positive.
        let vol: f64 = m
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                a.dot(&b.cross(&c)) / 6.0
            })
            .sum();
        assert!(vol > 0.0, "volume {vol}");
    }

    fn square() -> TriMesh {
        let mut m = TriMesh::new();
        let a = m.add_vertex(Vec3::new(0.0, 0.0, 0.0), None);
        let b = m.add_vertex(Vec3::new(1.0, 0.0, 0.0), None);
        let c = m.add_vertex(Vec3::new(1.0, 1.0, 0.0), None);
        let d = m.add_vertex(Vec3::new(0.0, 1.0, 0.0), None);
        m.add_quad([a, b, c, d]);
        m
    }

    #[test]
    fn normals_of_ccw_square_point_up() {
        let mut m = square();
        m.compute_normals();
        for n in &m.normals {
            assert!((n - Vec3::z()).norm() < 1e-15);
        }
        assert_eq!(m.triangles.len(), 2);
        m.validate().unwrap();
    }

    /// `compute_normals` as it was before it went parallel (2026-12-03), the reference that
    /// every policy and thread count must match to the bit.
    fn normals_before(m: &TriMesh) -> Vec<Vec3> {
        let mut acc = vec![Vec3::zeros(); m.positions.len()];
        for tri in &m.triangles {
            let [a, b, c] = tri.map(|i| m.positions[i as usize]);
            let n = (b - a).cross(&(c - a));
            for &i in tri {
                acc[i as usize] += n;
            }
        }
        for n in &mut acc {
            let len = n.norm();
            if len > 0.0 {
                *n /= len;
            }
        }
        acc
    }

    fn bits(v: &[Vec3]) -> Vec<[u64; 3]> {
        v.iter()
            .map(|n| [n.x.to_bits(), n.y.to_bits(), n.z.to_bits()])
            .collect()
    }

    /// Every policy, on pools of 1, 2, 3 and 7 threads, twice in a row (the second call reuses
    /// the normal buffer), gives the old normals to the bit.
    fn assert_normals_as_before(m: &TriMesh) {
        let want = bits(&normals_before(m));
        for threads in [1, 2, 3, 7] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            for par in [
                Parallelism::Sequential,
                Parallelism::Rayon,
                Parallelism::Auto,
            ] {
                let mut m = m.clone();
                for _ in 0..2 {
                    pool.install(|| m.compute_normals_with(par));
                    assert_eq!(bits(&m.normals), want, "{par:?} on {threads} threads");
                }
            }
        }
    }

    /// Seeded xorshift64* in `[0, 1)`.
    fn rng(seed: u64) -> impl FnMut() -> f64 {
        let mut x = seed;
        move || {
            x ^= x >> 12;
            x ^= x << 25;
            x ^= x >> 27;
            (x.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn parallel_normals_equal_the_sequential_ones_to_the_bit() {
        assert_normals_as_before(&TriMesh::new());
        assert_normals_as_before(&square());
        assert_normals_as_before(&square_and_wall());
        // Degenerate triangles (a repeated corner, three collinear points, a point), an
        // unreferenced vertex, a vertex that only degenerate triangles use, and a NaN.
        let mut m = square();
        let e = m.add_vertex(Vec3::new(2.0, 0.0, 0.0), None);
        let _unused = m.add_vertex(Vec3::new(5.0, 5.0, 5.0), None);
        let f = m.add_vertex(Vec3::new(3.0, 0.0, 0.0), None);
        let g = m.add_vertex(Vec3::new(-1.0, 2.0, f64::NAN), None);
        m.add_triangle([0, 0, 2]);
        m.add_triangle([0, 1, e]);
        m.add_triangle([f, f, f]);
        m.add_triangle([1, 2, g]);
        assert_normals_as_before(&m);
        // A revolution surface (index locality, as tessellators produce) with degenerate
        // triangles at the poles, above the parallel threshold.
        let profile: Vec<(f64, f64)> = (0..=100)
            .map(|i| {
                let a = std::f64::consts::PI * i as f64 / 100.0;
                (a.sin(), -a.cos())
            })
            .collect();
        let sphere = TriMesh::revolution(&profile, 200);
        assert!(sphere.triangles.len() > NORMALS_PARALLEL_THRESHOLD);
        assert_normals_as_before(&sphere);
        // Random positions and random triangles (no locality: every vertex's triangles spread
        // over the whole list, some vertices unreferenced), with random rounding in the sums.
        let mut r = rng(0x5eed_0031);
        let mut m = TriMesh::new();
        for _ in 0..20_000 {
            let p = Vec3::new(r() - 0.5, r() * 3.0, (r() - 0.5) * 1e-3);
            m.add_vertex(p, None);
        }
        for _ in 0..40_000 {
            let t = [r(), r(), r()].map(|x| (x * 19_000.0) as u32);
            m.add_triangle(t);
        }
        assert_normals_as_before(&m);
    }

    #[test]
    #[should_panic(expected = "references vertex 9")]
    fn parallel_normals_panic_on_a_missing_vertex() {
        let mut m = square();
        m.triangles.push([9, 9, 9]);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        pool.install(|| m.compute_normals_with(Parallelism::Rayon));
    }

    #[test]
    fn validate_catches_bad_index_and_nan() {
        let mut m = square();
        m.triangles.push([0, 1, 9]);
        assert_eq!(
            m.validate(),
            Err(MeshError::IndexOutOfRange {
                triangle: 2,
                index: 9,
                vertex_count: 4
            })
        );
        let mut m = square();
        m.positions[3].y = f64::NAN;
        assert_eq!(m.validate(), Err(MeshError::NonFiniteVertex { vertex: 3 }));
    }
}
