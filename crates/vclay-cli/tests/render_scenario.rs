//! `vclay render SCENARIO.toml`: a scenario is run and its frames animated.
use std::process::{Command, Output};

fn vclay(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vclay"))
        .args(args)
        .output()
        .expect("vclay runs")
}

const EGG: &str = r#"
[model]
kind = "dnurbs-swung"
primitive = "sphere"

[simulation]
dt = 0.05
steps = 12

[[timeline]]
action = "rope"
param = [1.0, 0.0]
from = [0.0, 0.0, 1.5]
stiffness = 30.0
"#;

#[test]
fn a_dnurbs_scenario_renders_to_a_gif_and_to_numbered_pngs() {
    let dir = tempfile::tempdir().unwrap();
    let sc = dir.path().join("egg.toml");
    std::fs::write(&sc, EGG).unwrap();
    let gif = dir.path().join("egg.gif");
    let o = vclay(&[
        "render",
        sc.to_str().unwrap(),
        "--out",
        gif.to_str().unwrap(),
        "--frames",
        "4",
        "--size",
        "64x48",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(&gif).unwrap();
    assert_eq!(&bytes[..6], b"GIF89a");
    let png = dir.path().join("egg.png");
    let o = vclay(&[
        "render",
        sc.to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
        "--frames",
        "3",
        "--size",
        "64x48",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let pngs: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with("egg_"))
        .collect();
    assert_eq!(pngs.len(), 3, "one PNG per frame");
    // A broken scenario is an error with its place, and nothing is written.
    std::fs::write(&sc, EGG.replace("steps = 12", "steps = -1")).unwrap();
    let bad = dir.path().join("bad.gif");
    let o = vclay(&[
        "render",
        sc.to_str().unwrap(),
        "--out",
        bad.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("egg.toml:"));
    assert!(!bad.exists());
}
