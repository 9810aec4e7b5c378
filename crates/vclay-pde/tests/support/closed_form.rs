//! The closed-form solution of `dynamic-pde-surfaces.txt` section III, eq (13)-(17), computed
//! independently of vclay-pde's solver: each component is `sum f_ij(u) g_ij(v)` where f_ij solves
//! the ODE that the PDE (1) gives for that g (b = 1, c = 2k^2, d = k^4, static):
//!
//! - g = 1 or v (g'' = 0): f'''' = 0, so f is a cubic (eq 15);
//! - g = exp(0.1 v) (g'' = 0.01 g): (D^2 + (0.1k)^2)^2 f = 0, so
//!   f = (c0 + c1 u) cos(0.1 k u) + (c2 + c3 u) sin(0.1 k u) (eq 16);
//! - g = sin v or cos v (g'' = -g): (D^2 - k^2)^2 f = 0, so
//!   f = (c0 + c1 u) e^(k u) + (c2 + c3 u) e^(-k u) (eq 17);
//!
//! with the four constants fitted to f(0), f'(0), f(1), f'(1) from eq (13) by a 4 x 4 Gaussian
//! elimination.
#![allow(dead_code)]

/// Parameters of eq (13) as printed below Fig 1.
pub struct Section3 {
    pub a: f64,
    pub b: f64,
    pub c: f64,
    pub ap: f64,
    pub bp: f64,
    pub cp: f64,
    pub d: f64,
    pub dp: f64,
    pub e: f64,
    pub ep: f64,
    pub f: f64,
    pub fp: f64,
    pub h0: f64,
    pub h0p: f64,
    pub h1: f64,
    pub h1p: f64,
    pub r: f64,
    pub rp: f64,
    /// The paper's a_i (shape parameter), 3.
    pub k: f64,
}

impl Section3 {
    pub fn paper() -> Self {
        Section3 {
            a: 4.763,
            b: 0.017,
            c: -3.395,
            ap: 0.0,
            bp: 0.0,
            cp: 0.0,
            d: 0.475,
            dp: 0.475,
            e: 0.0159,
            ep: 0.0159,
            f: -0.475,
            fp: -0.475,
            h0: 3.0,
            h0p: -3.0,
            h1: 0.1,
            h1p: -0.1,
            r: 1.0,
            rp: 1.0,
            k: 3.0,
        }
    }
}

/// Value and first derivative of four ODE basis functions at u.
type Basis = fn(f64, f64) -> [[f64; 2]; 4];

fn cubic(u: f64, _w: f64) -> [[f64; 2]; 4] {
    [
        [1.0, 0.0],
        [u, 1.0],
        [u * u, 2.0 * u],
        [u * u * u, 3.0 * u * u],
    ]
}

fn trig(u: f64, w: f64) -> [[f64; 2]; 4] {
    let (s, c) = (w * u).sin_cos();
    [
        [c, -w * s],
        [u * c, c - w * u * s],
        [s, w * c],
        [u * s, s + w * u * c],
    ]
}

fn hyper(u: f64, k: f64) -> [[f64; 2]; 4] {
    let (ep, em) = ((k * u).exp(), (-k * u).exp());
    [
        [ep, k * ep],
        [u * ep, ep + k * u * ep],
        [em, -k * em],
        [u * em, em - k * u * em],
    ]
}

/// Solves a 4 x 4 system by Gaussian elimination with partial pivoting.
fn solve4(mut m: [[f64; 4]; 4], mut r: [f64; 4]) -> [f64; 4] {
    for col in 0..4 {
        let piv = (col..4)
            .max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))
            .unwrap();
        m.swap(col, piv);
        r.swap(col, piv);
        for row in col + 1..4 {
            let f = m[row][col] / m[col][col];
            for k in col..4 {
                m[row][k] -= f * m[col][k];
            }
            r[row] -= f * r[col];
        }
    }
    let mut x = [0.0; 4];
    for row in (0..4).rev() {
        let mut s = r[row];
        for k in row + 1..4 {
            s -= m[row][k] * x[k];
        }
        x[row] = s / m[row][row];
    }
    x
}

/// One f_ij: the ODE basis, its parameter, and the fitted constants.
struct Factor {
    basis: Basis,
    w: f64,
    c: [f64; 4],
}

impl Factor {
    fn new(basis: Basis, w: f64, bc: [f64; 4]) -> Self {
        let (b0, b1) = (basis(0.0, w), basis(1.0, w));
        let mut m = [[0.0; 4]; 4];
        for k in 0..4 {
            m[0][k] = b0[k][0];
            m[1][k] = b0[k][1];
            m[2][k] = b1[k][0];
            m[3][k] = b1[k][1];
        }
        Factor {
            basis,
            w,
            c: solve4(m, bc),
        }
    }

    fn eval(&self, u: f64) -> f64 {
        let b = (self.basis)(u, self.w);
        (0..4).map(|k| self.c[k] * b[k][0]).sum()
    }
}

/// The closed-form surface (14).
pub struct ClosedForm {
    x: [Factor; 3],
    y: [Factor; 3],
    z: [Factor; 2],
}

impl ClosedForm {
    pub fn new(p: &Section3) -> Self {
        let k = p.k;
        ClosedForm {
            x: [
                Factor::new(cubic, 0.0, [p.a, p.ap, 0.0, 0.0]),
                Factor::new(trig, 0.1 * k, [p.c, p.cp, 0.0, 0.0]),
                Factor::new(hyper, k, [p.b, p.bp, p.r, p.rp]),
            ],
            y: [
                Factor::new(cubic, 0.0, [p.d, p.dp, 0.0, 0.0]),
                Factor::new(cubic, 0.0, [p.e, p.ep, 0.0, 0.0]),
                Factor::new(hyper, k, [p.f, p.fp, -p.r, -p.rp]),
            ],
            z: [
                Factor::new(cubic, 0.0, [p.h0, p.h0p, 0.0, 0.0]),
                Factor::new(cubic, 0.0, [-p.h1, -p.h1p, 0.0, 0.0]),
            ],
        }
    }

    pub fn point(&self, u: f64, v: f64) -> [f64; 3] {
        [
            self.x[0].eval(u) + self.x[1].eval(u) * (0.1 * v).exp() + self.x[2].eval(u) * v.sin(),
            self.y[0].eval(u) + self.y[1].eval(u) * v + self.y[2].eval(u) * v.cos(),
            self.z[0].eval(u) + self.z[1].eval(u) * v,
        ]
    }
}
