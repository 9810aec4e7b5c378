//! `render`: a model file, a list of entities or a mesh to a PNG with `vclay_render`'s
//! headless z-buffer rasterizer (the same scene building as `vclay render`).

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use vclay_core::TriMesh;
use vclay_io::model::Entity as IoEntity;
use vclay_render::scene::{CLAY, NET};
use vclay_render::{RenderOptions, Scene, View, render as render_scene};
use vclay_spline::{ParametricCurve, tessellate_surface, tessellate_volume_boundary};

use crate::errors::{PyResultExt, RenderError};
use crate::nurbs::{Entity, Loaded, read_any};
use crate::util;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(render, m)?)
}

/// Tessellation samples per axis for a knot vector with `spans` distinct knots.
fn samples_for(spans: usize) -> usize {
    (8 * spans).clamp(24, 96)
}

fn scene_from_entities(entities: &[IoEntity], wireframe: bool) -> PyResult<Scene> {
    let mut scene = Scene::new();
    let ctx = |i: usize, e: &IoEntity, err: String| {
        RenderError::new_err(format!("entity {i} ({}): {err}", e.type_name()))
    };
    for (i, e) in entities.iter().enumerate() {
        match e {
            IoEntity::Curve(c) => {
                let n = samples_for(c.knots().distinct().len()) * 4;
                let pts = c
                    .domain()
                    .linspace(n)
                    .into_iter()
                    .map(|u| c.point(u))
                    .collect::<Result<Vec<_>, _>>()
                    .map_err(|err| ctx(i, e, err.to_string()))?;
                scene.add_polyline(pts, [150, 60, 30], 2.5);
                if wireframe {
                    scene
                        .add_control_net(c.control_points(), &[c.control_points().len()], NET)
                        .py()?;
                }
            }
            IoEntity::Surface(s) => {
                let samples = s
                    .knots()
                    .each_ref()
                    .map(|k| samples_for(k.distinct().len()));
                let mut m = TriMesh::new();
                tessellate_surface(s, samples, &mut m).map_err(|err| ctx(i, e, err.to_string()))?;
                scene.add_mesh(m, CLAY);
                if wireframe {
                    scene
                        .add_control_net(s.control_points(), &s.dims(), NET)
                        .py()?;
                }
            }
            IoEntity::Volume(v) => {
                let samples = v
                    .knots()
                    .each_ref()
                    .map(|k| samples_for(k.distinct().len()) / 2);
                let mut m = TriMesh::new();
                tessellate_volume_boundary(v, samples, &mut m)
                    .map_err(|err| ctx(i, e, err.to_string()))?;
                scene.add_mesh(m, CLAY);
                if wireframe {
                    scene
                        .add_control_net(v.control_points(), &v.dims(), NET)
                        .py()?;
                }
            }
        }
    }
    Ok(scene)
}

fn scene_from_mesh(mut mesh: TriMesh, wireframe: bool) -> Scene {
    if mesh.normals.len() != mesh.positions.len() {
        mesh.compute_normals();
    }
    let mut scene = Scene::new().with_mesh(mesh);
    if wireframe {
        scene.meshes[0].edges = Some([60, 40, 30]);
    }
    scene
}

/// `render(source, out, size=(640, 480), view="iso", wireframe=False, ortho=False)`: writes a
/// PNG. `source` is a model or mesh file path, a list of entities, or a `(vertices,
/// triangles)` pair. `view` is `iso`, `front`, `top` or `side`; `wireframe` adds control nets
/// (meshes: triangle edges).
#[pyfunction]
#[pyo3(signature = (source, out, size = (640, 480), view = "iso", wireframe = false, ortho = false),
    text_signature = "(source, out, size=(640, 480), view='iso', wireframe=False, ortho=False)")]
fn render(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    out: PathBuf,
    size: (i64, i64),
    view: &str,
    wireframe: bool,
    ortho: bool,
) -> PyResult<()> {
    let side = |v: i64, what: &str| {
        u32::try_from(v).map_err(|_| {
            crate::errors::argument(format!(
                "{what} = {v}: expected a size in pixels (0 to {})",
                u32::MAX
            ))
        })
    };
    let size = (side(size.0, "size[0]")?, side(size.1, "size[1]")?);
    // `vclay render --size`'s estimate (one frame), against the memory limit, first.
    let supersample = RenderOptions::sized(1, 1).supersample;
    crate::limits::check(
        py,
        || format!("size={size:?}"),
        vclay_session::limits::render_bytes(size.0, size.1, supersample, 1, 1),
    )?;
    let view = View::parse(view).ok_or_else(|| {
        PyValueError::new_err(format!("view '{view}': expected iso, front, top or side"))
    })?;
    let scene = if let Ok(path) = source.extract::<PathBuf>() {
        match py.detach(|| read_any(&path))? {
            Loaded::Entities(e, faces) if faces.is_empty() => {
                let ents: Vec<IoEntity> = e.into_iter().map(|n| n.entity).collect();
                py.detach(|| scene_from_entities(&ents, wireframe))?
            }
            // STEP B-reps: their faces trimmed, as `vclay render` draws them.
            trimmed @ Loaded::Entities(..) => {
                let mesh = py.detach(|| crate::nurbs::mesh_of(&trimmed, 48))?;
                scene_from_mesh(mesh, wireframe)
            }
            Loaded::Meshes(ms) => {
                let mut all = TriMesh::new();
                for m in &ms {
                    all.append(m);
                }
                scene_from_mesh(all, wireframe)
            }
        }
    } else if let Ok((v, t)) = source.extract::<(Bound<'_, PyAny>, Bound<'_, PyAny>)>()
        && !v.is_instance_of::<Entity>()
    {
        scene_from_mesh(util::mesh_from(&v, &t)?, wireframe)
    } else {
        let mut ents = Vec::new();
        for item in source.try_iter()? {
            let item = item?;
            let e = item.cast::<Entity>().map_err(|_| {
                PyValueError::new_err(
                    "render: source must be a path, a list of entities or (vertices, triangles)",
                )
            })?;
            ents.push(e.borrow().entity.clone());
        }
        py.detach(|| scene_from_entities(&ents, wireframe))?
    };
    let opts = RenderOptions {
        view,
        orthographic: ortho,
        ..RenderOptions::sized(size.0, size.1)
    };
    py.detach(|| {
        let img = render_scene(&scene, &opts)?;
        img.write_png(&out)
    })
    .py()
}
