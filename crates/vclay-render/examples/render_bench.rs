//! Rendering throughput: the exact torus tessellated at several densities, rendered at the demo's
//! picture size and larger, plus a 36-frame turntable encoded as GIF.
//!
//! Run: `cargo run --release -p vclay-render --example render_bench`

use std::time::Instant;
use vclay_core::TriMesh;
use vclay_render::{RenderOptions, Scene, encode_gif, render, turntable};
use vclay_spline::{NurbsSurface, tessellate_surface};

fn best_of<T>(n: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..n {
        let t0 = Instant::now();
        let r = f();
        best = best.min(t0.elapsed().as_secs_f64() * 1e3);
        out = Some(r);
    }
    (best, out.expect("n > 0"))
}

fn main() {
    let torus = NurbsSurface::torus(2.0, 0.6).expect("torus");
    println!("| triangles | size | samples/pixel | ms per picture |");
    println!("| ---: | --- | ---: | ---: |");
    for samples in [[24, 48], [48, 96], [128, 256]] {
        let mut m = TriMesh::new();
        tessellate_surface(&torus, samples, &mut m).expect("tessellate");
        let tris = m.triangles.len();
        let scene = Scene::new().with_mesh(m);
        for (w, h) in [(480, 360), (1280, 960)] {
            for ss in [1, 3] {
                let opts = RenderOptions {
                    supersample: ss,
                    ..RenderOptions::sized(w, h)
                };
                let (ms, _) = best_of(5, || render(&scene, &opts).expect("render"));
                println!("| {tris} | {w}x{h} | {} | {ms:.1} |", ss * ss);
            }
        }
    }
    let mut m = TriMesh::new();
    tessellate_surface(&torus, [48, 96], &mut m).expect("tessellate");
    let scene = Scene::new().with_mesh(m);
    let opts = RenderOptions::sized(320, 240);
    let (ms_frames, frames) = best_of(1, || turntable(&scene, 36, &opts).expect("turntable"));
    let (ms_gif, bytes) = best_of(1, || encode_gif(&frames, 80).expect("gif"));
    println!(
        "turntable: 36 frames 320x240 rendered in {ms_frames:.0} ms, GIF encoded in {ms_gif:.0} ms ({} KiB)",
        bytes.len() / 1024
    );
}
