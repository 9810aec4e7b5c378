//! The smooth brush ([`crate::Edit::Smooth`]): a local fairing of the **rest** shape that the
//! physics then settles, so the clay smooths by its own dynamics instead of being moved
//! (issue 27: "a local stiffer fairness ... settled by the physics").
//!
//! One umbrella (Laplacian) step over the control net's edges (the `ControlNet` line set every
//! kind draws) at the selected control points `i`:
//!
//! ```text
//! p0_i <- p0_i + s (mean_{j in N(i)} p0_j - p0_i),      0 < s <= 1
//! ```
//!
//! (Taubin's umbrella operator, SIGGRAPH 1995, applied to the rest positions). The elastic
//! forces of the model (springs of `solids-journal.txt` section 4; the thin-plate energy of
//! `d-nurbs.txt` eq 17 against its rest shape) then pull the current shape towards the smoothed
//! rest shape. Points with no neighbour and fixed points stay.

use vclay_core::Vec3;

use crate::SessionError;
use crate::command::{Edit, Selection};
use crate::model::{LineRole, LineSet};
use crate::tools::ControlNet;

/// What an [`Edit::Smooth`] does to `net`, whose edges are the `control_net` line set: the rest
/// control points after one umbrella step of the edit's strength (default 0.5) at the unfixed
/// points under its brush (current positions; radius 0: the nearest point), and how many
/// points were smoothed. The kinds put the result into their rest shape.
pub(crate) fn smoothed_rest<N: ControlNet + ?Sized>(
    net: &N,
    control_net: LineSet,
    edit: &Edit,
) -> Result<(Vec<Vec3>, usize), SessionError> {
    let Edit::Smooth {
        near,
        radius,
        strength,
    } = edit
    else {
        return Err(SessionError::model("not a smooth edit"));
    };
    let sel = if *radius > 0.0 {
        Selection::brush(*near, *radius)
    } else {
        Selection::nearest(*near)
    };
    let selected: Vec<usize> = crate::tools::select_points(net, &sel)
        .map_err(|e| SessionError::command("", "", e))?
        .into_iter()
        .filter(|&i| !net.is_fixed(i))
        .collect();
    let rest = net.rest_points();
    let nb = neighbours(&[control_net], rest.len());
    let smoothed = smooth_rest(&rest, &nb, &selected, strength.unwrap_or(0.5));
    Ok((smoothed, selected.len()))
}

/// The log line of a smooth edit that smoothed `n` control points.
pub(crate) fn message(n: usize) -> String {
    format!("smoothed the rest shape at {n} control points")
}

/// The control net's neighbours of each of `n` points, from the segments of the model's
/// [`LineRole::ControlNet`] line sets (duplicates removed).
pub(crate) fn neighbours(lines: &[LineSet], n: usize) -> Vec<Vec<usize>> {
    let mut out = vec![Vec::new(); n];
    for set in lines
        .iter()
        .filter(|l| l.role == Some(LineRole::ControlNet))
    {
        for &[a, b] in &set.segments {
            let (a, b) = (a as usize, b as usize);
            if a < n && b < n && a != b {
                out[a].push(b);
                out[b].push(a);
            }
        }
    }
    for v in &mut out {
        v.sort_unstable();
        v.dedup();
    }
    out
}

/// The rest shape after one umbrella step of `strength` at `selected` (see the module docs).
pub(crate) fn smooth_rest(
    rest: &[Vec3],
    neighbours: &[Vec<usize>],
    selected: &[usize],
    strength: f64,
) -> Vec<Vec3> {
    let mut out = rest.to_vec();
    for &i in selected {
        let nb = &neighbours[i];
        if nb.is_empty() {
            continue;
        }
        let mean = nb.iter().map(|&j| rest[j]).sum::<Vec3>() / nb.len() as f64;
        out[i] = rest[i] + (mean - rest[i]) * strength;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bump_on_a_line_is_pulled_to_its_neighbours_mean() {
        let rest: Vec<Vec3> = (0..5)
            .map(|i| Vec3::new(i as f64, 0.0, if i == 2 { 1.0 } else { 0.0 }))
            .collect();
        let mut net = LineSet::new(LineRole::ControlNet);
        net.segments = (0..4).map(|i| [i, i + 1]).collect();
        let nb = neighbours(&[net], 5);
        assert_eq!(nb[2], [1, 3]);
        let half = smooth_rest(&rest, &nb, &[2], 0.5);
        assert!((half[2].z - 0.5).abs() < 1e-15 && half[2].x == 2.0);
        assert_eq!(half[1], rest[1], "unselected points stay");
        let full = smooth_rest(&rest, &nb, &[2], 1.0);
        assert_eq!(full[2].z, 0.0);
    }
}
