//! `vclay-studio [FILE] [--autosave PATH] [--paused] [--no-recovery] [--frame-log PATH]
//! [--bench [FRAMES]]`: the interactive studio (also started by `vclay studio ARGS`).

use std::io::Write;
use std::path::PathBuf;

use vclay_studio::{Options, Studio, bench};

const USAGE: &str = "usage: vclay-studio [FILE] [--autosave PATH] [--paused] [--no-recovery] [--frame-log PATH]\n       vclay-studio --bench [FRAMES]\n\nFILE: any file vclay reads, recognized by its content: a scenario, a session, a model file\n(JSON, STEP, IGES), a PDE spec, a triangular model, a lattice (.ovm, .vtu) or a mesh (.obj,\n.stl, .ply, .glb). Without FILE the start page offers built-in models.";

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let mut opts = Options {
        recent: vclay_studio::recent::default_file(),
        chooser: vclay_studio::native::Chooser::find(),
        ..Options::default()
    };
    let mut bench_frames = None;
    while let Some(a) = args.next() {
        match a.as_str() {
            "-h" | "--help" => {
                // Ignore a closed pipe (`vclay-studio --help | head`).
                let _ = writeln!(std::io::stdout(), "{USAGE}");
                return Ok(());
            }
            "--autosave" => {
                let p = args
                    .next()
                    .ok_or_else(|| anyhow::anyhow!("--autosave needs a path\n{USAGE}"))?;
                opts.autosave = Some(PathBuf::from(p));
            }
            "--paused" => opts.paused = true,
            "--frame-log" => {
                let p = args
                    .next()
                    .ok_or_else(|| anyhow::anyhow!("--frame-log needs a path\n{USAGE}"))?;
                opts.frame_log = Some(PathBuf::from(p));
            }
            "--no-recovery" => opts.no_recovery = true,
            "--bench" => {
                bench_frames = Some(300);
            }
            s if s.starts_with('-') => anyhow::bail!("unknown option {s}\n{USAGE}"),
            s => {
                if bench_frames.is_some() {
                    bench_frames = Some(
                        s.parse()
                            .map_err(|_| anyhow::anyhow!("--bench FRAMES: {s} is not a count"))?,
                    );
                } else if opts.file.is_some() {
                    anyhow::bail!("one FILE only\n{USAGE}");
                } else {
                    opts.file = Some(PathBuf::from(s));
                }
            }
        }
    }
    if let Some(frames) = bench_frames {
        return run_bench(frames);
    }
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("vclay studio")
            .with_inner_size([1280.0, 800.0]),
        depth_buffer: 24,
        renderer: eframe::Renderer::Glow,
        ..Default::default()
    };
    eframe::run_native(
        "vclay studio",
        native,
        Box::new(move |_cc| Ok(Box::new(Studio::new(opts)))),
    )
    .map_err(|e| anyhow::anyhow!("cannot open the window: {e}"))
}

fn run_bench(frames: usize) -> anyhow::Result<()> {
    println!(
        "| model | steps/frame | frame ms (mean / max) | CPU ms/frame | steps ms | display ms | buffers ms | triangles | frames/s | goal |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for case in &bench::CASES {
        let r = bench::run(case, frames).map_err(|e| anyhow::anyhow!("{}: {e}", case.name))?;
        println!(
            "| {} | {} | {:.2} / {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {:.0} | {:.0} |",
            r.name,
            r.steps,
            r.frame_ms,
            r.max_ms,
            r.cpu_ms,
            r.step_ms,
            r.display_ms,
            r.buffers_ms,
            r.triangles,
            r.fps(),
            r.goal_fps
        );
    }
    Ok(())
}
