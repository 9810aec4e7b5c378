//! Known-pixel and golden-image tests of the rasterizer.

use vclay_core::{MeshSink, TriMesh, Vec3};
use vclay_render::raster::BACKGROUND;
use vclay_render::{
    Camera, Image, Projection, RenderOptions, Scene, View, encode_gif, render, render_frames,
    turntable,
};

/// The unit cube [0,1]^3 with outward flat faces (4 vertices per face, face normals).
fn unit_cube() -> TriMesh {
    let mut m = TriMesh::new();
    let faces: [(Vec3, [Vec3; 4]); 6] = {
        let p = |x: f64, y: f64, z: f64| Vec3::new(x, y, z);
        [
            (
                -Vec3::y(),
                [p(0., 0., 0.), p(1., 0., 0.), p(1., 0., 1.), p(0., 0., 1.)],
            ),
            (
                Vec3::y(),
                [p(0., 1., 0.), p(0., 1., 1.), p(1., 1., 1.), p(1., 1., 0.)],
            ),
            (
                -Vec3::x(),
                [p(0., 0., 0.), p(0., 0., 1.), p(0., 1., 1.), p(0., 1., 0.)],
            ),
            (
                Vec3::x(),
                [p(1., 0., 0.), p(1., 1., 0.), p(1., 1., 1.), p(1., 0., 1.)],
            ),
            (
                -Vec3::z(),
                [p(0., 0., 0.), p(0., 1., 0.), p(1., 1., 0.), p(1., 0., 0.)],
            ),
            (
                Vec3::z(),
                [p(0., 0., 1.), p(1., 0., 1.), p(1., 1., 1.), p(0., 1., 1.)],
            ),
        ]
    };
    for (n, q) in faces {
        let i = q.map(|v| m.add_vertex(v, Some(n)));
        m.add_quad(i);
    }
    m.validate().unwrap();
    m
}

/// A square in the plane y = `y`, spanning [x0, x1] x [z0, z1], facing -y.
fn quad(y: f64, x0: f64, x1: f64, z0: f64, z1: f64) -> TriMesh {
    let mut m = TriMesh::new();
    let n = Some(-Vec3::y());
    let a = m.add_vertex(Vec3::new(x0, y, z0), n);
    let b = m.add_vertex(Vec3::new(x1, y, z0), n);
    let c = m.add_vertex(Vec3::new(x1, y, z1), n);
    let d = m.add_vertex(Vec3::new(x0, y, z1), n);
    m.add_quad([a, b, c, d]);
    m
}

/// Orthographic camera looking along +y at (0.5, 0.5, 0.5), one world unit to the top edge.
fn front_ortho() -> Camera {
    Camera {
        eye: Vec3::new(0.5, -4.0, 0.5),
        target: Vec3::new(0.5, 0.5, 0.5),
        up: Vec3::z(),
        projection: Projection::Orthographic { half_height: 1.0 },
        near: 0.5,
        far: 10.0,
    }
}

fn is_bg(c: [u8; 3]) -> bool {
    c == BACKGROUND
}

fn count_non_bg(img: &Image) -> usize {
    img.data.chunks(3).filter(|c| *c != BACKGROUND).count()
}

#[test]
fn unit_cube_front_ortho_covers_known_pixels() {
    // 100 x 100 pixels show [-0.5, 1.5]^2 world units: the cube's front face covers exactly
    // pixels 25..75 in both directions.
    let opts = RenderOptions {
        camera: Some(front_ortho()),
        ..RenderOptions::sized(100, 100)
    };
    let img = render(&Scene::new().with_mesh(unit_cube()), &opts).unwrap();
    for (x, y) in [(26, 26), (50, 50), (73, 73), (26, 73), (73, 26)] {
        assert!(!is_bg(img.pixel(x, y)), "({x},{y}) should be cube");
    }
    for (x, y) in [(23, 50), (76, 50), (50, 23), (50, 76), (0, 0), (99, 99)] {
        assert!(is_bg(img.pixel(x, y)), "({x},{y}) should be background");
    }
    // Exactly 50 x 50 pixels, all fully covered (edges fall on pixel boundaries).
    assert_eq!(count_non_bg(&img), 2500);
    // The face is flat and faces the viewer: uniform colour everywhere on it.
    let c = img.pixel(50, 50);
    for (x, y) in [(25, 25), (74, 74), (30, 60)] {
        assert_eq!(img.pixel(x, y), c);
    }
}

#[test]
fn shading_of_a_face_toward_the_viewer_matches_blinn_phong() {
    let opts = RenderOptions {
        camera: Some(front_ortho()),
        ..RenderOptions::sized(40, 40)
    };
    let img = render(&Scene::new().with_mesh(unit_cube()), &opts).unwrap();
    // Normal = direction to the eye = +z of the camera frame.
    let (mut diffuse, mut spec) = (opts.ambient, 0.0);
    for l in &opts.lights {
        let d = l.direction.normalize();
        diffuse += l.intensity * d.z.max(0.0);
        let h = (d + Vec3::z()).normalize();
        spec += l.intensity * h.z.powi(40);
    }
    let base = vclay_render::scene::CLAY;
    let expect =
        base.map(|b| ((b as f64 / 255.0 * diffuse + opts.specular * spec).min(1.0)) * 255.0);
    let got = img.pixel(20, 20);
    for k in 0..3 {
        assert!(
            (got[k] as f64 - expect[k]).abs() <= 1.0,
            "channel {k}: got {got:?}, expected {expect:?}"
        );
    }
}

#[test]
fn anti_aliasing_blends_partially_covered_pixels() {
    // Half a pixel of offset: the face edges cut pixels 25 and 74 in half.
    let mut cam = front_ortho();
    cam.eye.x += 0.01;
    cam.target.x += 0.01;
    let opts = RenderOptions {
        camera: Some(cam),
        ..RenderOptions::sized(100, 100)
    };
    let img = render(&Scene::new().with_mesh(unit_cube()), &opts).unwrap();
    let inside = img.pixel(50, 50);
    let edge = img.pixel(24, 50);
    // Strictly between background and face colour.
    for k in 0..3 {
        let (lo, hi) = (inside[k].min(BACKGROUND[k]), inside[k].max(BACKGROUND[k]));
        assert!(
            lo < edge[k] && edge[k] < hi,
            "edge {edge:?} inside {inside:?}"
        );
    }
    let plain = RenderOptions {
        supersample: 1,
        ..opts
    };
    let hard = render(&Scene::new().with_mesh(unit_cube()), &plain).unwrap();
    let e = hard.pixel(24, 50);
    assert!(
        e == BACKGROUND || e == hard.pixel(50, 50),
        "no blending without supersampling"
    );
}

#[test]
fn nearer_surface_wins_whatever_the_drawing_order() {
    let red = [220, 0, 0];
    let blue = [0, 0, 220];
    let near = quad(0.0, 0.0, 1.0, 0.0, 1.0);
    let far = quad(0.5, -0.5, 1.5, -0.5, 1.5);
    for swap in [false, true] {
        let mut s = Scene::new();
        if swap {
            s.add_mesh(far.clone(), blue);
            s.add_mesh(near.clone(), red);
        } else {
            s.add_mesh(near.clone(), red);
            s.add_mesh(far.clone(), blue);
        }
        let opts = RenderOptions {
            camera: Some(front_ortho()),
            supersample: 1,
            ..RenderOptions::sized(100, 100)
        };
        let img = render(&s, &opts).unwrap();
        let c = img.pixel(50, 50);
        assert!(
            c[0] > 100 && c[2] < 40,
            "swap={swap}: centre {c:?} should be red"
        );
        let c = img.pixel(15, 50);
        assert!(
            c[2] > 100 && c[0] < 40,
            "swap={swap}: border {c:?} should be blue"
        );
    }
}

#[test]
fn lines_and_markers_are_hidden_behind_surfaces() {
    let mut s = Scene::new();
    s.add_mesh(quad(0.0, 0.0, 1.0, 0.0, 1.0), [200, 200, 200]);
    // In front of the quad (y = -0.1): visible; behind it (y = 0.3): hidden.
    s.add_polyline(
        vec![Vec3::new(-0.4, -0.1, 0.25), Vec3::new(1.4, -0.1, 0.25)],
        [0, 0, 0],
        2.0,
    );
    s.add_polyline(
        vec![Vec3::new(-0.4, 0.3, 0.75), Vec3::new(1.4, 0.3, 0.75)],
        [0, 0, 0],
        2.0,
    );
    s.add_markers(&[Vec3::new(0.5, -0.2, 0.5)], [0, 200, 0], 3.0);
    let opts = RenderOptions {
        camera: Some(front_ortho()),
        ..RenderOptions::sized(100, 100)
    };
    let img = render(&s, &opts).unwrap();
    // z = 0.25 maps to row 62.5 and z = 0.75 to row 37.5 (y grows downward).
    assert!(img.pixel(50, 62)[0] < 60, "front line visible");
    assert!(
        img.pixel(10, 37)[0] < 60,
        "hidden line visible outside the quad"
    );
    assert!(img.pixel(50, 37)[0] > 150, "line behind the quad is hidden");
    let m = img.pixel(50, 50);
    assert!(m[1] > 150 && m[0] < 60, "marker {m:?}");
}

#[test]
fn iso_view_frames_the_cube_and_shows_three_shades() {
    let opts = RenderOptions::sized(80, 60);
    let img = render(&Scene::new().with_mesh(unit_cube()), &opts).unwrap();
    assert!(!is_bg(img.pixel(40, 30)), "centre is cube");
    for (x, y) in [(0, 0), (79, 0), (0, 59), (79, 59)] {
        assert!(is_bg(img.pixel(x, y)), "corner ({x},{y}) is background");
    }
    // Framed: the object spans a good part of the picture but stays inside with a margin.
    let n = count_non_bg(&img);
    assert!(n > 800 && n < 3000, "{n} cube pixels");
    let cols: Vec<u32> = (0..80)
        .filter(|&x| (0..60).any(|y| !is_bg(img.pixel(x, y))))
        .collect();
    assert!(*cols.first().unwrap() > 2 && *cols.last().unwrap() < 77);
    // Top, front and right faces have three distinct flat shades.
    let mut shades: Vec<[u8; 3]> = img
        .data
        .chunks(3)
        .map(|c| [c[0], c[1], c[2]])
        .filter(|c| !is_bg(*c))
        .collect();
    shades.sort();
    let mut counts: Vec<usize> = shades.chunk_by(|a, b| a == b).map(|g| g.len()).collect();
    counts.sort_unstable_by(|a, b| b.cmp(a));
    assert!(
        counts.len() >= 3 && counts[2] > 100,
        "three large flat faces: {:?}",
        &counts[..3]
    );
}

#[test]
fn named_views_see_the_expected_faces() {
    // Colour each face of a cube differently by using six single-face meshes.
    let cube = unit_cube();
    let colors = [
        [255, 0, 0],
        [0, 255, 0],
        [0, 0, 255],
        [255, 255, 0],
        [0, 255, 255],
        [255, 0, 255],
    ];
    let mut s = Scene::new();
    for (f, col) in colors.iter().enumerate() {
        let mut m = TriMesh::new();
        m.positions = cube.positions[4 * f..4 * f + 4].to_vec();
        m.normals = cube.normals[4 * f..4 * f + 4].to_vec();
        m.triangles = vec![[0, 1, 2], [0, 2, 3]];
        s.add_mesh(m, *col);
    }
    // front sees the -y face (red), side the +x face (yellow), top the +z face (magenta).
    for (view, dominant) in [
        (View::Front, [true, false, false]),
        (View::Side, [true, true, false]),
        (View::Top, [true, false, true]),
    ] {
        let opts = RenderOptions {
            view,
            orthographic: true,
            ..RenderOptions::sized(40, 40)
        };
        let c = render(&s, &opts).unwrap().pixel(20, 20);
        let on = c.map(|v| v > 60);
        assert_eq!(on, dominant, "{view:?}: centre {c:?}");
    }
}

#[test]
fn png_round_trip_is_lossless_and_gif_has_all_frames() {
    let opts = RenderOptions::sized(24, 18);
    let img = render(&Scene::new().with_mesh(unit_cube()), &opts).unwrap();
    let back = Image::decode_png(&img.encode_png().unwrap()).unwrap();
    assert!(back == img, "PNG round trip");
    // Three frames: a quarter turn would show the symmetric cube unchanged.
    let frames = turntable(&Scene::new().with_mesh(unit_cube()), 3, &opts).unwrap();
    // A turntable frames the bounding sphere (constant size while turning).
    let (c, r) = Scene::new()
        .with_mesh(unit_cube())
        .bounding_sphere()
        .unwrap();
    let sphere = RenderOptions {
        camera: Some(opts.camera_for(c, r).unwrap()),
        ..opts.clone()
    };
    let first = render(&Scene::new().with_mesh(unit_cube()), &sphere).unwrap();
    assert!(frames[0] == first, "turntable starts at the requested view");
    assert!(frames[1] != frames[0], "the camera turns");
    let bytes = encode_gif(&frames, 80).unwrap();
    let mut dec = gif::DecodeOptions::new();
    dec.set_color_output(gif::ColorOutput::RGBA);
    let mut d = dec.read_info(std::io::Cursor::new(bytes)).unwrap();
    let mut n = 0;
    while let Some(f) = d.read_next_frame().unwrap() {
        assert_eq!((f.width, f.height, f.delay), (24, 18, 8));
        n += 1;
    }
    assert_eq!(n, 3);
}

#[test]
fn frames_share_one_camera() {
    let a = Scene::new().with_mesh(unit_cube());
    let mut moved = unit_cube();
    for p in &mut moved.positions {
        p.x += 2.0;
    }
    let b = Scene::new().with_mesh(moved);
    let opts = RenderOptions {
        view: View::Front,
        ..RenderOptions::sized(60, 30)
    };
    let f = render_frames(&[a.clone(), b], &opts).unwrap();
    // One camera frames both: the first cube is on the left half, the second on the right.
    let left = |img: &Image| (0..30).filter(|&x| !is_bg(img.pixel(x, 15))).count();
    assert!(left(&f[0]) > 5 && left(&f[1]) == 0);
    // A single-frame render frames the cube alone, so it looks different.
    assert!(render(&a, &opts).unwrap() != f[0]);
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let s = Scene::new().with_mesh(unit_cube());
    let e = render(&s, &RenderOptions::sized(0, 10)).unwrap_err();
    assert!(e.to_string().contains("0x10"), "{e}");
    assert!(matches!(
        render(&Scene::new(), &RenderOptions::sized(8, 8)),
        Err(vclay_render::RenderError::EmptyScene)
    ));
    let mut bad = unit_cube();
    bad.positions[3].y = f64::NAN;
    let e = render(&Scene::new().with_mesh(bad), &RenderOptions::sized(8, 8)).unwrap_err();
    assert!(
        e.to_string().contains("mesh 0") && e.to_string().contains("vertex 3"),
        "{e}"
    );
    let mut cam = front_ortho();
    cam.up = Vec3::y();
    let e = render(
        &s,
        &RenderOptions {
            camera: Some(cam),
            ..RenderOptions::sized(8, 8)
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("parallel"), "{e}");
    assert!(encode_gif(&[], 10).is_err());
}

#[test]
fn golden_iso_cube() {
    // Golden image with a tolerance: mean absolute difference below 1 level and no pixel off by
    // more than 48 levels (anti-aliasing round-off). Regenerate with VCLAY_UPDATE_GOLDEN=1.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/cube_iso.png");
    let mut s = Scene::new().with_mesh(unit_cube());
    s.add_control_net(
        &[
            Vec3::new(-0.2, -0.2, 1.3),
            Vec3::new(1.2, -0.2, 1.3),
            Vec3::new(-0.2, 1.2, 1.3),
            Vec3::new(1.2, 1.2, 1.3),
        ],
        &[2, 2],
        vclay_render::scene::NET,
    )
    .unwrap();
    let img = render(&s, &RenderOptions::sized(64, 48)).unwrap();
    if std::env::var_os("VCLAY_UPDATE_GOLDEN").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        img.write_png(&path).unwrap();
    }
    let golden = Image::decode_png(&std::fs::read(&path).unwrap()).unwrap();
    assert_eq!((golden.width, golden.height), (img.width, img.height));
    let diffs: Vec<i32> = img
        .data
        .iter()
        .zip(&golden.data)
        .map(|(a, b)| (*a as i32 - *b as i32).abs())
        .collect();
    let mean = diffs.iter().sum::<i32>() as f64 / diffs.len() as f64;
    let max = *diffs.iter().max().unwrap();
    assert!(mean < 1.0 && max <= 48, "mean {mean}, max {max}");
}

#[test]
fn write_animation_writes_gif_or_numbered_pngs() {
    let dir = tempfile::tempdir().unwrap();
    let frames: Vec<Scene> = (0..3)
        .map(|k| {
            let mut m = unit_cube();
            for p in &mut m.positions {
                p.z *= 1.0 + 0.5 * k as f64;
            }
            Scene::new().with_mesh(m)
        })
        .collect();
    let opts = RenderOptions::sized(20, 16);
    let files =
        vclay_render::write_animation(dir.path().join("run.png"), &frames, &opts, 50).unwrap();
    assert_eq!(files.len(), 3);
    assert!(files[2].ends_with("run_0002.png"));
    let last = Image::decode_png(&std::fs::read(&files[2]).unwrap()).unwrap();
    let first = Image::decode_png(&std::fs::read(&files[0]).unwrap()).unwrap();
    assert!(count_non_bg(&last) > count_non_bg(&first), "the cube grows");
    let gif =
        vclay_render::write_animation(dir.path().join("run.gif"), &frames, &opts, 50).unwrap();
    assert_eq!(&std::fs::read(&gif[0]).unwrap()[..6], b"GIF89a");
    assert!(vclay_render::write_animation(dir.path().join("run.mp4"), &frames, &opts, 50).is_err());
}

#[test]
fn framing_fits_the_projected_object_with_the_margin() {
    // A long thin bar seen from the front: its width, not its bounding sphere, sets the scale.
    let mut bar = unit_cube();
    for p in &mut bar.positions {
        p.x = 4.0 * p.x + 10.0;
        p.z *= 0.2;
    }
    for orthographic in [true, false] {
        let opts = RenderOptions {
            view: View::Front,
            orthographic,
            ..RenderOptions::sized(110, 80)
        };
        let img = render(&Scene::new().with_mesh(bar.clone()), &opts).unwrap();
        let cols: Vec<u32> = (0..110)
            .filter(|&x| (0..80).any(|y| !is_bg(img.pixel(x, y))))
            .collect();
        let rows: Vec<u32> = (0..80)
            .filter(|&y| (0..110).any(|x| !is_bg(img.pixel(x, y))))
            .collect();
        let (x0, x1) = (cols[0], *cols.last().unwrap());
        // 110 / FRAME_MARGIN = 100 pixels wide, centred: columns 5..104 (one pixel of slack).
        assert!(
            (4..=6).contains(&x0) && (103..=105).contains(&x1),
            "ortho={orthographic}: {x0}..{x1}"
        );
        let (y0, y1) = (rows[0], *rows.last().unwrap());
        assert!(
            (y0 + y1) / 2 >= 38 && (y0 + y1) / 2 <= 41,
            "vertically centred: {y0}..{y1}"
        );
    }
}
