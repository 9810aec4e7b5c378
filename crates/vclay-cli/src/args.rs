//! Parsers for compact command-line values: `4x4x4`, `x0,y0,z0,x1,y1,z1`, `SX,SY,SZ:TX,TY,TZ`.
//! Each error names the argument text and what was expected.

use anyhow::{Result, bail};
use vclay::Vec3;

/// Parses `AxBxC` into three positive integers (`4x4x4`); a single number `N` means `NxNxN`.
pub fn triple_usize(text: &str, what: &str) -> Result<[usize; 3]> {
    let parts: Vec<&str> = text.split(['x', 'X']).collect();
    let nums: Result<Vec<usize>, _> = parts.iter().map(|p| p.trim().parse::<usize>()).collect();
    match nums {
        Ok(n) if n.len() == 3 && n.iter().all(|&v| v > 0) => Ok([n[0], n[1], n[2]]),
        Ok(n) if n.len() == 1 && n[0] > 0 => Ok([n[0]; 3]),
        _ => bail!("{what} '{text}': expected three positive integers like 4x4x4"),
    }
}

/// Parses `x,y,z` into a finite point.
pub fn point(text: &str, what: &str) -> Result<Vec3> {
    let v = numbers(text, what, 3)?;
    Ok(Vec3::new(v[0], v[1], v[2]))
}

/// Parses `xmin,ymin,zmin,xmax,ymax,zmax` into a box with positive extent on every axis.
pub fn bbox(text: &str) -> Result<(Vec3, Vec3)> {
    let v = numbers(text, "--box", 6)?;
    let (lo, hi) = (Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5]));
    for a in 0..3 {
        if hi[a] <= lo[a] {
            bail!(
                "--box '{text}': max must exceed min on every axis (axis {} has min {} and max {})",
                ["x", "y", "z"][a],
                lo[a],
                hi[a]
            );
        }
    }
    Ok((lo, hi))
}

/// Parses `SX,SY,SZ:TX,TY,TZ` into a source and a target point.
pub fn movement(text: &str) -> Result<(Vec3, Vec3)> {
    let Some((s, t)) = text.split_once(':') else {
        bail!("--move '{text}': expected SOURCE:TARGET like 0,0,1:0,0,1.5");
    };
    Ok((point(s, "--move source")?, point(t, "--move target")?))
}

fn numbers(text: &str, what: &str, count: usize) -> Result<Vec<f64>> {
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() != count {
        bail!(
            "{what} '{text}': expected {count} comma-separated numbers, found {}",
            parts.len()
        );
    }
    let mut out = Vec::with_capacity(count);
    for (i, p) in parts.iter().enumerate() {
        match p.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => out.push(v),
            _ => bail!(
                "{what} '{text}': item {} ('{}') is not a finite number",
                i + 1,
                p.trim()
            ),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_rejects() {
        assert_eq!(triple_usize("4x5x6", "--lattice").unwrap(), [4, 5, 6]);
        assert_eq!(triple_usize("7", "--lattice").unwrap(), [7, 7, 7]);
        assert!(triple_usize("4x0x4", "--lattice").is_err());
        assert!(triple_usize("4x4", "--lattice").is_err());
        let (s, t) = movement("0,0,1:0.5,-1,2e-1").unwrap();
        assert_eq!(s, Vec3::new(0., 0., 1.));
        assert_eq!(t, Vec3::new(0.5, -1., 0.2));
        let e = movement("0,0,1:0,x,1").unwrap_err().to_string();
        assert!(e.contains("item 2 ('x')"), "{e}");
        assert!(movement("0,0,1").is_err());
        let e = bbox("0,0,0,1,-1,1").unwrap_err().to_string();
        assert!(e.contains("axis y"), "{e}");
        assert!(point("1,2,nan", "p").is_err());
    }
}
