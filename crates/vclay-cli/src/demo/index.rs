//! The demo's `index.html`: one page with every step's pictures, what each shows, the paper
//! figure it reproduces and the table of timings.
//!
//! Generic: every mesh a step wrote (`.obj`, `.ply`, `.stl`, `.glb`) is rendered headless to a
//! PNG beside it (`torus.obj` -> `torus.obj.png`, [`PICTURE_SIZE`]); pictures a step wrote itself
//! (`.png`, `.gif`, `.svg`) are shown as they are; every other file is linked.

use super::Record;
use anyhow::Result;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// Size of the pictures rendered for the page (small, so the demo stays quick). They render on
/// all cores, one picture per thread.
pub const PICTURE_SIZE: (u32, u32) = (480, 360);

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn ext(f: &str) -> String {
    Path::new(f)
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

fn is_mesh(f: &str) -> bool {
    matches!(ext(f).as_str(), "obj" | "ply" | "stl" | "glb")
}

/// Renders every mesh file of the records to `FILE.png`, on as many threads as the machine has;
/// returns each file's outcome (an error message when it failed).
fn render_meshes(out: &Path, records: &[Record]) -> HashMap<String, Result<(), String>> {
    let jobs: Vec<&String> = records
        .iter()
        .flat_map(|r| r.files.iter())
        .filter(|f| is_mesh(f))
        .collect();
    let next = AtomicUsize::new(0);
    let workers = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(jobs.len())
        .max(1);
    let (w, h) = PICTURE_SIZE;
    let done: Vec<Vec<(String, Result<(), String>)>> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|_| {
                scope.spawn(|| {
                    let mut mine = Vec::new();
                    loop {
                        let k = next.fetch_add(1, Ordering::Relaxed);
                        let Some(f) = jobs.get(k) else { break };
                        let png = out.join(format!("{f}.png"));
                        let r = crate::render::mesh_to_png(&out.join(f), &png, w, h)
                            .map_err(|e| format!("{e:#}"));
                        mine.push(((*f).clone(), r));
                    }
                    mine
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join()
                    .unwrap_or_else(|_| vec![("?".into(), Err("render thread panicked".into()))])
            })
            .collect()
    });
    done.into_iter().flatten().collect()
}

/// Renders the steps' meshes and writes `out/index.html`. Returns the number of pictures rendered
/// and the milliseconds it took.
pub(super) fn write_index(out: &Path, records: &[Record]) -> Result<(usize, f64)> {
    let t0 = Instant::now();
    let results = render_meshes(out, records);
    let mut rendered = 0;
    let mut body = String::new();
    for (k, r) in records.iter().enumerate() {
        let _ = writeln!(
            body,
            "<section id=\"step-{k}\">\n<h2>{}. {}</h2>\n<p>{}</p>",
            k + 1,
            esc(r.name),
            esc(&r.what)
        );
        let repro = if r.reproduces.is_empty() {
            "No paper figure: a capability check.".to_string()
        } else {
            format!("Reproduces: <b>{}</b>.", esc(r.reproduces))
        };
        let _ = writeln!(body, "<p class=\"repro\">{repro}</p>\n<div class=\"pics\">");
        let mut others = Vec::new();
        for f in &r.files {
            let e = ext(f);
            let pic = match e.as_str() {
                _ if is_mesh(f) && results.contains_key(f) => {
                    let png = format!("{f}.png");
                    match &results[f] {
                        Ok(()) => {
                            rendered += 1;
                            others.push(f.clone());
                            Some(png)
                        }
                        Err(err) => {
                            eprintln!("demo index: cannot render {f}: {err}");
                            let _ = writeln!(
                                body,
                                "<p class=\"err\">Could not render {}: {}</p>",
                                esc(f),
                                esc(err)
                            );
                            others.push(f.clone());
                            None
                        }
                    }
                }
                "png" | "gif" | "svg" => Some(f.clone()),
                _ => {
                    others.push(f.clone());
                    None
                }
            };
            if let Some(p) = pic {
                let _ = writeln!(
                    body,
                    "<figure><img src=\"{0}\" alt=\"{1}\"><figcaption>{1}</figcaption></figure>",
                    esc(&p),
                    esc(f)
                );
            }
        }
        body.push_str("</div>\n");
        if !others.is_empty() {
            let links: Vec<String> = others
                .iter()
                .map(|f| format!("<a href=\"{0}\">{0}</a>", esc(f)))
                .collect();
            let _ = writeln!(body, "<p class=\"files\">Files: {}</p>", links.join(", "));
        }
        body.push_str("</section>\n");
    }
    let mut table = String::from(
        "<table>\n<tr><th>#</th><th>step</th><th>time (ms)</th><th>reproduces</th><th>result</th></tr>\n",
    );
    let mut total = 0.0;
    for (k, r) in records.iter().enumerate() {
        total += r.millis;
        let _ = writeln!(
            table,
            "<tr><td>{}</td><td><a href=\"#step-{k}\">{}</a></td><td class=\"num\">{:.1}</td><td>{}</td><td>{}</td></tr>",
            k + 1,
            esc(r.name),
            r.millis,
            esc(r.reproduces),
            esc(&r.what)
        );
    }
    let _ = writeln!(
        table,
        "<tr><td></td><td><b>total</b></td><td class=\"num\"><b>{total:.1}</b></td><td></td><td></td></tr>\n</table>"
    );
    let html = format!(
        r#"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>vclay demo</title>
<style>
body {{ font-family: sans-serif; max-width: 1100px; margin: 2em auto; color: #222; }}
table {{ border-collapse: collapse; margin-bottom: 2em; }}
td, th {{ border: 1px solid #ccc; padding: 4px 8px; vertical-align: top; }}
td.num {{ text-align: right; font-variant-numeric: tabular-nums; }}
.pics {{ display: flex; flex-wrap: wrap; gap: 12px; }}
figure {{ margin: 0; }}
figure img {{ max-width: 480px; border: 1px solid #ddd; }}
figcaption {{ font-size: 0.85em; color: #555; }}
.repro {{ color: #444; }}
.err {{ color: #b00; }}
</style>
</head>
<body>
<h1>vclay demo</h1>
<p>Every step of <code>vclay demo</code>: what it computed, the paper figure it reproduces, its
pictures (rendered headless by vclay's software renderer) and the files it wrote.</p>
<h2>Timings</h2>
{table}
{body}
<script>
// For headless checks (bench/check_index.sh): how many pictures loaded, and which did not.
window.addEventListener('load', () => {{
  const imgs = Array.from(document.images);
  const broken = imgs.filter((i) => !i.complete || i.naturalWidth === 0).map((i) => i.getAttribute('src'));
  document.body.setAttribute('data-images', String(imgs.length));
  document.body.setAttribute('data-broken', broken.join(' '));
}});
</script>
</body>
</html>
"#
    );
    let path = out.join("index.html");
    vclay::io::write_atomic(&path, |w| w.write_all(html.as_bytes()))?;
    Ok((rendered, t0.elapsed().as_secs_f64() * 1e3))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_shows_rendered_meshes_pictures_links_and_timings() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path();
        std::fs::create_dir_all(out.join("sub")).unwrap();
        std::fs::write(
            out.join("sub/tri.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n",
        )
        .unwrap();
        std::fs::write(
            out.join("plot.svg"),
            "<svg xmlns=\"http://www.w3.org/2000/svg\"/>",
        )
        .unwrap();
        std::fs::write(out.join("model.json"), "{}").unwrap();
        let records = vec![
            Record {
                name: "mesh <step>",
                reproduces: "paper.txt Fig 2",
                what: "a tetrahedron & a plot".into(),
                files: vec!["sub/tri.obj".into(), "plot.svg".into(), "model.json".into()],
                millis: 12.5,
            },
            Record {
                name: "no files",
                reproduces: "",
                what: "nothing written".into(),
                files: vec![],
                millis: 1.0,
            },
        ];
        let (n, _) = write_index(out, &records).unwrap();
        assert_eq!(n, 1);
        assert!(out.join("sub/tri.obj.png").exists());
        let html = std::fs::read_to_string(out.join("index.html")).unwrap();
        assert!(html.contains("<img src=\"sub/tri.obj.png\""));
        assert!(html.contains("<img src=\"plot.svg\""));
        assert!(html.contains("<a href=\"model.json\">"));
        assert!(html.contains("mesh &lt;step&gt;"), "names are escaped");
        assert!(html.contains("Reproduces: <b>paper.txt Fig 2</b>"));
        assert!(html.contains("No paper figure"));
        assert!(html.contains("<b>13.5</b>"), "total time");
    }
}
