//! Line plots as SVG: energy, residual and step time over a run.
//!
//! **What.** A [`Plot`] is one panel (title, axis labels, linear or logarithmic y axis, one or more
//! [`Series`]); [`panels_svg`] stacks panels into one SVG document; [`RunHistory::to_svg`] draws
//! the standard three panels of a simulation run (energy, residual on a log axis, step time).
//!
//! **How.** SVG is written by hand (no font or drawing library is needed, and browsers render
//! it): axes with "nice" ticks (1, 2 or 5 times a power of ten; whole decades on log axes), one
//! polyline per series, a legend when there are several.
//!
//! **Limitations.** Non-finite values are errors (a diverged run is reported, not plotted);
//! values `<= 0` are errors on a log axis.

use crate::error::RenderError;
use std::fmt::Write as _;
use std::path::Path;

/// Series colours, in order.
const PALETTE: [&str; 6] = [
    "#c0392b", "#2471a3", "#229954", "#7d3c98", "#d68910", "#5d6d7e",
];

/// One curve of a plot.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend label.
    pub name: String,
    /// `(x, y)` samples in drawing order.
    pub points: Vec<(f64, f64)>,
}

/// One plot panel.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Plot {
    /// Title above the panel.
    pub title: String,
    /// Label of the x axis.
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// Logarithmic y axis (all values must be > 0).
    pub log_y: bool,
    /// The curves.
    pub series: Vec<Series>,
}

/// The per-step record of a simulation run, as the run owner collects it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunHistory {
    /// Simulated time (or step index) of each record.
    pub time: Vec<f64>,
    /// Total energy at each record (empty to leave the panel out).
    pub energy: Vec<f64>,
    /// Residual (force or constraint norm) at each record (empty to leave the panel out).
    pub residual: Vec<f64>,
    /// Wall-clock milliseconds of each step (empty to leave the panel out).
    pub step_ms: Vec<f64>,
}

impl RunHistory {
    /// The run as stacked panels (energy, residual on a log axis, step time), `width` pixels wide.
    pub fn to_svg(&self, width: u32) -> Result<String, RenderError> {
        let mut plots = Vec::new();
        let mut panel = |name: &str, title: &str, y: &[f64], unit: &str, log_y: bool| {
            if y.is_empty() {
                return Ok(());
            }
            if y.len() != self.time.len() {
                return Err(RenderError::Plot(format!(
                    "{name}: {} values for {} times",
                    y.len(),
                    self.time.len()
                )));
            }
            plots.push(Plot {
                title: title.into(),
                x_label: "time".into(),
                y_label: unit.into(),
                log_y,
                series: vec![Series {
                    name: name.into(),
                    points: self.time.iter().copied().zip(y.iter().copied()).collect(),
                }],
            });
            Ok(())
        };
        panel("energy", "Energy", &self.energy, "energy", false)?;
        panel("residual", "Residual", &self.residual, "residual", true)?;
        panel("step time", "Step time", &self.step_ms, "ms", false)?;
        panels_svg(&plots, width, 220)
    }
}

/// "Nice" tick positions covering `[lo, hi]` (about `target` of them).
fn nice_ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
    let span = (hi - lo).max(f64::MIN_POSITIVE);
    let raw = span / target.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

fn fmt_tick(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() >= 1e5 || v.abs() < 1e-3 {
        format!("{v:.0e}")
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

impl Plot {
    fn check(&self, index: usize) -> Result<(), RenderError> {
        if self.series.iter().all(|s| s.points.is_empty()) {
            return Err(RenderError::Plot(format!(
                "panel {index} ({}): no data",
                self.title
            )));
        }
        for s in &self.series {
            for (k, &(x, y)) in s.points.iter().enumerate() {
                if !(x.is_finite() && y.is_finite()) {
                    return Err(RenderError::Plot(format!(
                        "panel {index} ({}), series '{}', sample {k}: non-finite value ({x}, {y})",
                        self.title, s.name
                    )));
                }
                if self.log_y && y <= 0.0 {
                    return Err(RenderError::Plot(format!(
                        "panel {index} ({}), series '{}', sample {k}: value {y} <= 0 on a log axis",
                        self.title, s.name
                    )));
                }
            }
        }
        Ok(())
    }

    /// Draws the panel into `svg` in the box `(x0, y0, w, h)`.
    fn draw(&self, svg: &mut String, x0: f64, y0: f64, w: f64, h: f64) {
        let (left, right, top, bottom) = (64.0, 16.0, 28.0, 40.0);
        let (px0, px1) = (x0 + left, x0 + w - right);
        let (py0, py1) = (y0 + top, y0 + h - bottom);
        let pts = self.series.iter().flat_map(|s| s.points.iter());
        let (mut xl, mut xh, mut yl, mut yh) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for &(x, y) in pts {
            let y = if self.log_y { y.log10() } else { y };
            xl = xl.min(x);
            xh = xh.max(x);
            yl = yl.min(y);
            yh = yh.max(y);
        }
        if xh <= xl {
            xl -= 0.5;
            xh += 0.5;
        }
        if yh <= yl {
            let d = if yl == 0.0 { 1.0 } else { 0.1 * yl.abs() };
            yl -= d;
            yh += d;
        }
        let pad = 0.05 * (yh - yl);
        let (yl, yh) = (yl - pad, yh + pad);
        let sx = |x: f64| px0 + (x - xl) / (xh - xl) * (px1 - px0);
        let sy = |y: f64| py1 - (y - yl) / (yh - yl) * (py1 - py0);
        let _ = writeln!(
            svg,
            r##"<text x="{:.1}" y="{:.1}" font-size="14" font-weight="bold">{}</text>"##,
            px0,
            y0 + 18.0,
            escape(&self.title)
        );
        let _ = writeln!(
            svg,
            r##"<rect x="{px0:.1}" y="{py0:.1}" width="{:.1}" height="{:.1}" fill="white" stroke="#444"/>"##,
            px1 - px0,
            py1 - py0
        );
        for t in nice_ticks(xl, xh, 6) {
            let x = sx(t);
            let _ = writeln!(
                svg,
                r##"<line x1="{x:.1}" y1="{py0:.1}" x2="{x:.1}" y2="{py1:.1}" stroke="#ddd"/><text x="{x:.1}" y="{:.1}" font-size="11" text-anchor="middle">{}</text>"##,
                py1 + 14.0,
                fmt_tick(t)
            );
        }
        let yticks: Vec<f64> = if self.log_y {
            (yl.ceil() as i64..=yh.floor() as i64)
                .map(|e| e as f64)
                .collect()
        } else {
            nice_ticks(yl, yh, 5)
        };
        for t in yticks {
            let y = sy(t);
            let label = if self.log_y {
                format!("1e{}", t as i64)
            } else {
                fmt_tick(t)
            };
            let _ = writeln!(
                svg,
                r##"<line x1="{px0:.1}" y1="{y:.1}" x2="{px1:.1}" y2="{y:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" font-size="11" text-anchor="end">{label}</text>"##,
                px0 - 4.0,
                y + 4.0
            );
        }
        let _ = writeln!(
            svg,
            r##"<text x="{:.1}" y="{:.1}" font-size="12" text-anchor="middle">{}</text>"##,
            0.5 * (px0 + px1),
            py1 + 32.0,
            escape(&self.x_label)
        );
        let _ = writeln!(
            svg,
            r##"<text transform="translate({:.1},{:.1}) rotate(-90)" font-size="12" text-anchor="middle">{}</text>"##,
            x0 + 14.0,
            0.5 * (py0 + py1),
            escape(&self.y_label)
        );
        for (k, s) in self.series.iter().enumerate() {
            let color = PALETTE[k % PALETTE.len()];
            let mut d = String::new();
            for &(x, y) in &s.points {
                let y = if self.log_y { y.log10() } else { y };
                let _ = write!(d, "{:.2},{:.2} ", sx(x), sy(y));
            }
            let _ = writeln!(
                svg,
                r##"<polyline fill="none" stroke="{color}" stroke-width="1.6" points="{}"/>"##,
                d.trim_end()
            );
            if self.series.len() > 1 {
                let ly = py0 + 14.0 + 16.0 * k as f64;
                let _ = writeln!(
                    svg,
                    r##"<line x1="{:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="{color}" stroke-width="2"/><text x="{:.1}" y="{:.1}" font-size="11">{}</text>"##,
                    px1 - 110.0,
                    px1 - 90.0,
                    px1 - 85.0,
                    ly + 4.0,
                    escape(&s.name)
                );
            }
        }
    }

    /// This panel alone as an SVG document.
    pub fn to_svg(&self, width: u32, height: u32) -> Result<String, RenderError> {
        panels_svg(std::slice::from_ref(self), width, height)
    }
}

/// Stacks `plots` vertically, each `panel_height` pixels tall, into one SVG document.
pub fn panels_svg(plots: &[Plot], width: u32, panel_height: u32) -> Result<String, RenderError> {
    if plots.is_empty() {
        return Err(RenderError::Plot("no panels".into()));
    }
    if width < 120 || panel_height < 80 {
        return Err(RenderError::Plot(format!(
            "panel size {width}x{panel_height} too small (at least 120x80)"
        )));
    }
    for (i, p) in plots.iter().enumerate() {
        p.check(i)?;
    }
    let (w, h) = (width as f64, panel_height as f64);
    let total = h * plots.len() as f64;
    let mut svg = format!(
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{total}" viewBox="0 0 {width} {total}" font-family="sans-serif">
<rect width="100%" height="100%" fill="#fafafa"/>
"##
    );
    for (i, p) in plots.iter().enumerate() {
        p.draw(&mut svg, 0.0, h * i as f64, w, h);
    }
    svg.push_str("</svg>\n");
    Ok(svg)
}

/// Writes an SVG document atomically.
pub fn write_svg(path: impl AsRef<Path>, svg: &str) -> Result<(), RenderError> {
    vclay_io::write_atomic(path.as_ref(), |w| w.write_all(svg.as_bytes()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_ticks_cover_range_with_round_steps() {
        let t = nice_ticks(0.03, 0.97, 5);
        assert_eq!(t.first().copied(), Some(0.2));
        assert!((t[1] - t[0] - 0.2).abs() < 1e-12);
        assert!(*t.last().unwrap() <= 0.97);
    }

    #[test]
    fn run_history_svg_has_three_panels_and_rejects_nan() {
        let time: Vec<f64> = (0..20).map(|k| k as f64 * 0.1).collect();
        let h = RunHistory {
            energy: time.iter().map(|t| (-t).exp()).collect(),
            residual: time.iter().map(|t| 10f64.powf(-3.0 * t)).collect(),
            step_ms: time.iter().map(|_| 1.5).collect(),
            time: time.clone(),
        };
        let svg = h.to_svg(500).unwrap();
        assert_eq!(svg.matches("<polyline").count(), 3);
        assert!(svg.contains("1e-3"), "log axis has decade labels");
        let mut bad = h.clone();
        bad.energy[4] = f64::NAN;
        let e = bad.to_svg(500).unwrap_err().to_string();
        assert!(e.contains("sample 4"), "{e}");
        let mut neg = h;
        neg.residual[2] = 0.0;
        assert!(
            neg.to_svg(500)
                .unwrap_err()
                .to_string()
                .contains("log axis")
        );
    }
}
