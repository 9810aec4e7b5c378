//! Demo steps of the lattice layer (issue 3): subdivision solids.

use anyhow::{Result, ensure};
use std::path::Path;
use vclay::io::mesh::write_mesh;
use vclay::lattice::formats::vtu;
use vclay::lattice::{BoundaryRule, Features, SubdivisionRules, SubdivisionSolid, boundary_mesh};
use vclay::lattice::{CellId, Lattice, gallery, primitives};

fn subdivide(control: Lattice, levels: usize) -> Result<SubdivisionSolid> {
    let features = Features::none(&control);
    Ok(SubdivisionSolid::new(
        control,
        features,
        SubdivisionRules::new(BoundaryRule::Smooth),
        levels,
    )?)
}

/// The paper's gear (16 cells, `subdivision-solids-conference.txt` Table 1 and Fig. 1), the
/// tetrahedron with holes (split into 10 convex cells so that none folds; issue 19), the soccer
/// player and the cactus (Table 1 and Fig. 1, built by face extrusion) and the journal's spiked
/// and holed objects (`subdivision-solids-journal.txt` Table 2), subdivided with smooth
/// boundaries; each written as a VTK unstructured grid (cells) and an OBJ (boundary surface).
/// Checks the counts against the tables (cells only for Table 2, the only counts it gives) and
/// that no cell of the subdivided lattice has a non-positive volume.
pub fn subdivided_solids(out: &Path) -> Result<(String, Vec<String>)> {
    std::fs::create_dir_all(out.join("subdivision"))?;
    let mut files = Vec::new();
    let mut parts = Vec::new();
    // (name, control lattice, level, the table's [points, edges, faces, cells] at that level,
    // or only its cells).
    type Case = (&'static str, Lattice, usize, Result<[usize; 4], usize>);
    let cases: [Case; 6] = [
        (
            "gear",
            primitives::gear(1.0, 2.0, 2.6, 0.5),
            2,
            Ok([1480, 3864, 3344, 960]),
        ),
        (
            "tetrahedron-with-holes",
            primitives::tetrahedron_with_holes_split(2.0, primitives::DEFAULT_SPLIT_HOLE),
            3,
            Err(52 * 64),
        ),
        (
            "soccer-player",
            gallery::soccer_player(2.0),
            2,
            Ok([2450, 6320, 5408, 1536]),
        ),
        (
            "cactus",
            gallery::cactus(4.0),
            2,
            Ok([2625, 6800, 5840, 1664]),
        ),
        ("spiked-object", gallery::spiked_object(1.0), 1, Err(600)),
        ("holed-object", gallery::holed_object(1.0), 1, Err(1080)),
    ];
    for (name, control, levels, table) in cases {
        let control_cells = control.num_cells();
        let solid = subdivide(control, levels)?;
        let fine = solid.finest();
        let counts = fine.counts().to_array();
        match table {
            Ok(t) => ensure!(
                counts == t,
                "{name}: counts {counts:?} differ from the table's {t:?}"
            ),
            Err(cells) => ensure!(
                counts[3] == cells,
                "{name}: {} cells, expected {cells}",
                counts[3]
            ),
        }
        let folded = (0..fine.num_cells())
            .filter(|&c| fine.cell_signed_volume(CellId::new(c)) <= 0.0)
            .count();
        ensure!(
            folded == 0,
            "{name}: {folded} folded cells at level {levels}"
        );
        let vtu_name = format!("subdivision/{name}-level{levels}.vtu");
        let obj_name = format!("subdivision/{name}-level{levels}.obj");
        vtu::write(fine, &out.join(&vtu_name))?;
        let mut surface = boundary_mesh(fine);
        surface.compute_normals();
        write_mesh(out.join(&obj_name), &surface)?;
        parts.push(format!(
            "{name} {control_cells} -> {} cells at level {levels} ({} points, {} boundary triangles)",
            counts[3],
            counts[0],
            surface.triangles.len()
        ));
        files.push(vtu_name);
        files.push(obj_name);
    }
    Ok((
        format!(
            "{}; element counts equal the conference paper's Table 1 (gear, soccer player, \
             cactus) and the journal's Table 2 cells (spiked and holed objects); no cell folds",
            parts.join("; ")
        ),
        files,
    ))
}
