//! `Lattice`: a subdivision-solid cell complex (`vclay_lattice`): the papers' primitives,
//! `.ovm` read and write, MacCracken-Joy subdivision (`subdivision-solids-journal.txt`
//! sections 3.3, 4.2), counts, points as arrays, and the boundary surface as triangles.

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use vclay_lattice::command::{MAX_PREDICTED_CELLS, OutputFormat, primitive};
use vclay_lattice::formats::ovm;
use vclay_lattice::{
    BoundaryRule, CellId, Features, Lattice as KLattice, SubdivisionRules, boundary_mesh, subdivide,
};

use crate::errors::{FileError, GeometryError, PyResultExt};
use crate::util;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Lattice>()
}

/// A polyhedral cell complex (points, edges, faces, cells), validated on construction: the
/// control or subdivided lattice of a subdivision solid.
#[pyclass(module = "vclay", frozen)]
#[derive(Debug)]
pub struct Lattice {
    lattice: KLattice,
}

fn boundary_rule(name: &str) -> PyResult<BoundaryRule> {
    match name {
        "interior" => Ok(BoundaryRule::Interior),
        "smooth" => Ok(BoundaryRule::Smooth),
        "sharp" => Ok(BoundaryRule::Sharp),
        other => Err(PyValueError::new_err(format!(
            "boundary \"{other}\": expected \"interior\", \"smooth\" or \"sharp\""
        ))),
    }
}

#[pymethods]
impl Lattice {
    /// `Lattice.primitive(spec)`: one of the papers' models by the `vclay subdivide
    /// --primitive` names: `box[:AxBxC]`, `cylinder[:SxLxR]`, `torus`, `torus:SxC`, `gear`,
    /// `cube-with-holes`, `tetrahedron-with-holes[:HOLE]`, `tetrahedron-with-holes-paper[:HOLE]`,
    /// `soccer-player`, `cactus`, `spiked-object`, `holed-object`, `l[:AxW]`, `t[:AxW]`.
    ///
    /// Sizes: the numbers of the spec bound its cell count (`box:AxBxC` has `(A-1)(B-1)(C-1)`
    /// cells); their product is checked against the memory limit with `vclay subdivide`'s
    /// estimate per cell (`BYTES_PER_CELL`) before the lattice is built.
    #[staticmethod]
    fn primitive(py: Python<'_>, spec: &str) -> PyResult<Self> {
        let cells: f64 = spec
            .split_once(':')
            .map(|(_, args)| {
                args.split(['x', 'X'])
                    .filter_map(|t| t.trim().parse::<f64>().ok())
                    .map(|x| x.max(1.0))
                    .product()
            })
            .unwrap_or(1.0);
        crate::limits::check(
            py,
            || format!("primitive {spec:?} (up to {cells:.3e} cells)"),
            cells * vclay_lattice::command::BYTES_PER_CELL as f64,
        )?;
        let lattice = py.detach(|| primitive(spec)).py()?;
        Ok(Self { lattice })
    }

    /// `Lattice.read(path)`: an OpenVolumeMesh `.ovm` file (errors name the line).
    #[staticmethod]
    fn read(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let lattice = py.detach(|| ovm::read(&path)).py()?;
        Ok(Self { lattice })
    }

    /// Writes the lattice (`.ovm`, `.vtu`) or its boundary surface (`.obj`, `.ply`, `.stl`).
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let f = OutputFormat::from_path(&path).py()?;
        py.detach(|| f.write(&self.lattice, &path)).py()
    }

    /// The lattice as `.ovm` text (points written exactly: `from_ovm` reads the same bits).
    fn to_ovm(&self) -> String {
        ovm::to_string(&self.lattice)
    }

    /// `Lattice.from_ovm(text)`: a lattice from `.ovm` text (errors name the line).
    #[staticmethod]
    fn from_ovm(py: Python<'_>, text: &str) -> PyResult<Self> {
        let lattice = py.detach(|| ovm::parse(text, "<ovm text>")).py()?;
        Ok(Self { lattice })
    }

    /// Pickling and `copy`: `Lattice.from_ovm(self.to_ovm())`, exact to the bit.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let from = slf.get_type().getattr("from_ovm")?;
        (from, (slf.get().to_ovm(),))
            .into_pyobject(py)
            .map(|t| t.into_any())
    }

    /// Whether two lattices have the same points, edges, faces and cells, in the same order.
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<Self>()
            .is_ok_and(|o| ovm::to_string(&o.get().lattice) == ovm::to_string(&self.lattice))
    }

    /// `levels` MacCracken-Joy subdivision steps with the boundary rule `"interior"`,
    /// `"smooth"` or `"sharp"`: a new lattice. Refused above 50 million predicted cells.
    #[pyo3(signature = (levels = 1, boundary = "sharp"))]
    fn subdivide(&self, py: Python<'_>, levels: i64, boundary: &str) -> PyResult<Self> {
        let levels = util::count(levels, "levels")?;
        let rules = SubdivisionRules::new(boundary_rule(boundary)?);
        let predicted = (self.lattice.num_cells() as u128)
            .saturating_mul(8u128.saturating_pow(levels.min(64) as u32));
        if predicted > MAX_PREDICTED_CELLS {
            return Err(GeometryError::new_err(format!(
                "{levels} levels would give about {predicted} cells (more than {MAX_PREDICTED_CELLS}); use fewer levels"
            )));
        }
        // `vclay subdivide --levels`'s estimate, against the memory limit.
        crate::limits::check(
            py,
            || format!("levels={levels} ({predicted} cells)"),
            vclay_session::limits::subdivision_bytes(self.lattice.num_cells(), levels),
        )?;
        let start = &self.lattice;
        let out = py.detach(|| {
            let mut lat = start.clone();
            let mut features = Features::none(&lat);
            for _ in 0..levels {
                let r = subdivide(&lat, &features, &rules)?;
                lat = r.lattice;
                features = r.features;
            }
            Ok::<_, vclay_lattice::LatticeError>(lat)
        });
        Ok(Self { lattice: out.py()? })
    }

    /// Counts and checks as a dict: points, edges, faces, cells, boundary_faces and
    /// inverted_cells (cells of non-positive signed volume).
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let l = &self.lattice;
        let c = l.counts();
        let (inverted, boundary) = py.detach(|| {
            let inv = (0..l.num_cells())
                .filter(|&k| l.cell_signed_volume(CellId::new(k)) <= 0.0)
                .count();
            let b = (0..l.num_faces())
                .filter(|&f| l.is_boundary_face(vclay_lattice::FaceId::new(f)))
                .count();
            (inv, b)
        });
        let d = PyDict::new(py);
        d.set_item("points", c.points)?;
        d.set_item("edges", c.edges)?;
        d.set_item("faces", c.faces)?;
        d.set_item("cells", c.cells)?;
        d.set_item("boundary_faces", boundary)?;
        d.set_item("inverted_cells", inverted)?;
        Ok(d)
    }

    /// The points, `(n, 3)` (a copy).
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray2<f64>> {
        util::points_array(py, self.lattice.points())
    }

    /// A lattice of the same topology with new points `(n, 3)`.
    fn with_points(&self, points: &Bound<'_, PyAny>) -> PyResult<Self> {
        let p = util::points(points, "points")?;
        if p.len() != self.lattice.num_points() {
            return Err(PyValueError::new_err(format!(
                "points: expected {} points, got {}",
                self.lattice.num_points(),
                p.len()
            )));
        }
        if let Some(i) = p.iter().position(|q| !q.iter().all(|c| c.is_finite())) {
            return Err(GeometryError::new_err(format!("points[{i}] is not finite")));
        }
        let mut lattice = self.lattice.clone();
        lattice.set_points(p);
        Ok(Self { lattice })
    }

    /// Edges as a `(m, 2)` int64 array of point indices (numpy's index type, as
    /// `np.argsort` gives).
    #[getter]
    fn edges<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray2<i64>> {
        use numpy::IntoPyArray;
        let v: Vec<i64> = self
            .lattice
            .edges()
            .iter()
            .flat_map(|e| [e[0].index() as i64, e[1].index() as i64])
            .collect();
        numpy::ndarray::Array2::from_shape_vec((self.lattice.num_edges(), 2), v)
            .expect("shape matches the data")
            .into_pyarray(py)
    }

    /// Number of cells.
    fn __len__(&self) -> usize {
        self.lattice.num_cells()
    }

    /// The outward boundary surface: `(vertices, triangles, normals)`.
    fn boundary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let l = &self.lattice;
        let mesh = py.detach(|| boundary_mesh(l));
        util::mesh_arrays(py, &mesh)
    }

    fn __repr__(&self) -> String {
        let c = self.lattice.counts();
        format!(
            "<vclay Lattice: {} points, {} edges, {} faces, {} cells>",
            c.points, c.edges, c.faces, c.cells
        )
    }
}

#[allow(dead_code)]
fn unused(_: FileError) {}
