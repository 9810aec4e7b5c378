//! Painted material as a colour map (`Model::display_fields`): choosing the paint tool colours
//! the cube by edge stiffness; a uniform cube keeps the clay colour, a painted one shows the
//! map's cool and warm ends; View > Colour goes back to clay.
use crate::common;

use egui::Key;
use egui::accesskit::Role;
use vclay_session::{Command, Edit};
use vclay_studio::render::{CLAY, Layers, SceneBuffers};
use vclay_studio::worker::Request;
use vclay_studio::{Studio, Tool};

use common::{click, harness, quiet, wait_for};

/// The distinct vertex colours of the shaded mesh.
fn colours(s: &Studio) -> Vec<[u32; 3]> {
    let b = SceneBuffers::build(s.frame(), &Layers::default());
    let mut c: Vec<[u32; 3]> = b
        .tri_vertices
        .chunks(9)
        .map(|v| [v[6], v[7], v[8]].map(|x| (x * 1000.0).round() as u32))
        .collect();
    c.sort();
    c.dedup();
    c
}

#[test]
fn the_paint_tool_shows_stiffness_as_colours() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(quiet(dir.path()));
    click(
        &mut h,
        Role::Button,
        "4^3 subdivision cube (rope, extrude, delete cell)",
    );
    wait_for(&mut h, 30, "first frame", |s| !s.frame().models.is_empty());
    let clay = [CLAY.map(|x| (x * 1000.0).round() as u32)];
    assert_eq!(colours(h.state()), clay);
    h.key_press(Key::P);
    h.step();
    assert_eq!(h.state().tool, Tool::Paint);
    assert_eq!(h.state().colour_by, Some("edge-stiffness"));
    wait_for(&mut h, 30, "the field in the frame", |s| {
        s.frame().models[0].field.is_some()
    });
    // Nothing painted yet: uniform, clay.
    assert_eq!(colours(h.state()), clay);
    let paint: Edit = serde_json::from_value(serde_json::json!({
        "action": "material", "cells": [0], "edge_stiffness": 5000.0
    }))
    .unwrap();
    h.state()
        .worker()
        .unwrap()
        .send(Request::Apply(Command::new(paint)));
    wait_for(&mut h, 30, "the painted frame", |s| {
        s.frame().models[0]
            .field
            .as_deref()
            .is_some_and(|f| vclay_studio::render::field_range(f).is_some())
    });
    let c = colours(h.state());
    assert!(
        c.len() > 2,
        "a painted cube has a range of colours: {c:?}; log {:?}",
        h.state().log().collect::<Vec<_>>()
    );
    assert!(!c.contains(&clay[0]));
    h.state_mut().choose_colour(None);
    wait_for(&mut h, 30, "clay again", |s| {
        s.frame().models[0].field.is_none()
    });
    assert_eq!(colours(h.state()), clay);
}
