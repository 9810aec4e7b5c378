//! `Part`: a CAD part of trimmed faces (issue 30) in Python, read by `load_part(path)` from
//! STEP, IGES (144/142 trimmed surfaces or 186 B-reps) or a model JSON with `"shells"`, and
//! written back by `Part.save(path)` as STEP (`MANIFOLD_SOLID_BREP`), IGES or model JSON, with
//! its trims (`vclay_io::trimmed`, docs/formats.md section 1 "Trimmed faces").
//!
//! A part is its entities (the exact `Curve`/`Surface` geometry, as `load` gives) and its
//! shells: faces that each lie on a surface entity, bounded by an outer loop and holes of
//! shared edges, with the loops' curves in the surface's parameters (pcurves). What Python
//! reads: `faces(shell)` (surface, sense, loops as parameter polygons and edge uses),
//! `edges(shell)` (exact 3D curves), `closed(shell)`, and `mesh(samples)` (crack-free: shared
//! edges sampled once, with the face of each triangle). To sculpt a face with physics, open
//! the file as a session (`vclay.open(path)`, kind `cad-part`).

use std::path::PathBuf;

use numpy::{IntoPyArray, ndarray::Array2};
use pyo3::exceptions::{PyIndexError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use vclay_io::brep::{LoopItem, Shell};
use vclay_io::model::NamedEntity;

use crate::errors::{FileError, PyResultExt};
use crate::util;

/// Samples of each pcurve in the parameter polygons of `Part.faces` (both ends included).
pub const LOOP_SAMPLES: usize = 33;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Part>()?;
    m.add_function(wrap_pyfunction!(load_part, m)?)?;
    Ok(())
}

/// A CAD part of trimmed faces: exact surfaces, shared edges, loops and pcurves.
///
/// `load_part(path)` reads one; `save(path)` writes it back (`.step`/`.stp`, `.igs`/`.iges`,
/// `.json`) with its trims, or meshed (`.obj`, `.stl`, `.ply`, `.glb`). Pickles exactly.
#[pyclass(module = "vclay", frozen)]
#[derive(Clone, Debug)]
pub struct Part {
    entities: Vec<NamedEntity>,
    shells: Vec<Shell>,
}

impl Part {
    fn shell(&self, shell: i64) -> PyResult<&Shell> {
        usize::try_from(shell)
            .ok()
            .and_then(|i| self.shells.get(i))
            .ok_or_else(|| {
                PyIndexError::new_err(format!(
                    "shell {shell} out of range (the part has {} shells)",
                    self.shells.len()
                ))
            })
    }

    fn json(&self) -> String {
        vclay_io::model::trimmed_to_json(&self.entities, &self.shells).to_string()
    }
}

/// `load_part(path)`: the trimmed shells of a CAD file (STEP B-rep, IGES 144/142 or 186, or a
/// model JSON with `"shells"`) as a `Part`. A file without trimmed faces raises `FileError`
/// (use `load` for its entities).
#[pyfunction]
fn load_part(py: Python<'_>, path: PathBuf) -> PyResult<Part> {
    let m = py.detach(|| vclay_io::model::import_model(&path)).py()?;
    if m.shells.is_empty() {
        return Err(FileError::new_err(format!(
            "{}: no trimmed faces (a STEP B-rep, IGES trimmed surfaces or B-rep, or \"shells\" in a model JSON); use load for its entities",
            path.display()
        )));
    }
    Ok(Part {
        entities: m.entities,
        shells: m.shells,
    })
}

#[pymethods]
impl Part {
    /// A part from the model JSON text that `to_json` writes (with `"shells"`).
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        let v: serde_json::Value = serde_json::from_str(text)
            .map_err(|e| FileError::new_err(format!("part JSON: {e}")))?;
        let (entities, shells) = vclay_io::model::trimmed_model_of_value(&v).py()?;
        Ok(Self { entities, shells })
    }

    /// The part as model JSON text (docs/formats.md section 1), as `save("x.json")` writes.
    fn to_json(&self) -> String {
        self.json()
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let ctor = py.get_type::<Part>().getattr("from_json")?;
        (ctor, (slf.get().json(),))
            .into_pyobject(py)
            .map(|t| t.into_any())
    }

    fn __repr__(&self) -> String {
        let faces: usize = self.shells.iter().map(|s| s.faces.len()).sum();
        let closed = self.shells.iter().filter(|s| s.closed).count();
        format!(
            "Part({} entities, {} shells ({closed} closed), {faces} faces)",
            self.entities.len(),
            self.shells.len()
        )
    }

    /// The entities (`Curve`, `Surface`) of the part, as `load` gives them; a face's
    /// `"entity"` is an index into this list.
    #[getter]
    fn entities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let items = self
            .entities
            .iter()
            .map(|n| crate::nurbs::wrap(py, n.entity.clone(), n.name.clone()))
            .collect::<PyResult<Vec<_>>>()?;
        PyList::new(py, items)
    }

    /// How many shells the part has.
    fn shell_count(&self) -> usize {
        self.shells.len()
    }

    /// Whether `shell` is closed: every edge used by two faces in opposite directions, so the
    /// faces bound a solid.
    #[pyo3(signature = (shell = 0))]
    fn closed(&self, shell: i64) -> PyResult<bool> {
        Ok(self.shell(shell)?.closed)
    }

    /// The faces of `shell`, each a dict: `surface` (a `Surface`), `entity` (its index in
    /// `entities`, or None), `same_sense` (whether the outward normal is `S_u x S_v`),
    /// `loops` (the outer loop then the holes, each an (n, 2) array of `(u, v)`: every edge
    /// use's pcurve sampled at 33 points in loop direction) and `edges` (per loop, the
    /// `(edge, forward)` uses; a pole is `(-1 - vertex, True)`).
    #[pyo3(signature = (shell = 0))]
    fn faces<'py>(&self, py: Python<'py>, shell: i64) -> PyResult<Bound<'py, PyList>> {
        let sh = self.shell(shell)?;
        let mut out = Vec::with_capacity(sh.faces.len());
        for f in &sh.faces {
            let d = PyDict::new(py);
            d.set_item(
                "surface",
                crate::nurbs::wrap(
                    py,
                    vclay_io::model::Entity::Surface(f.surface.clone()),
                    None,
                )?,
            )?;
            d.set_item("entity", f.entity)?;
            d.set_item("same_sense", f.same_sense)?;
            let mut loops = Vec::new();
            let mut uses = Vec::new();
            for l in f.loops() {
                let poly = f.loop_polygon(l, LOOP_SAMPLES);
                let flat: Vec<f64> = poly.iter().flatten().copied().collect();
                let a = Array2::from_shape_vec((poly.len(), 2), flat)
                    .expect("shape matches the data")
                    .into_pyarray(py);
                loops.push(a.into_any());
                let u: Vec<(i64, bool)> = l
                    .iter()
                    .map(|it| match *it {
                        LoopItem::Edge { edge, forward, .. } => (edge as i64, forward),
                        LoopItem::Pole { vertex } => (-1 - vertex as i64, true),
                    })
                    .collect();
                uses.push(u);
            }
            d.set_item("loops", loops)?;
            d.set_item("edges", uses)?;
            out.push(d);
        }
        PyList::new(py, out)
    }

    /// The edges of `shell` as exact 3D `Curve`s (an edge runs from its start vertex at the
    /// curve's first parameter to its end vertex).
    #[pyo3(signature = (shell = 0))]
    fn edges<'py>(&self, py: Python<'py>, shell: i64) -> PyResult<Bound<'py, PyList>> {
        let items = self
            .shell(shell)?
            .edges
            .iter()
            .map(|e| crate::nurbs::wrap(py, vclay_io::model::Entity::Curve(e.curve.clone()), None))
            .collect::<PyResult<Vec<_>>>()?;
        PyList::new(py, items)
    }

    /// `(vertices, triangles, normals, faces)` of `shell` meshed with its trims, crack-free
    /// (shared edges sampled once; edge spacing `size / samples`, 2 to 4096); `faces[t]` is
    /// the face of triangle `t`.
    #[pyo3(signature = (shell = 0, samples = 32))]
    fn mesh<'py>(&self, py: Python<'py>, shell: i64, samples: i64) -> PyResult<Bound<'py, PyAny>> {
        let samples = util::count(samples, "samples")?;
        if !(2..=vclay_io::trimmed::MAX_SHELL_SAMPLES).contains(&samples) {
            return Err(PyValueError::new_err(format!(
                "samples {samples}: must be from 2 to {}",
                vclay_io::trimmed::MAX_SHELL_SAMPLES
            )));
        }
        let sh = self.shell(shell)?.clone();
        let (mesh, faces) = py
            .detach(|| vclay_io::trimmed::tessellate_shell_faces(&sh, samples))
            .map_err(|e| FileError::new_err(format!("shell {shell}: {e}")))?;
        let (v, t, n): (Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>) =
            util::mesh_arrays(py, &mesh)?.extract()?;
        let faces = numpy::ndarray::Array1::from_vec(faces).into_pyarray(py);
        (v, t, n, faces).into_pyobject(py).map(|x| x.into_any())
    }

    /// Writes the part: `.step`/`.stp` (each closed shell a `MANIFOLD_SOLID_BREP`),
    /// `.igs`/`.iges` (trimmed surfaces 144/142), `.json` (the model with `"shells"`), or the
    /// shells meshed (`.obj`, `.stl`, `.ply`, `.glb`; `samples` as `mesh`).
    #[pyo3(signature = (path, samples = 32))]
    fn save(&self, py: Python<'_>, path: PathBuf, samples: i64) -> PyResult<()> {
        let samples = util::count(samples, "samples")?;
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_lowercase())
            .unwrap_or_default();
        let (ents, shells) = (&self.entities, &self.shells);
        let mesh = || -> PyResult<vclay_core::TriMesh> {
            let mut all = vclay_core::TriMesh::new();
            for (k, sh) in shells.iter().enumerate() {
                let m = vclay_io::trimmed::tessellate_shell(sh, samples)
                    .map_err(|e| FileError::new_err(format!("shell {k}: {e}")))?;
                all.append(&m);
            }
            Ok(all)
        };
        py.detach(|| match ext.as_str() {
            "step" | "stp" => vclay_io::step::write_step_trimmed(
                &path,
                ents,
                shells,
                vclay_io::step::StepLayout::Brep,
            )
            .py(),
            "igs" | "iges" => vclay_io::iges::write_iges_trimmed(
                &path,
                ents,
                shells,
                vclay_io::iges::IgesLayout::default(),
            )
            .py(),
            "json" => vclay_io::model::write_trimmed_model(&path, ents, shells).py(),
            "obj" | "stl" | "ply" => vclay_io::mesh::write_mesh(&path, &mesh()?).py(),
            "glb" => vclay_io::gltf::write_glb(
                &path,
                &[vclay_io::gltf::GlbMesh::new("part", mesh()?)],
            )
            .py(),
            other => Err(FileError::new_err(format!(
                "{}: unknown output format \".{other}\"; a part is written as .step, .stp, .igs, .iges, .json, .obj, .stl, .ply or .glb",
                path.display()
            ))),
        })
    }
}
