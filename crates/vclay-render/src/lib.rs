//! # vclay-render
//!
//! Headless pictures of vclay objects, in pure Rust: no GPU, no display, no system graphics
//! library. `vclay demo` and `vclay render` depend on it, so it must work on a bare machine.
//!
//! **What.** A [`Scene`] holds shaded triangle meshes ([`vclay_core::TriMesh`], smooth shading
//! from per-vertex normals), polylines (control nets, lattice edges, springs, curves) and point
//! markers (data points, constraints). [`render`] draws it to an [`Image`] with a camera that
//! frames it along a [`View`] (iso, front, top, side or a given direction) or a given
//! [`Camera`]; [`Image::write_png`] saves it. Animations: [`render_frames`] draws a sequence of
//! scenes (a scenario's frames) with one camera and [`write_animation`] saves them, [`turntable`] turns the camera around a model,
//! [`write_gif`] and [`write_png_sequence`] save frames. [`plot`] draws energy, residual and step
//! time over a run as SVG.
//!
//! **How.** A supersampled z-buffer rasterizer with per-sample Blinn-Phong shading and two
//! camera-fixed lights ([`raster`]); PNG through the `png` crate, GIF through the `gif` crate.
//! Every file is written to a temporary file renamed over the target
//! ([`vclay_io::write_atomic`]).
//!
//! **Limitations.** No clipping against the near plane (framed cameras never need it), no
//! shadows, no transparency, no text in raster pictures (plots are SVG).
//!
//! ```
//! use vclay_core::{MeshSink, TriMesh, Vec3};
//! use vclay_render::{RenderOptions, Scene, View, render};
//! let mut m = TriMesh::new();
//! let a = m.add_vertex(Vec3::new(0.0, 0.0, 0.0), None);
//! let b = m.add_vertex(Vec3::new(1.0, 0.0, 0.0), None);
//! let c = m.add_vertex(Vec3::new(0.0, 0.0, 1.0), None);
//! m.add_triangle([a, b, c]);
//! let opts = RenderOptions { view: View::Front, ..RenderOptions::sized(32, 24) };
//! let img = render(&Scene::new().with_mesh(m), &opts).unwrap();
//! assert_eq!((img.width, img.height), (32, 24));
//! ```
#![warn(missing_docs)]

pub mod camera;
pub mod error;
pub mod image;
pub mod plot;
pub mod raster;
pub mod scene;

pub use camera::{Camera, Projection, View};
pub use error::RenderError;
pub use image::{Image, encode_gif, write_gif, write_png_sequence};
pub use plot::{Plot, RunHistory, Series};
pub use raster::{
    Light, MAX_IMAGE_SIDE, RenderOptions, render, render_frames, turntable, write_animation,
};
pub use scene::{Marker, Polyline, Rgb, Scene, SceneMesh};
