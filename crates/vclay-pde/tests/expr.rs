//! Expressions: parsing, errors with columns, exact derivatives, splitting into basic functions.

use vclay_pde::basis::{split, split_u_polynomial};
use vclay_pde::expr::{Expr, ExprErrorKind, MAX_DEPTH, MAX_DERIVED_DEPTH, Var};

fn parse(s: &str) -> Expr {
    Expr::parse(s).unwrap_or_else(|e| panic!("{s}: {e}"))
}

#[test]
fn precedence_and_associativity() {
    let cases = [
        ("1 + 2*3", 7.0),
        ("2^3^2", 512.0),
        ("-2^2", -4.0),
        ("(1+2)*(3-1)/4", 1.5),
        ("2*-3", -6.0),
        ("1e-3*1000", 1.0),
        (".5 + 0.25", 0.75),
        ("sqrt(16) + ln(exp(2)) + log(1)", 6.0),
        ("cos(pi) + sin(0) + cosh(0) + sinh(0) + tan(0)", 0.0),
        ("8/2/2", 2.0),
        ("2^-1", 0.5),
    ];
    for (s, want) in cases {
        let got = parse(s).eval(0.0, 0.0, 0.0);
        assert!((got - want).abs() < 1e-12, "{s} = {got}, want {want}");
    }
    let e = parse("u*10 + v*100 + t*1000");
    assert_eq!(e.eval(1.0, 2.0, 3.0), 3210.0);
}

#[test]
fn display_round_trips() {
    for s in [
        "4.763 + 0.017*sin(v) - 3.395*exp(0.1*v)",
        "-(v - t)^2/(1 + u)",
        "2^(-v)*cos(5*v)",
        "a - (b - c)",
        "(-2)^v",
    ] {
        let params = |n: &str| match n {
            "a" => Some(1.0),
            "b" => Some(2.0),
            "c" => Some(4.0),
            _ => None,
        };
        let e = Expr::parse_with(s, &params).unwrap();
        let back = Expr::parse(&e.to_string()).unwrap();
        for (u, v, t) in [(0.3, 0.7, 0.2), (0.9, 2.0, 1.5)] {
            let (a, b) = (e.eval(u, v, t), back.eval(u, v, t));
            assert!(
                (a - b).abs() <= 1e-12 * a.abs().max(1.0) || (a.is_nan() && b.is_nan()),
                "{s} -> {e}: {a} vs {b}"
            );
        }
    }
}

#[test]
fn errors_point_at_the_column() {
    type Check = fn(&ExprErrorKind) -> bool;
    let cases: [(&str, usize, Check); 9] = [
        (
            "1 + sni(v)",
            5,
            |k| matches!(k, ExprErrorKind::UnknownFunction(n) if n == "sni"),
        ),
        ("sin(v", 4, |k| matches!(k, ExprErrorKind::UnclosedParen)),
        ("(1 + v))", 8, |k| matches!(k, ExprErrorKind::UnopenedParen)),
        (
            "2 * q",
            5,
            |k| matches!(k, ExprErrorKind::UnknownName(n) if n == "q"),
        ),
        ("1 +", 4, |k| matches!(k, ExprErrorKind::ExpectedOperand)),
        ("2v", 2, |k| matches!(k, ExprErrorKind::TrailingInput)),
        ("1 # 2", 3, |k| {
            matches!(k, ExprErrorKind::UnexpectedChar('#'))
        }),
        ("sin + 1", 1, |k| {
            matches!(k, ExprErrorKind::MissingArgument(_))
        }),
        ("   ", 1, |k| matches!(k, ExprErrorKind::Empty)),
    ];
    for (s, col, check) in cases {
        let e = Expr::parse(s).expect_err(s);
        assert_eq!(e.column, col, "{s}: {e}");
        assert!(check(&e.kind), "{s}: {e}");
        // The message names the column and the pointer puts the caret under it.
        assert!(e.to_string().starts_with(&format!("column {col}:")));
        let pointer = e.pointer(s);
        let caret_line = pointer.lines().nth(1).unwrap();
        assert_eq!(caret_line.find('^'), Some(2 + col - 1), "{pointer}");
    }
    // Columns count characters, not bytes.
    let e = Expr::parse("1 + \u{3b1}").unwrap_err();
    assert_eq!(e.column, 5);
}

/// Derivatives against central finite differences.
#[test]
fn derivatives_are_exact() {
    let exprs = [
        "4.763 + 0.017*sin(v) - 3.395*exp(0.1*v)",
        "t*sin(5*v) + t^3*cos(v)",
        "v^2*t/(1 + v*v)",
        "sqrt(2 + sin(v*t))*ln(3 + v)",
        "tan(0.3*v)*cosh(t) + sinh(v - t)",
        "(1 + v)^t",
        "exp(-v)^2",
    ];
    let fd = |e: &Expr, x: Var, v: f64, t: f64| {
        let h = 1e-5;
        let (vp, vm, tp, tm) = match x {
            Var::V => (v + h, v - h, t, t),
            _ => (v, v, t + h, t - h),
        };
        (e.eval(0.0, vp, tp) - e.eval(0.0, vm, tm)) / (2.0 * h)
    };
    for s in exprs {
        let e = parse(s);
        for x in [Var::V, Var::T] {
            let d = e.derivative(x);
            let d2 = d.derivative(x);
            for (v, t) in [(0.4, 0.3), (1.7, 0.9), (2.9, 1.2)] {
                let (exact, num) = (d.eval(0.0, v, t), fd(&e, x, v, t));
                assert!(
                    (exact - num).abs() < 1e-6 * exact.abs().max(1.0),
                    "d/d{x:?} {s} at ({v},{t}): {exact} vs {num} ({d})"
                );
                let (exact2, num2) = (d2.eval(0.0, v, t), fd(&d, x, v, t));
                assert!(
                    (exact2 - num2).abs() < 1e-6 * exact2.abs().max(1.0),
                    "d2/d{x:?}2 {s}: {exact2} vs {num2}"
                );
            }
        }
    }
    // d4/dv4 of exp(0.1 v) is 1e-4 exp(0.1 v) and of sin(5v) is 625 sin(5v), exactly.
    let g = parse("exp(0.1*v)");
    let d4 = g.nth_derivative(Var::V, 4);
    assert!((d4.eval(0.0, 2.0, 0.0) - 1e-4 * (0.2f64).exp()).abs() < 1e-15);
    let g = parse("t*sin(5*v)");
    let d4 = g.nth_derivative(Var::V, 4);
    assert!((d4.eval(0.0, 0.3, 2.0) - 625.0 * 2.0 * (1.5f64).sin()).abs() < 1e-10);
    assert_eq!(g.nth_derivative(Var::T, 2).as_number(), Some(0.0));
}

#[test]
fn split_into_basic_functions() {
    let terms = split(&parse("4.763 + 0.017*sin(v) - 3.395*exp(0.1*v)"));
    let got: Vec<(f64, String)> = terms
        .iter()
        .map(|(c, t)| (*c, t.basic().to_string()))
        .collect();
    assert_eq!(
        got,
        vec![
            (4.763, "1".to_string()),
            (0.017, "sin(v)".to_string()),
            (-3.395, "exp(0.1*v)".to_string())
        ]
    );
    // Products distribute, numbers come out, equal factors merge.
    let terms = split(&parse("2*t*(sin(5*v) + 3*cos(v)) - t*sin(5*v) + v*v - v^2"));
    let mut got: Vec<(f64, String)> = terms.iter().map(|(c, t)| (*c, t.key())).collect();
    got.sort_by(|a, b| a.1.cmp(&b.1));
    assert_eq!(got.len(), 2, "{got:?}");
    assert!(
        got.iter()
            .any(|(c, k)| *c == 1.0 && k.contains("sin(5*v)") && k.contains("[t]"))
    );
    assert!(got.iter().any(|(c, k)| *c == 6.0 && k.contains("cos(v)")));
    // Reassembled sums equal the expression.
    for s in [
        "(1 + v)^3 - 2*(t - v)/4",
        "t^2*sin(v)/(2*t) + exp(v)/(1 + v)",
    ] {
        let e = parse(s);
        let parts = split(&e);
        for (v, t) in [(0.3, 0.5), (1.1, 2.0)] {
            let sum: f64 = parts
                .iter()
                .map(|(c, b)| c * b.basic().eval(0.0, v, t))
                .sum();
            assert!((sum - e.eval(0.0, v, t)).abs() < 1e-12, "{s}");
        }
    }
}

#[test]
fn u_polynomials() {
    let e = parse("1 + 2*u - t*u^3 + (u*t)^2");
    let c = split_u_polynomial(&e).unwrap();
    assert_eq!(c.len(), 4);
    let t = 0.7;
    let want = [1.0, 2.0, t * t, -t];
    for k in 0..4 {
        assert!(
            (c[k].eval(0.0, 0.0, t) - want[k]).abs() < 1e-14,
            "u^{k}: {}",
            c[k]
        );
    }
    assert!(split_u_polynomial(&parse("sin(u)")).is_err());
    assert!(split_u_polynomial(&parse("1/u")).is_err());
}

#[test]
fn deep_nesting_is_an_error_not_a_stack_overflow() {
    let s = format!("{}v{}", "(".repeat(10_000), ")".repeat(10_000));
    let e = Expr::parse(&s).unwrap_err();
    assert_eq!(e.kind, ExprErrorKind::TooDeep);
    assert!(Expr::parse(&format!("{}v{}", "(".repeat(30), ")".repeat(30))).is_ok());
}

/// Issue 17: long flat chains overflowed the stack (only parentheses had a limit).
#[test]
fn long_chains_are_errors_not_stack_overflows() {
    let chain = |op: &str, n: usize| vec!["v"; n].join(op);
    for text in [
        chain("+", 30_000),
        chain("*", 100_000),
        chain("^", 100_000),
        format!("{}v", "-".repeat(30_000)),
    ] {
        let e = Expr::parse(&text).unwrap_err();
        assert!(
            matches!(
                e.kind,
                ExprErrorKind::TooLong | ExprErrorKind::TooDeepTree { .. }
            ),
            "{e}"
        );
        // The message quotes at most a window of the text.
        assert!(e.pointer(&text).len() < 300);
    }
    // Within the token limit but deeper than MAX_DEPTH: a flat chain, a unary chain, powers.
    let deep = MAX_DEPTH + 1;
    for text in [
        chain("+", deep),
        format!("{}v", "-".repeat(deep)),
        chain("^", deep),
    ] {
        let e = Expr::parse(&text).unwrap_err();
        assert!(matches!(e.kind, ExprErrorKind::TooDeepTree { .. }), "{e}");
    }
    // Just under the limit parses, evaluates and differentiates.
    let ok = parse(&chain("+", MAX_DEPTH - 1));
    assert_eq!(ok.eval(0.0, 2.0, 0.0), 2.0 * (MAX_DEPTH - 1) as f64);
    assert_eq!(
        ok.try_derivative(Var::V).unwrap().eval(0.0, 1.0, 0.0),
        (MAX_DEPTH - 1) as f64
    );
}

/// Issue 17: `v^v^...^v` of 400 characters grew to 4 GB while differentiating.
#[test]
fn derivatives_that_would_explode_are_refused_before_they_are_built() {
    let tower = parse(&vec!["v"; 200].join("^"));
    let e = tower.try_derivative(Var::V).unwrap_err();
    assert!(
        matches!(e.kind, ExprErrorKind::DerivativeTooLarge { .. }),
        "{e}"
    );
    assert!(e.to_string().contains("simplify"), "{e}");
    // Ordinary functions keep their derivatives (and the bound is not in the way).
    let g = parse("4.763 + 0.017*sin(v) - 3.395*exp(0.1*v)*t^2");
    assert_eq!(g.try_derivative(Var::V).unwrap(), g.derivative(Var::V));
    assert_eq!(
        g.try_nth_derivative(Var::V, 4).unwrap(),
        g.nth_derivative(Var::V, 4)
    );
}

/// The deepest derived trees allowed evaluate, clone and drop on a 2 MB thread stack (the
/// default of spawned threads and rayon workers).
#[test]
fn deepest_allowed_trees_fit_a_small_stack() {
    std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(|| {
            let mut e = Expr::Var(Var::V);
            for k in 0..MAX_DERIVED_DEPTH as usize + 8 {
                e = if k % 2 == 0 {
                    Expr::Add(Box::new(e), Box::new(Expr::Var(Var::T)))
                } else {
                    Expr::Mul(Box::new(Expr::Num(0.5)), Box::new(e))
                };
            }
            assert!(e.eval(0.0, 1.0, 1.0).is_finite());
            assert!(e.derivative(Var::V).eval(0.0, 1.0, 1.0).is_finite());
            let c = e.clone();
            assert_eq!(c.size(), e.size());
            assert!(!c.to_string().is_empty());
            drop(c);
        })
        .unwrap()
        .join()
        .unwrap();
}

/// Issue 17: `0/0` and `0*(1/0)` were simplified to 0; they are errors like `1/0`.
#[test]
fn constant_division_by_zero_is_an_error() {
    for (text, column) in [
        ("1/0", 2),
        ("0/0", 2),
        ("0*(1/0)", 5),
        ("v + exp(1000)", 5),
        ("2^2000", 2),
    ] {
        let e = Expr::parse(text).unwrap_err();
        assert!(matches!(e.kind, ExprErrorKind::NotFinite(_)), "{text}: {e}");
        assert_eq!(e.column, column, "{text}: {e}");
    }
    assert!(matches!(
        Expr::parse("1e400").unwrap_err().kind,
        ExprErrorKind::BadNumber(_)
    ));
    // Zero over a variable is still 0 (the usual simplification).
    assert_eq!(parse("0/v"), Expr::Num(0.0));
}
