//! Splitting boundary functions into basic functions and coefficients
//! (`dynamic-pde-surfaces.txt` eq 3).
//!
//! What: a boundary function such as `4.763 + 0.017*sin(v) - 3.395*exp(0.1*v)` becomes
//! `4.763 * g_1 + 0.017 * g_2 - 3.395 * g_3` with `g_1 = 1`, `g_2 = sin(v)`, `g_3 = exp(0.1*v)`.
//! The four boundary functions of one component share one list of basic functions g_ij; a basic
//! function missing from a condition has coefficient 0 there (eq 3 with a_ijk = 0).
//!
//! How: the expression tree is expanded into a sum of terms `coefficient * product of factors^k`
//! by distributing products over sums (and integer powers of sums), pulling numbers out, and
//! merging equal factors (`t*t = t^2`). A factor is any non-numeric sub-expression that is not a
//! sum or a product, for example `v`, `sin(5*v)`, `exp(0.1*v)`, `(1 + v^2)^(-1)`. Terms with the
//! same factors are merged.
//!
//! Limitations: identities are not recognised (`sin(v)^2` and `1 - cos(v)^2` are different basic
//! functions); when they make basic functions linearly dependent the solver reports a rank
//! deficiency naming them. Expansion stops at [`MAX_TERMS`] terms, beyond which a product is kept
//! as one factor.

use crate::expr::{Expr, Var, mul, pow};
use std::collections::BTreeMap;

/// Largest number of terms an expansion may produce before a product is kept whole.
pub const MAX_TERMS: usize = 256;

/// Largest integer power of a sum that is expanded (`(1 + v)^3` becomes four terms).
pub const MAX_EXPANDED_POWER: i32 = 8;

/// One term of an expanded expression: `coefficient * prod(factor^power)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Term {
    /// The numeric coefficient.
    pub coefficient: f64,
    /// Factors by canonical text, with their expression and integer power (never 0).
    pub factors: BTreeMap<String, (Expr, i32)>,
}

impl Term {
    fn number(c: f64) -> Self {
        Term {
            coefficient: c,
            factors: BTreeMap::new(),
        }
    }

    fn factor(e: Expr) -> Self {
        let mut factors = BTreeMap::new();
        factors.insert(e.to_string(), (e, 1));
        Term {
            coefficient: 1.0,
            factors,
        }
    }

    fn times(&self, other: &Term) -> Term {
        let mut factors = self.factors.clone();
        for (k, (e, p)) in &other.factors {
            let entry = factors.entry(k.clone()).or_insert((e.clone(), 0));
            entry.1 += p;
            if entry.1 == 0 {
                factors.remove(k);
            }
        }
        Term {
            coefficient: self.coefficient * other.coefficient,
            factors,
        }
    }

    fn powi(&self, n: i32) -> Term {
        Term {
            coefficient: self.coefficient.powi(n),
            factors: self
                .factors
                .iter()
                .map(|(k, (e, p))| (k.clone(), (e.clone(), p * n)))
                .collect(),
        }
    }

    /// Canonical text of the factor product ("1" for no factors); equal keys mean equal
    /// functions.
    pub fn key(&self) -> String {
        if self.factors.is_empty() {
            return "1".into();
        }
        self.factors
            .iter()
            .map(|(k, (_, p))| {
                if *p == 1 {
                    format!("[{k}]")
                } else {
                    format!("[{k}]^{p}")
                }
            })
            .collect::<Vec<_>>()
            .join("*")
    }

    /// The factor product as an expression (1 for no factors).
    pub fn basic(&self) -> Expr {
        let mut e: Option<Expr> = None;
        for (f, p) in self.factors.values() {
            let fp = pow(f.clone(), Expr::Num(f64::from(*p)));
            e = Some(match e {
                None => fp,
                Some(a) => mul(a, fp),
            });
        }
        e.unwrap_or(Expr::Num(1.0))
    }

    /// The power of the variable `x` as a factor (0 if absent).
    pub fn power_of(&self, x: Var) -> i32 {
        self.factors
            .get(&Expr::Var(x).to_string())
            .map_or(0, |(_, p)| *p)
    }

    /// This term with the factor `x` removed.
    pub fn without(&self, x: Var) -> Term {
        let mut t = self.clone();
        t.factors.remove(&Expr::Var(x).to_string());
        t
    }
}

/// Expands an expression into terms (not yet merged).
pub fn expand(e: &Expr) -> Vec<Term> {
    match e {
        Expr::Num(x) => vec![Term::number(*x)],
        Expr::Var(_) | Expr::Call(..) => vec![Term::factor(e.clone())],
        Expr::Neg(a) => expand(a)
            .into_iter()
            .map(|mut t| {
                t.coefficient = -t.coefficient;
                t
            })
            .collect(),
        Expr::Add(a, b) => {
            let mut v = expand(a);
            v.extend(expand(b));
            v
        }
        Expr::Sub(a, b) => {
            let mut v = expand(a);
            v.extend(expand(b).into_iter().map(|mut t| {
                t.coefficient = -t.coefficient;
                t
            }));
            v
        }
        Expr::Mul(a, b) => {
            let (ea, eb) = (expand(a), expand(b));
            if ea.len() * eb.len() > MAX_TERMS {
                return vec![Term::factor(e.clone())];
            }
            let mut v = Vec::with_capacity(ea.len() * eb.len());
            for x in &ea {
                for y in &eb {
                    v.push(x.times(y));
                }
            }
            v
        }
        Expr::Div(a, b) => {
            let eb = merge(expand(b));
            if eb.len() == 1 && eb[0].coefficient != 0.0 {
                let inv = eb[0].powi(-1);
                expand(a).iter().map(|x| x.times(&inv)).collect()
            } else {
                // a * (b)^(-1) with b kept whole.
                let inv = Term::factor(b.as_ref().clone()).powi(-1);
                expand(a).iter().map(|x| x.times(&inv)).collect()
            }
        }
        Expr::Pow(a, b) => {
            let n = match **b {
                Expr::Num(n) if n.fract() == 0.0 && n.abs() <= f64::from(i32::MAX) => n as i32,
                _ => return vec![Term::factor(e.clone())],
            };
            let ea = merge(expand(a));
            if ea.len() == 1 {
                return vec![ea[0].powi(n)];
            }
            if !(0..=MAX_EXPANDED_POWER).contains(&n) {
                return vec![Term::factor(e.clone())];
            }
            let mut acc = vec![Term::number(1.0)];
            for _ in 0..n {
                if acc.len() * ea.len() > MAX_TERMS {
                    return vec![Term::factor(e.clone())];
                }
                let mut next = Vec::with_capacity(acc.len() * ea.len());
                for x in &acc {
                    for y in &ea {
                        next.push(x.times(y));
                    }
                }
                acc = merge(next);
            }
            acc
        }
    }
}

/// Merges terms with equal factors and drops terms whose coefficient is exactly 0.
/// Keeps the order of first appearance.
pub fn merge(terms: Vec<Term>) -> Vec<Term> {
    let mut out: Vec<Term> = Vec::new();
    let mut index: BTreeMap<String, usize> = BTreeMap::new();
    for t in terms {
        let k = t.key();
        match index.get(&k) {
            Some(&i) => out[i].coefficient += t.coefficient,
            None => {
                index.insert(k, out.len());
                out.push(t);
            }
        }
    }
    out.retain(|t| t.coefficient != 0.0);
    out
}

/// Splits an expression into `(coefficient, basic function)` pairs with distinct basic
/// functions (eq 3). The basic function of a constant term is `1`.
pub fn split(e: &Expr) -> Vec<(f64, Term)> {
    merge(expand(e))
        .into_iter()
        .map(|t| {
            let c = t.coefficient;
            let mut b = t;
            b.coefficient = 1.0;
            (c, b)
        })
        .collect()
}

/// Splits an expression that is a polynomial in `u` into the coefficient functions of
/// `u^0, u^1, ...` (eq 34). Returns `Err(term)` with the text of a term that is not a
/// non-negative integer power of `u` times a function free of `u`.
pub fn split_u_polynomial(e: &Expr) -> Result<Vec<Expr>, String> {
    let mut coefs: Vec<Vec<Term>> = Vec::new();
    for t in merge(expand(e)) {
        let k = t.power_of(Var::U);
        let rest = t.without(Var::U);
        if k < 0 || rest.basic().depends_on(Var::U) {
            return Err(mul(Expr::Num(t.coefficient), t.basic()).to_string());
        }
        let k = k as usize;
        if coefs.len() <= k {
            coefs.resize(k + 1, Vec::new());
        }
        coefs[k].push(rest);
    }
    Ok(coefs
        .into_iter()
        .map(|terms| {
            terms
                .into_iter()
                .map(|t| mul(Expr::Num(t.coefficient), t.basic()))
                .fold(Expr::Num(0.0), crate::expr::add)
        })
        .collect())
}
