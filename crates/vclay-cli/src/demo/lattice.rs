//! Demo steps of the lattice layer (issue 3): subdivision solids.

use anyhow::{Result, ensure};
use std::path::Path;
use vclay::io::mesh::write_mesh;
use vclay::lattice::formats::vtu;
use vclay::lattice::{BoundaryRule, Features, SubdivisionRules, SubdivisionSolid, boundary_mesh};
use vclay::lattice::{Lattice, primitives};

fn subdivide(control: Lattice, levels: usize) -> Result<SubdivisionSolid> {
    let features = Features::none(&control);
    Ok(SubdivisionSolid::new(
        control,
        features,
        SubdivisionRules::new(BoundaryRule::Smooth),
        levels,
    )?)
}

/// The paper's gear (16 cells, `subdivision-solids-conference.txt` Table 1 and Fig. 1) and
/// tetrahedron with holes (one cell) subdivided with smooth boundaries; each written as a VTK
/// unstructured grid (cells) and an OBJ (boundary surface). Checks the counts against Table 1.
pub fn subdivided_solids(out: &Path) -> Result<(String, Vec<String>)> {
    std::fs::create_dir_all(out.join("subdivision"))?;
    let mut files = Vec::new();
    let mut parts = Vec::new();
    let cases = [
        (
            "gear",
            primitives::gear(1.0, 2.0, 2.6, 0.5),
            2,
            [1480, 3864, 3344, 960],
        ),
        (
            "tetrahedron-with-holes",
            primitives::tetrahedron_with_holes(2.0, 0.5),
            3,
            [2505, 6808, 6048, 1744],
        ),
    ];
    for (name, control, levels, table1) in cases {
        let control_cells = control.num_cells();
        let solid = subdivide(control, levels)?;
        let fine = solid.finest();
        let counts = fine.counts().to_array();
        ensure!(
            counts == table1,
            "{name}: counts {counts:?} differ from Table 1 {table1:?}"
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
            "{}; element counts equal the conference paper's Table 1",
            parts.join("; ")
        ),
        files,
    ))
}
